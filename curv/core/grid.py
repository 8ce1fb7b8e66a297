"""The uniform grid over points: the points sorted by cell, the structure behind every search of a
point cloud (its nearest neighbours, :mod:`curv.core.knn`; its balls, :mod:`curv.core.grid_balls`).

The points are sorted by grid cell (cells keyed ``(ix * ny + iy) * nz + iz``), so that the cells
``iz - 1 .. iz + 1`` of one ``(ix, iy)`` column are one contiguous run of points: a block of cells
is a few runs (:mod:`curv.core.grid_blocks`). The cell size aims at a few points per occupied cell
for a sample of a surface (a 2-D set in 3-D), measured on a subsample; it only affects speed, never
an answer.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import MeshError
from .jit import jit_parallel, launch, prange
from .radix import stable_sort

__all__ = ["build_grid", "sample_cell_size", "cell_sample_step", "in_sorted_order"]

_POINTS_PER_CELL = 0.5
"""Target points per occupied cell, per wanted neighbour (k = 10: 5 points a cell)."""

_SUBSAMPLE = 32768


def _cell_size(points: np.ndarray, k: int) -> float:
    """A grid cell edge giving about ``_POINTS_PER_CELL * k`` points per occupied cell on a surface."""
    n = points.shape[0]
    extent = float(np.ptp(points, axis=0).max())
    return sample_cell_size(points[::cell_sample_step(n)], n, extent, k)


def cell_sample_step(n: int) -> int:
    """Every how many points :func:`build_grid` samples to choose its cell size (in the points' order)."""
    return max(1, n // _SUBSAMPLE)


def sample_cell_size(sample: np.ndarray, n: int, extent: float, k: int) -> float:
    """The cell edge :func:`build_grid` chooses for ``n`` points spanning ``extent`` (the largest
    side of their bounding box), from ``sample``, every :func:`cell_sample_step`-th of them in their
    order: a caller that sees the points a chunk at a time (a file too large for memory) gets the
    grid an in-memory call would build."""
    if not extent > 0:
        return 1.0
    fraction = sample.shape[0] / n
    target = max(2.0, _POINTS_PER_CELL * k)
    # a surface: occupied cells ~ area / h^2, so points a cell ~ h^2
    h = extent * math.sqrt(target / sample.shape[0])
    lo = sample.min(axis=0)
    for _ in range(4):
        c3 = np.floor((sample - lo) / h).astype(np.int64)
        c3 -= c3.min(axis=0)
        span = c3.max(axis=0) + 1
        cells = np.unique((c3[:, 0] * span[1] + c3[:, 1]) * span[2] + c3[:, 2]).size
        per_cell = sample.shape[0] / cells
        h *= math.sqrt(target / per_cell)
    # the same points a cell for the full set: h shrinks like the sample's spacing
    return max(h * math.sqrt(fraction), extent * 1e-7)


@jit_parallel
def _coordinates_in(order, points, xs, ys, zs):
    """The points' coordinates in ``order`` (numpy's three gathers, in parallel)."""
    for i in prange(order.size):
        p = order[i]
        xs[i] = points[p, 0]
        ys[i] = points[p, 1]
        zs[i] = points[p, 2]


def build_grid(points: np.ndarray, k: int = 10, *, cell: float | None = None, origin: np.ndarray | None = None):
    """The uniform grid of :func:`curv.core.knn.nearest_neighbours` and of point-cloud ball supports.

    Parameters
    ----------
    points : (n, 3) float64
    k : int
        Neighbours the cell size is tuned for (about ``k / 2`` points per occupied cell).
    cell : float, optional
        The cell edge instead (ball queries: about the balls' radius, so that a ball spans one
        ring of cells around its centre's cell).
    origin : (3,) float64, optional
        The grid's lower corner instead of the points' least coordinates (at most those): a part
        of a larger cloud searched in the larger cloud's cells (:mod:`curv.tiles`).

    Returns
    -------
    cells : tuple of int64 arrays
        ``(cell_keys (c,), cell_start (c+1,), dims (3,), order (n,))``: the occupied cells' keys
        ``(ix * ny + iy) * nz + iz`` ascending, where each cell's points start in sorted order,
        the grid's size in cells, and the point index at each sorted position.
    coords : tuple of float64 arrays
        ``(origin_and_size (4,), xs, ys, zs)``: the grid's lower corner and cell edge, and the
        coordinates in sorted order.
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    n = points.shape[0]
    h = _cell_size(points, k) if cell is None else float(cell)
    lo = points.min(axis=0) if origin is None else np.asarray(origin, dtype=np.float64).reshape(3)
    cells3 = np.floor((points - lo) / h).astype(np.int64)
    dims = cells3.max(axis=0) + 1
    if float(dims[0]) * float(dims[1]) * float(dims[2]) > 2.0 ** 62:
        raise MeshError("the points span too many grid cells (a few points very far from the rest?)")
    keys = (cells3[:, 0] * dims[1] + cells3[:, 1]) * dims[2] + cells3[:, 2]
    del cells3
    order, keys = stable_sort(keys)  # np.argsort(keys, kind="stable") and keys[order], in parallel
    starts = np.flatnonzero(np.diff(keys)) + 1
    cell_keys = keys[np.concatenate(([0], starts))]
    cell_start = np.concatenate(([0], starts, [n])).astype(np.int64)
    del keys
    xs, ys, zs = np.empty(n), np.empty(n), np.empty(n)
    launch(_coordinates_in, order, points, xs, ys, zs)
    origin = np.array([lo[0], lo[1], lo[2], h])
    arrays = (cell_keys, cell_start, dims.astype(np.int64), order.astype(np.int64), origin, xs, ys, zs)
    for arr in arrays:
        arr.setflags(write=False)
    return arrays[:4], arrays[4:]


def in_sorted_order(grid):
    """``grid`` (:func:`build_grid`) as the grid of its points taken in its sorted order (row i of
    those points is row ``grid[0][3][i]`` of the grid's): the same cells, keys and coordinates, the
    order the identity. What :func:`build_grid` would return for those points with this grid's
    origin and cell, without sorting again."""
    (cell_keys, cell_start, dims, order), coords = grid
    identity = np.arange(order.size, dtype=np.int64)
    identity.setflags(write=False)
    return (cell_keys, cell_start, dims, identity), coords
