"""Per-face geometry of a mesh and its repeated positions.

:func:`triangle_geometry` gives the vector area, area and degeneracy of every triangle,
:func:`polygon_geometry` the same of every polygon of any size;
:func:`duplicate_positions` the vertices that repeat the position of a lower one.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import jit, jit_parallel, prange

__all__ = ["triangle_geometry", "polygon_geometry", "duplicate_positions", "KERNELS"]


@jit_parallel
def triangle_geometry(tri, vertices, shape, degenerate):
    """Per triangle (p0, p1, p2): Newell vector area ``(p1 - p0) x (p2 - p0) / 2``, its norm, and
    degeneracy (a repeated index, or area <= 1e-12 times the squared longest side).

    ``shape = (vector_area (m, 3), area (m,))``, or None when not asked for (a 1-ring estimator
    reads only ``degenerate`` (m,), and writing 32 bytes per face it never reads cost it more than
    the test; numba compiles that case without the writes).
    """
    for f in prange(tri.shape[0]):
        i, j, k = tri[f, 0], tri[f, 1], tri[f, 2]
        ax = vertices[j, 0] - vertices[i, 0]
        ay = vertices[j, 1] - vertices[i, 1]
        az = vertices[j, 2] - vertices[i, 2]
        bx = vertices[k, 0] - vertices[i, 0]
        by = vertices[k, 1] - vertices[i, 1]
        bz = vertices[k, 2] - vertices[i, 2]
        nx = 0.5 * (ay * bz - az * by)
        ny = 0.5 * (az * bx - ax * bz)
        nz = 0.5 * (ax * by - ay * bx)
        a = math.sqrt(nx * nx + ny * ny + nz * nz)
        if shape is not None:
            shape[0][f, 0] = nx
            shape[0][f, 1] = ny
            shape[0][f, 2] = nz
            shape[1][f] = a
        cx = vertices[k, 0] - vertices[j, 0]
        cy = vertices[k, 1] - vertices[j, 1]
        cz = vertices[k, 2] - vertices[j, 2]
        longest2 = max(ax * ax + ay * ay + az * az, cx * cx + cy * cy + cz * cz, bx * bx + by * by + bz * bz)
        degenerate[f] = i == j or j == k or i == k or a <= 1e-12 * longest2


@jit_parallel
def polygon_geometry(faces, vertices, shape, degenerate):
    """Per polygon: Newell vector area (half the sum of ``p_c x p_next(c)`` over its corners), its
    norm, and degeneracy (an index repeated anywhere in the face, or area <= 1e-12 times the squared
    longest side). One face at a time: the arrays of every corner's position and cross product that
    numpy would make (0.5 GB at a million quads) are never built.

    ``faces = (offsets (m + 1,), indices (c,))``, the corners of face f at ``offsets[f]:offsets[f+1]``;
    ``shape = (vector_area (m, 3), area (m,))``; ``degenerate`` (m,) bool.
    """
    offsets, indices = faces
    for f in prange(offsets.size - 1):
        start, stop = offsets[f], offsets[f + 1]
        nx = ny = nz = 0.0
        longest2 = 0.0
        repeated = False
        for c in range(start, stop):
            i = indices[c]
            j = indices[c + 1] if c + 1 < stop else indices[start]
            ax, ay, az = vertices[i, 0], vertices[i, 1], vertices[i, 2]
            bx, by, bz = vertices[j, 0], vertices[j, 1], vertices[j, 2]
            nx += ay * bz - az * by
            ny += az * bx - ax * bz
            nz += ax * by - ay * bx
            dx, dy, dz = bx - ax, by - ay, bz - az
            longest2 = max(longest2, dx * dx + dy * dy + dz * dz)
            for d in range(c + 1, stop):
                repeated = repeated or indices[d] == i
        nx, ny, nz = 0.5 * nx, 0.5 * ny, 0.5 * nz
        a = math.sqrt(nx * nx + ny * ny + nz * nz)
        shape[0][f, 0] = nx
        shape[0][f, 1] = ny
        shape[0][f, 2] = nz
        shape[1][f] = a
        degenerate[f] = repeated or a <= 1e-12 * longest2


@jit
def _mix(h, bits):
    """Fold 64 bits into the hash h (multiply-xorshift: nearby coordinates spread over the table)."""
    h = (h ^ bits) * np.uint64(0x9E3779B97F4A7C15)
    return h ^ (h >> np.uint64(31))


@jit
def duplicate_positions(vertices, bits, out):
    """``out[v]`` = True where vertex v sits at exactly the position of a vertex with a lower index.

    One pass in index order with an open-addressing hash table of the positions seen (linear time;
    a sort would be n log n).

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite positions (``0.0`` and ``-0.0`` are the same position, as for ``==``).
    bits : (n, 3) uint64
        The same memory as ``vertices`` seen as integers (``vertices.view(np.uint64)``), to hash.
    out : (n,) bool
    """
    n = vertices.shape[0]
    size = 1
    while size < 2 * n:
        size *= 2
    table = np.full(size, -1, np.int64)
    mask = np.uint64(size - 1)
    for v in range(n):
        x, y, z = vertices[v, 0], vertices[v, 1], vertices[v, 2]
        h = np.uint64(0)
        for c in range(3):
            # -0.0 == 0.0: both hash as 0
            h = _mix(h, bits[v, c] if vertices[v, c] != 0.0 else np.uint64(0))
        slot = h & mask
        out[v] = False
        while True:
            w = table[slot]
            if w < 0:
                table[slot] = v
                break
            if vertices[w, 0] == x and vertices[w, 1] == y and vertices[w, 2] == z:
                out[v] = True
                break
            slot = (slot + np.uint64(1)) & mask


KERNELS = (triangle_geometry, polygon_geometry, duplicate_positions)
"""The numba dispatchers of this module (for :func:`curv.core.jit.compile_pending`)."""
