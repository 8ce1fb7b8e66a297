"""Balls of points through a point cloud's grid (numba): the support of a point of a cloud is every
point within its radius (:mod:`curv.geometry.neighbourhood`, the point normals' one pass).

A ball is read from the block of cells that holds it (:mod:`curv.core.grid_blocks`), in the
block's order, so every way of asking (by original index, :func:`grid_ball`; by sorted position,
:func:`grid_gather`; from a cell's block looked up once, :func:`block_gather`) gives the same points
in the same order.
"""

from __future__ import annotations

import math

from .grid_blocks import block_around, next_run, ring_of, start_walk
from .jit import jit

__all__ = ["grid_ball", "grid_gather", "block_gather"]


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
    return block_around(cx, cy, cz, ring_of(radius2, dims, origin), dims)


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
    block = _ball_cells(px, py, pz, radius2, dims, origin)
    queue[0] = centre
    if dist2 is not None:
        dist2[0] = 0.0
    count = 1
    walk = start_walk(block, dims, cell_keys)
    while True:
        a, b, walk = next_run(block, dims, cells, walk)
        if a < 0:
            break
        for j in range(a, b):
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
        :func:`curv.core.grid.build_grid`.
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
        :func:`curv.core.grid.build_grid`.
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
def block_gather(i, radius2, block, coords, queue, dist2):
    """:func:`grid_gather` from a block of :func:`curv.core.grid_blocks.block_cells` (around the
    cell of sorted point ``i``, at least as many rings as this radius needs): the same ball in the same order.

    ``block``: ``(runs, m, bounds)``, the block's occupied cells as runs and their boxes
    (:func:`curv.core.grid_blocks.block_cells`); a cell whose box lies farther than the radius from
    the centre is skipped (a ball's points keep their order: the same ball). ``queue``
    and ``dist2`` need one slot more than the grid has points (each candidate is written before it
    is tested: no branch per candidate). Returns ``count`` (``queue[1:count]`` the ball).
    """
    runs, m, bounds = block
    xs, ys, zs = coords[1], coords[2], coords[3]
    px, py, pz = xs[i], ys[i], zs[i]
    queue[0] = i
    dist2[0] = 0.0
    count = 1
    for r in range(m):
        ex = max(bounds[r, 0] - px, px - bounds[r, 1], 0.0)
        ey = max(bounds[r, 2] - py, py - bounds[r, 3], 0.0)
        ez = max(bounds[r, 4] - pz, pz - bounds[r, 5], 0.0)
        if ex * ex + ey * ey + ez * ez > radius2:
            continue
        for j in range(runs[r, 0], runs[r, 1]):
            dx, dy, dz = xs[j] - px, ys[j] - py, zs[j] - pz
            d2 = dx * dx + dy * dy + dz * dz
            queue[count] = j
            dist2[count] = d2
            count += (d2 <= radius2) & (j != i)
    return count
