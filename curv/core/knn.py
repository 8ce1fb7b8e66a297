"""Nearest neighbours of points through a uniform grid (numba): the search behind point clouds.

The points are sorted by grid cell (cells keyed ``(ix * ny + iy) * nz + iz``), so that the cells
``iz - 1 .. iz + 1`` of one ``(ix, iy)`` column are one contiguous run of points: a point's 27
surrounding cells are 9 runs, found once per cell by binary search over the sorted cell keys.
A point's k nearest are final once the k-th is closer than the nearest face of the searched
block of cells; otherwise the block grows by a ring of cells (sparse places, outliers).

The cell size aims at a few points per occupied cell for a sample of a surface (a 2-D set in 3-D),
measured on a subsample; it only affects speed, never the answer. The same grid answers ball
queries (:func:`grid_ball`): the support of a point of a cloud is every point in its ball.

Measured (docs/BENCHMARKS.md, "Point clouds"): 1M points on a sphere, k = 10, about 4x faster
than scipy's cKDTree query on the same two cores, which is why this is a grid and not a tree.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import MeshError
from .jit import jit, jit_parallel, launch, prange

__all__ = ["build_grid", "sample_cell_size", "cell_sample_step", "nearest_neighbours", "grid_ball", "grid_gather",
           "symmetric_graph", "neighbour_steps", "GRAPH_NEIGHBOURS"]

GRAPH_NEIGHBOURS = 10
"""Neighbours per point of a point cloud's neighbour graph (made symmetric: about 13 edges a
point), along which normals are oriented. Supports are not searched along it: a search through
the graph inside the ball missed 0.03 % of the ball's points on uniform random samples and 5-10 %
on scan rows 5:1 apart (the rows' kNN lists stay in their row), so supports come from the grid
(:func:`grid_ball`), exactly."""

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


@jit
def _first_at_least(keys, value):
    """Index of the first ``keys[i] >= value`` in sorted ``keys`` (binary search)."""
    lo, hi = 0, keys.size
    while lo < hi:
        mid = (lo + hi) >> 1
        if keys[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo


@jit
def _scan_block(i, ring, cx, cy, cz, dims, cell_keys, cell_start, xs, ys, zs, out_d, out_i, k):
    """Scan the (2 ring + 1)^3 cells around cell (cx, cy, cz) for the k nearest of sorted point i.

    Row i of ``out_d`` (squared distances) and ``out_i`` (sorted indices) is kept ascending. Rows
    are indexed, not sliced: a view made per point inside a parallel loop costs an atomic
    reference count each time.
    """
    nx, ny, nz = dims[0], dims[1], dims[2]
    px, py, pz = xs[i], ys[i], zs[i]
    z0 = max(cz - ring, 0)
    z1 = min(cz + ring, nz - 1)
    for ix in range(max(cx - ring, 0), min(cx + ring, nx - 1) + 1):
        for iy in range(max(cy - ring, 0), min(cy + ring, ny - 1) + 1):
            base = (ix * ny + iy) * nz
            a = _first_at_least(cell_keys, base + z0)
            b = _first_at_least(cell_keys, base + z1 + 1)
            for j in range(cell_start[a], cell_start[b]):
                if j == i:
                    continue
                dx, dy, dz = xs[j] - px, ys[j] - py, zs[j] - pz
                d2 = dx * dx + dy * dy + dz * dz
                if d2 >= out_d[i, k - 1]:
                    continue
                # insertion into the ascending row, written out here: a helper call per
                # candidate costs reference counting on its array arguments (several times slower)
                m = k - 1
                while m > 0 and out_d[i, m - 1] > d2:
                    out_d[i, m] = out_d[i, m - 1]
                    out_i[i, m] = out_i[i, m - 1]
                    m -= 1
                out_d[i, m] = d2
                out_i[i, m] = j


@jit
def _margin(i, ring, cx, cy, cz, dims, lo, h, xs, ys, zs):
    """Distance from sorted point i to the nearest face of its searched block that has cells beyond."""
    m = math.inf
    c = (cx, cy, cz)
    p = (xs[i], ys[i], zs[i])
    for a in range(3):
        if c[a] - ring > 0:
            m = min(m, p[a] - (lo[a] + (c[a] - ring) * h))
        if c[a] + ring < dims[a] - 1:
            m = min(m, lo[a] + (c[a] + ring + 1) * h - p[a])
    return m


@jit_parallel
def _knn_kernel(cell_keys, cell_start, dims, lo, h, xs, ys, zs, k, out_d, out_i):
    n_cells = cell_keys.size
    nx, ny, nz = dims[0], dims[1], dims[2]
    for c in prange(n_cells):
        key = cell_keys[c]
        cz = key % nz
        cy = (key // nz) % ny
        cx = key // (nz * ny)
        for i in range(cell_start[c], cell_start[c + 1]):
            ring = 1
            while True:
                for j in range(k):
                    out_d[i, j] = np.inf
                    out_i[i, j] = -1
                _scan_block(i, ring, cx, cy, cz, dims, cell_keys, cell_start, xs, ys, zs, out_d, out_i, k)
                margin = _margin(i, ring, cx, cy, cz, dims, lo, h, xs, ys, zs)
                # final when the k-th is inside the block's sphere, or the block holds everything
                if out_d[i, k - 1] <= margin * margin or margin == math.inf:
                    break
                ring += 1


def build_grid(points: np.ndarray, k: int = 10, *, cell: float | None = None, origin: np.ndarray | None = None):
    """The uniform grid of :func:`nearest_neighbours` and of point-cloud ball supports.

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
    order = np.argsort(keys, kind="stable")
    keys = keys[order]
    starts = np.flatnonzero(np.diff(keys)) + 1
    cell_keys = keys[np.concatenate(([0], starts))]
    cell_start = np.concatenate(([0], starts, [n])).astype(np.int64)
    del keys
    xs, ys, zs = (np.ascontiguousarray(points[order, c]) for c in range(3))
    origin = np.array([lo[0], lo[1], lo[2], h])
    arrays = (cell_keys, cell_start, dims.astype(np.int64), order.astype(np.int64), origin, xs, ys, zs)
    for arr in arrays:
        arr.setflags(write=False)
    return arrays[:4], arrays[4:]


def nearest_neighbours(points: np.ndarray, k: int, grid=None) -> tuple[np.ndarray, np.ndarray]:
    """The k nearest other points of every point (a uniform-grid search).

    Parameters
    ----------
    points : (n, 3) float64
    k : int
        Neighbours wanted (>= 1).
    grid : optional
        :func:`build_grid` of these points, if already made.

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
    (cell_keys, cell_start, dims, order), (origin, xs, ys, zs) = grid or build_grid(points, k)
    n = order.size
    out_d = np.empty((n, k))
    out_i = np.empty((n, k), np.int64)
    launch(_knn_kernel, cell_keys, cell_start, dims, origin[:3].copy(), float(origin[3]), xs, ys, zs, int(k),
           out_d, out_i)
    # back to the caller's order: rows by original point, entries as original indices
    indices = np.empty_like(out_i)
    indices[order] = np.where(out_i >= 0, order[np.maximum(out_i, 0)], -1)
    del out_i
    distances = np.empty_like(out_d)
    np.sqrt(out_d, out=out_d)
    distances[order] = out_d
    return indices, distances


@jit
def _ball_cells(px, py, pz, radius2, dims, origin):
    """The block of grid cells ``(x0, x1, y0, y1, z0, z1)`` (inclusive) that holds every point within
    ``sqrt(radius2)`` of (px, py, pz): the point's cell and enough rings around it that a ball of
    that radius around any point of the cell stays inside."""
    nx, ny, nz = dims[0], dims[1], dims[2]
    h = origin[3]
    cx = min(max(int(math.floor((px - origin[0]) / h)), 0), nx - 1)
    cy = min(max(int(math.floor((py - origin[1]) / h)), 0), ny - 1)
    cz = min(max(int(math.floor((pz - origin[2]) / h)), 0), nz - 1)
    widest = max(nx, max(ny, nz))
    reach = math.sqrt(radius2) / h
    # an infinite or huge ball (fewer points than knn=K asks for) covers the whole grid
    ring = widest if not reach < widest else int(math.ceil(reach))
    return (max(cx - ring, 0), min(cx + ring, nx - 1), max(cy - ring, 0), min(cy + ring, ny - 1),
            max(cz - ring, 0), min(cz + ring, nz - 1))


@jit
def _ball_scan(px, py, pz, centre, radius2, cells, coords, names, queue, dist2):
    """The points of the grid within ``sqrt(radius2)`` of (px, py, pz), but ``centre``, after it.

    ``queue[0] = centre`` and ``queue[1:count]`` the ball's points in the scan order of the grid
    (its cells, then their sorted positions): original indices (``names``, the grid's ``order``)
    or sorted positions (``names`` None), the centre named the same way. ``dist2`` (n,) float64
    receives their squared distances (0 at 0), unless None. Returns ``count``.
    """
    cell_keys, cell_start, dims, order = cells
    origin, xs, ys, zs = coords
    ny, nz = dims[1], dims[2]
    x0, x1, y0, y1, z0, z1 = _ball_cells(px, py, pz, radius2, dims, origin)
    queue[0] = centre
    if dist2 is not None:
        dist2[0] = 0.0
    count = 1
    for ix in range(x0, x1 + 1):
        for iy in range(y0, y1 + 1):
            base = (ix * ny + iy) * nz
            a = _first_at_least(cell_keys, base + z0)
            b = _first_at_least(cell_keys, base + z1 + 1)
            for j in range(cell_start[a], cell_start[b]):
                dx, dy, dz = xs[j] - px, ys[j] - py, zs[j] - pz
                d2 = dx * dx + dy * dy + dz * dz
                if d2 <= radius2:
                    q = j if names is None else names[j]
                    if q != centre:
                        queue[count] = q
                        if dist2 is not None:
                            dist2[count] = d2
                        count += 1
    return count


@jit
def grid_ball(p, radius2, cells, coords, x, y, z, queue):
    """Every point within ``sqrt(radius2)`` of point ``p`` (p excluded), through the grid.

    Parameters
    ----------
    p : int
        The centre point (an index of the original order).
    radius2 : float
        Squared radius.
    cells, coords : tuples
        :func:`build_grid`.
    x, y, z : (n,) float64
        The coordinates in the original order.
    queue : (n,) int64
        Receives ``p`` at 0 and the ball's points (original indices) after it.

    Returns
    -------
    count : int
        ``queue[1:count]`` is the ball.
    """
    return _ball_scan(x[p], y[p], z[p], p, radius2, cells, coords, cells[3], queue, None)


@jit
def grid_gather(i, radius2, cells, coords, queue, dist2):
    """The ball of sorted point ``i`` in sorted positions, with the squared distances.

    The same ball as :func:`grid_ball`, found in the same order, but named by positions in the
    grid's sorted order (``coords``' columns), so that a kernel walking the points cell by cell
    reads its neighbours' coordinates from nearby memory instead of from random places.

    Parameters
    ----------
    i : int
        The centre's sorted position (``cells[3][i]`` is its index in the cloud).
    radius2 : float
        Squared radius.
    cells, coords : tuples
        :func:`build_grid`.
    queue : (n,) int64
        Receives ``i`` at 0 and the ball's sorted positions after it.
    dist2 : (n,) float64
        Receives 0 at 0 and the squared distance of each ball point after it.

    Returns
    -------
    count : int
        ``queue[1:count]`` is the ball (the centre excluded).
    """
    xs, ys, zs = coords[1], coords[2], coords[3]
    return _ball_scan(xs[i], ys[i], zs[i], i, radius2, cells, coords, None, queue, dist2)


@jit
def _graph_counts(indices, counts):
    n, k = indices.shape
    for i in range(n):
        for j in range(k):
            q = indices[i, j]
            if q >= 0:
                counts[i] += 1
                counts[q] += 1


@jit
def _graph_fill(indices, indptr, fill, out):
    n, k = indices.shape
    for i in range(n):
        for j in range(k):
            q = indices[i, j]
            if q >= 0:
                out[indptr[i] + fill[i]] = q
                fill[i] += 1
                out[indptr[q] + fill[q]] = i
                fill[q] += 1


@jit_parallel
def _graph_dedupe(indptr, out, unique):
    n = indptr.size - 1
    for i in prange(n):
        row = out[indptr[i]:indptr[i + 1]]
        row.sort()
        u = 0
        for j in range(row.size):
            if j == 0 or row[j] != row[j - 1]:
                row[u] = row[j]
                u += 1
        unique[i] = u


@jit_parallel
def _graph_compact(indptr, out, new_ptr, new):
    n = indptr.size - 1
    for i in prange(n):
        for j in range(new_ptr[i + 1] - new_ptr[i]):
            new[new_ptr[i] + j] = out[indptr[i] + j]


def symmetric_graph(indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The symmetric neighbour graph of kNN lists: q is a neighbour of p if either lists the other.

    Parameters
    ----------
    indices : (n, k) int64
        :func:`nearest_neighbours` indices (-1 entries ignored).

    Returns
    -------
    indptr : (n+1,) int64
    neighbours : (a,) int64
        Row p is ``neighbours[indptr[p]:indptr[p+1]]``, sorted, without repeats or p itself.
    """
    n = indices.shape[0]
    counts = np.zeros(n, np.int64)
    _graph_counts(indices, counts)
    indptr = np.zeros(n + 1, np.int64)
    np.cumsum(counts, out=indptr[1:])
    out = np.empty(indptr[-1], np.int64)
    _graph_fill(indices, indptr, np.zeros(n, np.int64), out)
    unique = np.empty(n, np.int64)
    launch(_graph_dedupe, indptr, out, unique)
    new_ptr = np.zeros(n + 1, np.int64)
    np.cumsum(unique, out=new_ptr[1:])
    new = np.empty(new_ptr[-1], np.int64)
    launch(_graph_compact, indptr, out, new_ptr, new)
    return new_ptr, new


@jit_parallel
def _steps_kernel(points, indices, parts, out):
    n, k = indices.shape
    for t in prange(parts):
        lo, hi = t * n // parts, (t + 1) * n // parts
        for a in range(3):
            out[t, a] = np.inf
        for p in range(lo, hi):
            for j in range(k):
                q = indices[p, j]
                if q >= 0:
                    for a in range(3):
                        d = abs(points[q, a] - points[p, a])
                        if 0.0 < d < out[t, a]:
                            out[t, a] = d


def neighbour_steps(points: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """(3,) float64: per axis, the smallest non-zero coordinate difference between a point and one of
    its nearest (``indices`` (n, k), -1 entries skipped); 0 where every difference is 0.

    On coordinates stored on a grid (a LAS file's scale, rounding) no two points differ by less than
    the grid's step, and near neighbours differ by one step somewhere, so this is the step; on
    coordinates of full precision it is tiny (n k differences of spread values)."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    indices = np.ascontiguousarray(indices, dtype=np.int64)
    parts = max(1, min(64, indices.shape[0]))
    out = np.empty((parts, 3))
    launch(_steps_kernel, points, indices, parts, out)
    least = out.min(axis=0)
    return np.where(np.isfinite(least), least, 0.0)
