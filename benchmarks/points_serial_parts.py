"""The steps around the one pass of a point-cloud estimate, each timed on its own (issue 33, item 5).

Run by hand, once per tree and thread count, the trees alternating::

    CURV_THREADS=1 PYTHONPATH=TREE python benchmarks/points_serial_parts.py [N] [--orient]

N uniform random points of the unit sphere (seed 0, default 1M), as ``points_profile.py``. After
one estimate on 3,000 points (numba's cache loaded, not timed) each step runs 5 times in one
process and its median wall and CPU seconds are printed: the grid (its sort by cell and the
coordinates in that order), the 10 nearest on that grid (the search and its rows put back in the
caller's order), the symmetric neighbour graph, the orientation from each part's top with the graph
held (the spanning tree and its walk), and a result's rows put back in the cloud's order.
``--orient`` then times the orientation's own steps the same way (``orientation.py``'s kernels on
the held graph and normals): the tree's edges and weights, their ranking, Kruskal's forest, the walk
of each part's tree (on a fresh copy of the normals each time, the copy included) and the neighbours'
agreement.
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

    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    n = int(args[0]) if args else 1_000_000
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
    if "--orient" in sys.argv:
        _orient_steps(twin, normals)


def _orient_steps(twin, normals) -> None:
    """The steps of ``orient_normals(..., orient="top")``, each timed as :func:`main`'s."""
    from curv.core.jit import launch
    from curv.point_normals import orientation as o

    graph = twin.adjacency
    indptr, neighbours = graph.indptr, graph.indices
    n = normals.shape[0]
    finite = np.isfinite(normals).all(axis=1)
    safe = np.where(finite[:, None], normals, 0.0)
    rows, cols, weight = o._tree_edges(indptr, neighbours, safe, finite)
    rank = o._stable_rank(weight)
    ptr, adj, part = o._spanning_forest(n, rank, rows, cols)
    key = twin.points[:, 2].copy()
    root_sign = normals[:, 2].copy()
    ambiguous = np.zeros(n, bool)
    steps = [("  tree edges and weights", lambda: o._tree_edges(indptr, neighbours, safe, finite)),
             ("  rank (radix sort)", lambda: o._stable_rank(weight)),
             ("  spanning forest (Kruskal, CSR)", lambda: o._spanning_forest(n, rank, rows, cols)),
             ("  walk (propagate, copy)", lambda: o._propagate(ptr, adj, part, key, root_sign, normals.copy())),
             ("  agreement", lambda: launch(o._agreement, indptr, neighbours, safe, o.AGREE_COSINE, ambiguous))]
    print(f"  ({rows.size} edges, {np.unique(part).size} parts)", flush=True)
    for label, work in steps:
        wall, cpu = _median(work)
        print(f"{label:<32} wall {wall:6.3f}  cpu {cpu:6.3f}", flush=True)


if __name__ == "__main__":
    main()
