"""The searches of a point-cloud estimate, each timed on its own, for an A/B of two trees (issue 33, item 5).

Run by hand from outside the trees, once per tree, the trees alternating::

    CURV_THREADS=1 PYTHONPATH=TREE python benchmarks/points_search_parts.py LABEL [N] [--repeat 5]

N uniform random points of the unit sphere (seed 0, default 1M), as ``points_profile.py``. After
one estimate on 3,000 points (numba's cache loaded, not timed), each step runs ``--repeat`` times
in one process and its median and least CPU seconds are printed: the 10 nearest
(:func:`curv.core.knn.nearest_neighbours`) of the grid-ordered twin (what an estimate searches) and
of the cloud in its own order; the pass's ball walk alone (:func:`curv.core.grid_blocks.cell_runs`
and :func:`curv.core.grid_balls.block_gather` at the qs estimate's outer radii); the normals' pass
as qs and jet run it (frames at R3, jet fits at R2, the line check at R2); and mru's line check at
R1, which that pass owes and runs on its own.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from curv.core.grid_balls import block_gather
from curv.core.grid_blocks import cell_runs
from curv.core.jit import jit


@jit
def _ball_walk(grid, outer2, queue, dist2):
    """The pass's walk and ball search, nothing done with the balls; returns their total size."""
    cells, coords = grid
    order = cells[3]
    block = (np.empty((64, 2), np.int64), 0, np.empty((64, 6)))
    total = 0
    c = 0
    cell_end = 0
    for i in range(order.size):
        if i >= cell_end:
            c, cell_end, block = cell_runs(i, c, outer2, cells, coords[0], block)
        total += block_gather(i, outer2[order[i]], block, coords, queue, dist2)
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("label")
    parser.add_argument("n", type=int, nargs="?", default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()

    import curv
    from curv import point_normals as pn
    from curv.core.grid import build_grid
    from curv.core.jit import run_to_end
    from curv.core.knn import nearest_neighbours
    from curv.point_normals.normals import EXACT_GAP, ONE_SIDED_GAP, _default_spreads, _radii
    from curv.point_normals.one_pass import _one_pass

    p = np.random.default_rng(0).normal(size=(args.n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    curv.estimate(curv.PointCloud(p[:3000].copy()), "mru", 2)
    twin = pn.grid_ordered(curv.PointCloud(p))[0]
    grid = build_grid(p, 10)
    border, r2, spreads = pn.border_radii(twin), _radii(twin, 2), _default_spreads(twin)
    outer2 = np.square(np.stack([border, r2, spreads[0]])).max(axis=0)
    ball_grid = twin.ball_grid(np.sqrt(outer2))
    queue, dist2 = np.empty(args.n + 1, np.int64), np.empty(args.n + 1)
    steps = {
        "10 nearest of the twin": lambda: nearest_neighbours(twin.points, 10, twin.grid),
        "10 nearest, the cloud's own order": lambda: nearest_neighbours(p, 10, grid),
        "ball walk alone (blocks and gather)": lambda: _ball_walk(ball_grid, outer2, queue, dist2),
        "normals' pass (qs, jet)": lambda: run_to_end(_one_pass(twin, border, r2, jet=True, spreads=spreads[:1],
                                                                screens=(EXACT_GAP, ONE_SIDED_GAP))),
        "line check R1 on its own (mru)": lambda: run_to_end(_one_pass(twin, spreads=spreads[1:])),
    }
    for label, work in steps.items():
        work()  # compile or load
        cpu = []
        for _ in range(args.repeat):
            c = time.process_time()
            work()
            cpu.append(time.process_time() - c)
        print(f"{args.label:8} {label:38} CPU s median {np.median(cpu):6.3f}  least {min(cpu):6.3f}", flush=True)


if __name__ == "__main__":
    main()
