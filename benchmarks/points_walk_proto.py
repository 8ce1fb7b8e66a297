"""What one grid walk for the 10 nearest and the R3 ball could save (issue 33, item 5, design change 1).

Run by hand from the repository root (one thread, so the CPU seconds are the kernels' own)::

    CURV_THREADS=1 PYTHONPATH=. python benchmarks/points_walk_proto.py 1000000 [--repeat 3]

N uniform random points of the unit sphere (seed 0, as ``points_profile.py``), their twin in grid
order (what an estimate runs on), with the outer radii the default qs estimate's pass reads. Timed
(median CPU s of ``--repeat``, serial kernels):

- ``knn (library)``: :func:`curv.core.knn.nearest_neighbours` of the twin on its grid, as the
  estimate calls it (the search and the rows put back);
- ``knn kernel``: the same search without the rows back;
- ``ball walk``: the pass's search alone (:func:`curv.core.grid_blocks.cell_runs` and
  :func:`curv.core.grid_balls.block_gather` at the outer radius, nothing done with the ball);
- ``fused, ideal``: the same walk that also keeps the 10 nearest of each point among its ball
  (ties broken by the lower sorted position, as the library's search does), its outer radius known
  in advance. The upper bound of a one-walk design: in the library the outer radius is the border
  test's, which reads the spacings of the point's 10 nearest (``normals._calm_spacing``), and the
  ball grid's cell follows the median of every radius, so neither is known before the walk;
- ``fused, two steps``: the ball walk as the pass runs it, then the 10 nearest selected from the
  ball it found (same upper-bound caveat);
- ``knn on the ball grid``: the 10 nearest searched on the ball grid's ring-1 blocks (the
  first walk of a two-walk design that shares the pass's grid);

Every variant's lists are checked equal to the library's.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from curv.core.grid_balls import block_gather
from curv.core.grid_blocks import cell_block, cell_runs
from curv.core.jit import jit

K = 10


@jit
def _insert(d2, j, row_d, row_i, k):
    """Keep (d2, j) among the k smallest by (distance, position), ascending."""
    if d2 > row_d[k - 1] or (d2 == row_d[k - 1] and j >= row_i[k - 1]):
        return
    s = k - 1
    while s > 0 and (row_d[s - 1] > d2 or (row_d[s - 1] == d2 and row_i[s - 1] > j)):
        row_d[s] = row_d[s - 1]
        row_i[s] = row_i[s - 1]
        s -= 1
    row_d[s] = d2
    row_i[s] = j


@jit
def _ball_walk(grid, outer2, queue, dist2):
    cells, coords = grid
    order, cell_start = cells[3], cells[1]
    n = order.size
    block = (np.empty((64, 2), np.int64), 0, np.empty((64, 6)))
    total = 0
    c = 0
    cell_end = 0
    for i in range(n):
        if i >= cell_end:
            c, cell_end, block = cell_runs(i, c, outer2, cells, coords[0], block)
        total += block_gather(i, outer2[order[i]], block, coords, queue, dist2)
    return total


@jit
def _fused_walk(grid, outer2, queue, dist2, out_d, out_i):
    """The ball walk that keeps the 10 nearest of each point among its ball's points (sorted
    positions of the ball grid mapped to the twin's, ``order``); returns (balls' size, points whose
    ball held fewer than K others: their lists are not final)."""
    cells, coords = grid
    order, cell_start = cells[3], cells[1]
    xs, ys, zs = coords[1], coords[2], coords[3]
    n = order.size
    block = (np.empty((64, 2), np.int64), 0, np.empty((64, 6)))
    total = 0
    short = 0
    c = 0
    cell_end = 0
    for i in range(n):
        if i >= cell_end:
            c, cell_end, block = cell_runs(i, c, outer2, cells, coords[0], block)
        p = order[i]
        radius2 = outer2[p]
        runs, m, columns = block
        px, py, pz = xs[i], ys[i], zs[i]
        row_d = out_d[p]
        row_i = out_i[p]
        for s in range(K):
            row_d[s] = np.inf
            row_i[s] = -1
        queue[0] = i
        dist2[0] = 0.0
        count = 1
        for r in range(m):
            ex = max(columns[r, 0] - px, px - columns[r, 1], 0.0)
            ey = max(columns[r, 2] - py, py - columns[r, 3], 0.0)
            if ex * ex + ey * ey > radius2:
                continue
            for j in range(runs[r, 0], runs[r, 1]):
                dx, dy, dz = xs[j] - px, ys[j] - py, zs[j] - pz
                d2 = dx * dx + dy * dy + dz * dz
                queue[count] = j
                dist2[count] = d2
                inside = (d2 <= radius2) & (j != i)
                count += inside
                if inside and d2 <= row_d[K - 1]:
                    _insert(d2, order[j], row_d, row_i, K)
        total += count
        short += count - 1 < K
    return total, short


@jit
def _fused_two_step(grid, outer2, queue, dist2, out_d, out_i):
    """The ball walk as the pass runs it (:func:`block_gather`, branch-free), then the 10 nearest
    selected from the ball it found (its sorted positions mapped to the twin's, ``order``)."""
    cells, coords = grid
    order, cell_start = cells[3], cells[1]
    n = order.size
    block = (np.empty((64, 2), np.int64), 0, np.empty((64, 6)))
    short = 0
    c = 0
    cell_end = 0
    for i in range(n):
        if i >= cell_end:
            c, cell_end, block = cell_runs(i, c, outer2, cells, coords[0], block)
        p = order[i]
        count = block_gather(i, outer2[p], block, coords, queue, dist2)
        row_d = out_d[p]
        row_i = out_i[p]
        for s in range(K):
            row_d[s] = np.inf
            row_i[s] = -1
        worst = np.inf
        for b in range(1, count):
            d2 = dist2[b]
            if d2 <= worst:
                _insert(d2, order[queue[b]], row_d, row_i, K)
                worst = row_d[K - 1]
        short += count - 1 < K
    return short


@jit
def _knn_ball_grid(grid, out_d, out_i):
    """The 10 nearest of every point among its ball-grid cell's ring-1 block (not checked final)."""
    cells, coords = grid
    cell_keys, cell_start, dims, order = cells
    xs, ys, zs = coords[1], coords[2], coords[3]
    runs = np.empty((64, 2), np.int64)
    for c in range(cell_keys.size):
        m, runs = cell_block(c, 1, cells, runs)
        for i in range(cell_start[c], cell_start[c + 1]):
            p = order[i]
            row_d = out_d[p]
            row_i = out_i[p]
            for s in range(K):
                row_d[s] = np.inf
                row_i[s] = -1
            px, py, pz = xs[i], ys[i], zs[i]
            for r in range(m):
                for j in range(runs[r, 0], runs[r, 1]):
                    if j == i:
                        continue
                    dx, dy, dz = xs[j] - px, ys[j] - py, zs[j] - pz
                    d2 = dx * dx + dy * dy + dz * dz
                    if d2 <= row_d[K - 1]:
                        _insert(d2, order[j], row_d, row_i, K)


def _cpu(work, repeat):
    runs = []
    for _ in range(repeat):
        c = time.process_time()
        work()
        runs.append(time.process_time() - c)
    return float(np.median(runs))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", type=int, nargs="?", default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    import curv
    from curv import point_normals as pn
    from curv.core.jit import launch
    from curv.core.knn import _knn_kernel, nearest_neighbours
    from curv.point_normals.normals import _default_spreads, _radii

    p = np.random.default_rng(0).normal(size=(args.n, 3))
    twin = pn.grid_ordered(curv.PointCloud(p / np.linalg.norm(p, axis=1, keepdims=True)))[0]
    pts = twin.points
    ref_i, ref_d = twin.nearest
    border, r2, spreads = pn.border_radii(twin), _radii(twin, 2), _default_spreads(twin)
    outer2 = np.square(np.stack([border, r2, *spreads])).max(axis=0)
    grid = twin.ball_grid(np.sqrt(outer2))
    n = args.n
    queue = np.empty(n + 1, np.int64)
    dist2 = np.empty(n + 1)
    out_d = np.empty((n, K))
    out_i = np.empty((n, K), np.int64)
    print(f"{n} points, ball grid cell {grid[1][0][3]:.4g}, knn grid cell {twin.grid[1][0][3]:.4g}, "
          f"median outer radius {np.median(np.sqrt(outer2)):.4g}, median spacing {np.median(ref_d[:, 5]):.4g}")

    def check(label, rows_i, rows_d):
        same = np.array_equal(rows_i, ref_i) and np.array_equal(np.sqrt(rows_d), ref_d)
        print(f"  {label}: lists equal to the library's: {same}")

    rows = {}
    rows["knn (library)"] = lambda: nearest_neighbours(pts, K, twin.grid)
    rows["knn kernel"] = lambda: launch(_knn_kernel, twin.grid[0], twin.grid[1], K, out_d, out_i)
    rows["ball walk"] = lambda: _ball_walk(grid, outer2, queue, dist2)
    rows["fused, ideal"] = lambda: _fused_walk(grid, outer2, queue, dist2, out_d, out_i)
    rows["fused, two steps"] = lambda: _fused_two_step(grid, outer2, queue, dist2, out_d, out_i)
    rows["knn on the ball grid"] = lambda: _knn_ball_grid(grid, out_d, out_i)
    results = {}
    for label, work in rows.items():
        work()  # compile or load
        results[label] = _cpu(work, args.repeat)
        print(f"{label:<24} {results[label]:7.3f} CPU s", flush=True)
        if label == "fused, ideal":
            total, short = work()
            print(f"  balls' mean size {total / n:.1f}, points with fewer than {K} in the ball: {short}")
        if label not in ("knn (library)", "ball walk"):
            check(label, out_i, out_d)
    two = results["knn (library)"] + results["ball walk"]
    for label in ("fused, ideal", "fused, two steps"):
        print(f"two searches (knn + ball walk) {two:.3f}; {label} {results[label]:.3f}: "
              f"saving at most {two - results[label]:.3f} CPU s")


if __name__ == "__main__":
    main()
