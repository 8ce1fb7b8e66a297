"""Blocks of grid cells and the runs of sorted points they hold (numba): how every search of a point
cloud's grid (:mod:`curv.core.grid`) reads the points near a place.

A block is ``(x0, x1, y0, y1, z0, z1)``, inclusive cell bounds. Its points are one run of sorted
positions per ``(ix, iy)`` column (the column's cells ``z0 .. z1``, found by binary search over the
sorted cell keys). A block with more columns than occupied cells between its first and last key (a
point far from the rest: a grid of mostly empty cells) walks those cells instead of its columns,
in the same order: a search never costs more than the points. Either way the runs come in
ascending key order, so every search that reads a block sees the same points in the same order.
The point normals' pass reads a block one run per occupied cell, each with its box
(:func:`block_cells`), so that a ball skips the cells beyond its radius in z as well as in x and y.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import jit

__all__ = ["cell_coordinates", "block_around", "ring_of", "start_walk", "next_run", "block_runs", "cell_block",
           "cell_of", "block_cells", "cell_runs"]


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
def cell_coordinates(key, dims):
    """The cell ``(ix, iy, iz)`` of cell key ``key`` (``(ix * ny + iy) * nz + iz``)."""
    ny, nz = dims[1], dims[2]
    return key // (nz * ny), (key // nz) % ny, key % nz


@jit
def block_around(cx, cy, cz, ring, dims):
    """The block of grid cells ``(x0, x1, y0, y1, z0, z1)`` (inclusive) within ``ring`` rings of cell
    (cx, cy, cz)."""
    nx, ny, nz = dims[0], dims[1], dims[2]
    return (max(cx - ring, 0), min(cx + ring, nx - 1), max(cy - ring, 0), min(cy + ring, ny - 1),
            max(cz - ring, 0), min(cz + ring, nz - 1))


@jit
def ring_of(radius2, dims, origin):
    """The rings of cells around a point's cell that hold its ball of squared radius ``radius2``."""
    widest = max(dims[0], max(dims[1], dims[2]))
    reach = math.sqrt(radius2) / origin[3]
    # an infinite or huge ball (fewer points than knn=K asks for) covers the whole grid
    return widest if not reach < widest else int(math.ceil(reach))


@jit
def _block_span(block, dims, cell_keys):
    """The occupied cells ``c0 <= c < c1`` between the block's first and last cell key, and whether
    to walk them (``sparse``) instead of the block's columns: when the block has more columns than
    that many cells (a few points far from the rest make the grid mostly empty), so that a search
    never costs more than the points and occupied cells, however many empty cells it spans."""
    x0, x1, y0, y1, z0, z1 = block
    ny, nz = dims[1], dims[2]
    c0 = _first_at_least(cell_keys, (x0 * ny + y0) * nz + z0)
    c1 = _first_at_least(cell_keys, (x1 * ny + y1) * nz + z1 + 1)
    return c0, c1, (x1 - x0 + 1) * (y1 - y0 + 1) > c1 - c0


@jit
def _in_block(key, block, dims):
    """Whether the cell of ``key`` lies in ``block`` (``(x0, x1, y0, y1, z0, z1)``, inclusive)."""
    x0, x1, y0, y1, z0, z1 = block
    ix, iy, iz = cell_coordinates(key, dims)
    return x0 <= ix <= x1 and y0 <= iy <= y1 and z0 <= iz <= z1


@jit
def start_walk(block, dims, cell_keys):
    """The walk of :func:`next_run` over ``block``: its columns, or its occupied cells when sparse.
    ``(next, end, sparse)``; ``end - next`` bounds the runs it gives."""
    x0, x1, y0, y1, z0, z1 = block
    c0, c1, sparse = _block_span(block, dims, cell_keys)
    if sparse:
        return c0, c1, True
    return 0, (x1 - x0 + 1) * (y1 - y0 + 1), False


@jit
def next_run(block, dims, cells, walk):
    """The next run of sorted positions of ``block`` (``(x0, x1, y0, y1, z0, z1)``, inclusive): one
    column's occupied cells, or when the walk is sparse one occupied cell in the block, in
    ascending key order either way (the same points in the same order).

    ``walk``: ``(next, end, sparse)`` from :func:`start_walk`, the column (or occupied cell) to
    look at next. Returns ``(a, b, walk)``: the run ``a <= j < b`` (``a == -1`` at the end) and the
    walk moved on.
    """
    cell_keys, cell_start = cells[0], cells[1]
    ny, nz = dims[1], dims[2]
    x0, x1, y0, y1, z0, z1 = block
    at, end, sparse = walk
    if sparse:
        while at < end:
            c = at
            at += 1
            if _in_block(cell_keys[c], block, dims):
                return cell_start[c], cell_start[c + 1], (at, end, sparse)
        return -1, -1, (at, end, sparse)
    columns = y1 - y0 + 1
    while at < end:
        ix = x0 + at // columns
        iy = y0 + at % columns
        at += 1
        base = (ix * ny + iy) * nz
        a = cell_start[_first_at_least(cell_keys, base + z0)]
        b = cell_start[_first_at_least(cell_keys, base + z1 + 1)]
        if b > a:
            return a, b, (at, end, sparse)
    return -1, -1, (at, end, sparse)


@jit
def block_runs(block, cells, runs):
    """The runs of sorted positions of ``block`` (:func:`next_run`'s, in its order):
    ``runs[r, 0] <= j < runs[r, 1]`` for ``r < m``.

    Parameters
    ----------
    block : 6-tuple of int
        ``(x0, x1, y0, y1, z0, z1)``, inclusive.
    cells : tuple
        :func:`curv.core.grid.build_grid`'s ``cells``.
    runs : (k, 2) int64
        Scratch; grown when the block has more runs.

    Returns
    -------
    m : int
    runs : (k', 2) int64
        The scratch (a new array when it grew).
    """
    dims = cells[2]
    walk = start_walk(block, dims, cells[0])
    # at most one run per column, or per occupied cell when the walk is sparse
    most = walk[1] - walk[0]
    if runs.shape[0] < most:
        runs = np.empty((most, 2), np.int64)
    m = 0
    while True:
        a, b, walk = next_run(block, dims, cells, walk)
        if a < 0:
            break
        runs[m, 0] = a
        runs[m, 1] = b
        m += 1
    return m, runs


@jit
def cell_block(c, ring, cells, runs):
    """The sorted positions of the cells within ``ring`` rings of occupied cell ``c`` (the block that
    holds the ball of a point of cell c whose radius needs that many, :func:`ring_of`), as runs
    (:func:`block_runs`): one run per column in :func:`curv.core.grid_balls.grid_gather`'s scan order
    (empty columns left out).

    Every point of cell c finds its ball among these (:func:`curv.core.grid_balls.block_gather`), so
    a kernel that walks the points cell by cell looks the columns up once per cell instead of once
    per point. Returns ``(m, runs)`` as :func:`block_runs`.
    """
    dims = cells[2]
    cx, cy, cz = cell_coordinates(cells[0][c], dims)
    return block_runs(block_around(cx, cy, cz, ring, dims), cells, runs)


@jit
def cell_of(i, cell_start):
    """The occupied cell that holds sorted position ``i`` (``cell_start[c] <= i < cell_start[c + 1]``)."""
    lo, hi = 0, cell_start.size - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if cell_start[mid] <= i:
            lo = mid
        else:
            hi = mid
    return lo


COLUMN_MARGIN = 1e-9
"""Relative widening of a cell's box in :func:`block_cells` (of the coordinates' size): a point's
cell is ``floor((x - origin) / h)`` in floating point, so it may lie a rounding outside the
cell's exact bounds."""


@jit
def _add_cell(c, k, cells, origin, out):
    """Row k of ``out = (runs, bounds)``: occupied cell c's sorted positions and its box, widened by
    :data:`COLUMN_MARGIN`."""
    runs, bounds = out
    cell_keys, cell_start, dims = cells[0], cells[1], cells[2]
    h = origin[3]
    runs[k, 0], runs[k, 1] = cell_start[c], cell_start[c + 1]
    ix, iy, iz = cell_coordinates(cell_keys[c], dims)
    for a, at in ((0, ix), (1, iy), (2, iz)):
        lo = origin[a] + at * h
        margin = COLUMN_MARGIN * (abs(origin[a]) + abs(lo) + 2.0 * h)
        bounds[k, 2 * a], bounds[k, 2 * a + 1] = lo - margin, lo + h + margin


@jit
def block_cells(block, cells, origin, runs, bounds):
    """The occupied cells of ``block`` (``(x0, x1, y0, y1, z0, z1)``, inclusive) one run each, in
    :func:`next_run`'s order (the same points in the same order), with their boxes: a ball skips
    every cell whose box lies farther than its radius (:func:`curv.core.grid_balls.block_gather`),
    in z too, where a column's run was skipped only in x and y (on a sphere's ball grid the pass's
    balls read a third fewer points, 282 -> 188 a point for 58 in the ball: docs/BENCHMARKS.md, "one
    walk for the nearest and the ball").

    Parameters
    ----------
    block : 6-tuple of int
    cells : tuple
        :func:`curv.core.grid.build_grid`'s ``cells``.
    origin : (4,) float64
        The grid's lower corner and cell edge.
    runs : (k, 2) int64
        Scratch for the cells' sorted positions (``runs[r, 0] <= j < runs[r, 1]``).
    bounds : (k, 6) float64
        Scratch for their boxes ``(x0, x1, y0, y1, z0, z1)``.

    Returns
    -------
    m : int
    runs, bounds : arrays
        ``runs[:m]``, ``bounds[:m]`` (new arrays when the scratch had too few rows).
    """
    cell_keys, dims = cells[0], cells[2]
    ny, nz = dims[1], dims[2]
    x0, x1, y0, y1, z0, z1 = block
    c0, c1, sparse = _block_span(block, dims, cell_keys)
    most = min(c1 - c0, (x1 - x0 + 1) * (y1 - y0 + 1) * (z1 - z0 + 1))
    if runs.shape[0] < most:
        runs = np.empty((most, 2), np.int64)
    if bounds.shape[0] < most:
        bounds = np.empty((most, 6))
    out = (runs, bounds)
    m = 0
    if sparse:
        for c in range(c0, c1):
            if _in_block(cell_keys[c], block, dims):
                _add_cell(c, m, cells, origin, out)
                m += 1
        return m, runs, bounds
    for ix in range(x0, x1 + 1):
        for iy in range(y0, y1 + 1):
            base = (ix * ny + iy) * nz
            c = _first_at_least(cell_keys, base + z0)
            # a column's cells in the block follow one another: no second search for its end
            while c < c1 and cell_keys[c] <= base + z1:
                _add_cell(c, m, cells, origin, out)
                m += 1
                c += 1
    return m, runs, bounds


@jit
def cell_runs(i, c, radius2, cells, origin, block):
    """Move a walk over the sorted points to the cell of sorted position ``i`` (at or after cell
    ``c``) and read that cell's block for the widest ball of its points: :func:`block_cells` of the
    block within the rings of the largest ``radius2`` (squared radii, (n,), original order) of the
    cell's points (:func:`cell_block`'s block).

    ``block``: the scratch ``(runs, m, bounds)``. Returns ``(c, cell_end, block)``, the cell, where
    its points end in sorted order, and ``(runs, m, bounds)`` filled (the arrays grown if needed):
    what :func:`curv.core.grid_balls.block_gather` reads for each of the cell's points.
    """
    cell_start, order = cells[1], cells[3]
    while cell_start[c + 1] <= i:
        c += 1
    widest = 0.0
    for j in range(cell_start[c], cell_start[c + 1]):
        widest = max(widest, radius2[order[j]])
    runs, _, bounds = block
    cx, cy, cz = cell_coordinates(cells[0][c], cells[2])
    ring = ring_of(widest, cells[2], origin)
    m, runs, bounds = block_cells(block_around(cx, cy, cz, ring, cells[2]), cells, origin, runs, bounds)
    return c, cell_start[c + 1], (runs, m, bounds)
