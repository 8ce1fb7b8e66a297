"""The steps around the one pass of a point-cloud estimate, each timed on its own (issue 33, item 5).

Run by hand, once per tree and thread count, the trees alternating::

    CURV_THREADS=1 PYTHONPATH=TREE python benchmarks/points_serial_parts.py [N]

N uniform random points of the unit sphere (seed 0, default 1M), as ``points_profile.py``. After
one estimate on 3,000 points (numba's cache loaded, not timed) each step runs 5 times in one
process and its median wall and CPU seconds are printed: the grid (its sort by cell and the
coordinates in that order), the 10 nearest on that grid (the search and its rows put back in the
caller's order), the symmetric neighbour graph, the orientation from each part's top with the graph
held (the spanning tree and its walk), and a result's rows put back in the cloud's order.
"""

from __future__ import annotations

import sys
import time

import numpy as np


def _median(work, repeats: int = 5) -> tuple[float, float]:
    walls, cpus = [], []
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        work()
        walls.append(time.perf_counter() - t)
        cpus.append(time.process_time() - c)
    return float(np.median(walls)), float(np.median(cpus))


def main() -> None:
    import curv
    from curv import point_normals as pn
    from curv.core.grid import build_grid
    from curv.core.jit import run_to_end
    from curv.core.knn import nearest_neighbours, symmetric_graph
    from curv.locality import rows_back
    from curv.point_normals.one_pass import _one_pass

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    p = np.random.default_rng(0).normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    curv.estimate(curv.PointCloud(p[:3000].copy()), "qs", 2)
    twin, order = pn.grid_ordered(curv.PointCloud(p))
    nearest = twin.nearest[0]
    normals = run_to_end(_one_pass(twin, pn.border_radii(twin))).normal_a
    result = curv.estimate(twin, "qs", 2)
    grid = build_grid(p, 10)
    steps = [("grid (sort and gathers)", lambda: build_grid(p, 10)),
             ("10 nearest (search, rows back)", lambda: nearest_neighbours(p, 10, grid)),
             ("symmetric graph", lambda: symmetric_graph(nearest)),
             ("orientation top (graph held)", lambda: pn.orient_normals(twin, normals, orient="top")),
             ("result rows back", lambda: rows_back(result, order))]
    for label, work in steps:
        wall, cpu = _median(work)
        print(f"{label:<32} wall {wall:6.3f}  cpu {cpu:6.3f}", flush=True)


if __name__ == "__main__":
    main()
