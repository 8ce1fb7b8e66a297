"""Nearest neighbours of points through a uniform grid (numba): the search behind point clouds.

The grid (:mod:`curv.core.grid`) sorts the points by cell; a point's 27 surrounding cells are 9
runs of sorted points, found once per cell (:func:`curv.core.grid_blocks.cell_block`). A point's k
nearest are final once the k-th is closer than the nearest face of the searched block of cells;
otherwise the block grows to the k-th candidate's distance, or doubles while fewer than k were found
(sparse places, outliers), and its runs are scanned again the same way (a block of mostly empty
cells walks its occupied cells: a search never costs more than the points).

Measured (docs/BENCHMARKS.md, "Point clouds"): 1M points on a sphere, k = 10, about 4x faster
than scipy's cKDTree query on the same two cores, which is why this is a grid and not a tree.

The public names of the grid's other modules can be imported from here too (``__all__``):
:mod:`curv.core.grid` (``build_grid``, ``in_sorted_order``, the cell size),
:mod:`curv.core.grid_blocks` (blocks of cells as runs of points), :mod:`curv.core.grid_balls`
(``grid_ball``, ``grid_gather``, ``block_gather``) and :mod:`curv.core.neighbour_graph`
(``symmetric_graph``, ``neighbour_steps``, ``GRAPH_NEIGHBOURS``).
"""

from __future__ import annotations

import math

import numpy as np

from .grid import build_grid, cell_sample_step, in_sorted_order, sample_cell_size
from .grid_balls import block_gather, grid_ball, grid_gather
from .grid_blocks import block_around, block_runs, cell_block, cell_coordinates, cell_of, ring_of
from .jit import jit, jit_parallel, launch, prange
from .neighbour_graph import GRAPH_NEIGHBOURS, neighbour_steps, symmetric_graph

__all__ = ["build_grid", "sample_cell_size", "cell_sample_step", "nearest_neighbours", "grid_ball", "grid_gather",
           "in_sorted_order", "cell_of", "ring_of", "cell_block", "block_gather",
           "symmetric_graph", "neighbour_steps", "GRAPH_NEIGHBOURS"]


@jit
def _scan_runs(i, runs, m, coords, out, k):
    """Keep in row i of ``out = (out_d, out_i)`` (squared distances, sorted indices, ascending) the k
    nearest of sorted point i among the runs ``runs[:m]`` of a block
    (:func:`~curv.core.grid_blocks.block_runs`), the k-th distance kept in a local. Rows are
    indexed, not sliced: a view made per point inside a parallel loop costs an atomic reference
    count each time; the insertion is written out here for the same reason (a helper call per
    candidate, several times slower)."""
    out_d, out_i = out
    xs, ys, zs = coords[1], coords[2], coords[3]
    px, py, pz = xs[i], ys[i], zs[i]
    worst = out_d[i, k - 1]
    for r in range(m):
        for j in range(runs[r, 0], runs[r, 1]):
            if j == i:
                continue
            dx, dy, dz = xs[j] - px, ys[j] - py, zs[j] - pz
            d2 = dx * dx + dy * dy + dz * dz
            if d2 >= worst:
                continue
            s = k - 1
            while s > 0 and out_d[i, s - 1] > d2:
                out_d[i, s] = out_d[i, s - 1]
                out_i[i, s] = out_i[i, s - 1]
                s -= 1
            out_d[i, s] = d2
            out_i[i, s] = j
            worst = out_d[i, k - 1]


@jit
def _margin(point, cell, ring, dims, origin):
    """Distance from ``point`` (x, y, z) in ``cell`` (cx, cy, cz) to the nearest face of the block of
    ``ring`` rings around it that has cells beyond (``origin``: the grid's corner and cell edge)."""
    m = math.inf
    h = origin[3]
    for a in range(3):
        if cell[a] - ring > 0:
            m = min(m, point[a] - (origin[a] + (cell[a] - ring) * h))
        if cell[a] + ring < dims[a] - 1:
            m = min(m, origin[a] + (cell[a] + ring + 1) * h - point[a])
    return m


@jit
def _wider_ring(ring, kth2, h, widest):
    """The next block of a kNN search whose block of ``ring`` rings did not settle it: wide enough
    for the k-th candidate's distance (its squared ``kth2``; every ring adds ``h`` to the margin),
    or twice as wide while fewer than k were found, so that a point far from the rest takes a few
    blocks, not one per ring of empty cells (a sparse block's walk bounds each block's cost,
    :mod:`curv.core.grid_blocks`)."""
    if math.isfinite(kth2):
        need = math.sqrt(kth2) / h + 1.0
        if need < widest:
            return max(ring + 1, int(math.ceil(need)))
        return widest
    return min(2 * ring, widest)


@jit_parallel
def _knn_kernel(cells, coords, k, out_d, out_i):
    """The k nearest of every sorted point: the cells in slices, one per thread; the first ring
    of cells around each cell looked up once for its points
    (:func:`~curv.core.grid_blocks.cell_block`), wider blocks point by point where the k-th nearest
    may lie beyond it (sparse places, outliers)."""
    cell_keys, cell_start, dims, _ = cells
    origin, xs, ys, zs = coords
    n_cells = cell_keys.size
    nx, ny, nz = dims[0], dims[1], dims[2]
    h = origin[3]
    widest = max(nx, max(ny, nz))
    parts = max(1, min(n_cells, 256))
    for t in prange(parts):
        runs = np.empty((64, 2), np.int64)
        wide = np.empty((64, 2), np.int64)
        for c in range(t * n_cells // parts, (t + 1) * n_cells // parts):
            cell = cell_coordinates(cell_keys[c], dims)
            m, runs = cell_block(c, 1, cells, runs)
            for i in range(cell_start[c], cell_start[c + 1]):
                for j in range(k):
                    out_d[i, j] = np.inf
                    out_i[i, j] = -1
                _scan_runs(i, runs, m, coords, (out_d, out_i), k)
                ring = 1
                while True:
                    margin = _margin((xs[i], ys[i], zs[i]), cell, ring, dims, origin)
                    # final when the k-th is inside the block's sphere, or the block holds everything
                    if out_d[i, k - 1] <= margin * margin or margin == math.inf:
                        break
                    ring = _wider_ring(ring, out_d[i, k - 1], h, widest)
                    for j in range(k):
                        out_d[i, j] = np.inf
                        out_i[i, j] = -1
                    wide_m, wide = block_runs(block_around(cell[0], cell[1], cell[2], ring, dims), cells, wide)
                    _scan_runs(i, wide, wide_m, coords, (out_d, out_i), k)


@jit_parallel
def _in_callers_order(order, found, indices, distances):
    """The search's rows (in the grid's sorted order) in the caller's: sorted row i is row
    ``order[i]``, its neighbours named by their positions in the caller's order (-1 kept), its
    squared distances square-rooted; ``found = (out_d, out_i)`` of :func:`_knn_kernel`."""
    out_d, out_i = found
    n, k = out_i.shape
    for i in prange(n):
        row = order[i]
        for j in range(k):
            q = out_i[i, j]
            indices[row, j] = order[q] if q >= 0 else -1
            distances[row, j] = math.sqrt(out_d[i, j])


def nearest_neighbours(points: np.ndarray, k: int, grid=None) -> tuple[np.ndarray, np.ndarray]:
    """The k nearest other points of every point (a uniform-grid search).

    Parameters
    ----------
    points : (n, 3) float64
    k : int
        Neighbours wanted (>= 1).
    grid : optional
        :func:`curv.core.grid.build_grid` of these points, if already made.

    Returns
    -------
    indices : (n, k) int64
        Nearest first; -1 where there are fewer than k other points. Ties in distance are in
        no particular order.
    distances : (n, k) float64
        Euclidean distances, ascending (inf with -1).
    """
    if k < 1:
        raise ValueError(f"k must be >= 1, got {k}")
    cells, coords = grid or build_grid(points, k)
    order = cells[3]
    n = order.size
    out_d = np.empty((n, k))
    out_i = np.empty((n, k), np.int64)
    launch(_knn_kernel, cells, coords, int(k), out_d, out_i)
    # back to the caller's order in one parallel pass (numpy's gathers and scatters here cost as
    # much as the search, on one thread)
    indices = np.empty_like(out_i)
    distances = np.empty_like(out_d)
    launch(_in_callers_order, order, (out_d, out_i), indices, distances)
    return indices, distances
