"""The corner pass: what one walk over the corners around each vertex gives, without the edge table.

The halfedges at u (leaving or arriving at one of its corners), sorted by their other endpoint w,
are exactly those of the edges (u, w), one per face: their distinct w are the neighbours, their
group sizes give border and non-manifold edges, and linking the corners whose faces share an edge
counts the fans. Everything is local to u, so vertices run in parallel. :func:`corner_pass` gives
the border, non-manifold and inconsistently oriented vertices, the edge neighbours, the longest
1-ring edge and the Max vertex normals (what a fresh estimate needs); :func:`fan_flags` the flags
alone.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..corner_normals import corner_terms, unit
from ..jit import jit, jit_parallel, launch, prange, threads
from .corners import find_root, insertion_sort, next_corner, prev_corner, ring_width, sort_pairs, thread_slice

__all__ = ["corner_pass", "CornerPass", "fan_flags", "KERNELS"]


@jit
def _one_fan(u, d, lead, trail, match):
    """The fans at u when its fan is clean, else 0.

    Clean: no face repeats u, and every edge (u, w) has exactly one halfedge leaving u (some corner's
    next vertex is w) and one arriving at u (some corner's previous vertex is w), so every edge has
    two faces that run it in opposite directions. Then corner i and the corner ``match[i]`` whose
    previous vertex is ``lead[i]`` share the edge (u, lead[i]), and the fans are the cycles of that
    permutation. Quadratic in the (small) corner count, with no sort.

    Parameters
    ----------
    u, d : int
        The vertex and its number of corners.
    lead, trail : (>= d,) int64
        The next and the previous vertex of each corner's face.
    match : (>= d,) int64
        Scratch.

    Returns
    -------
    int
        The number of fans (cycles), 0 when the fan is not clean (or u has no corner).
    """
    if d == 0:
        return 0
    for i in range(d):
        match[i] = -1
    for i in range(d):
        w = lead[i]
        if w == u or trail[i] == u:
            return 0
        # the first corner arriving from w: had two corners arrived from w, two leading corners would
        # have to share one (a collision below), since d leads matched to distinct corners use all d
        found = -1
        for j in range(d):
            if trail[j] == w:
                found = j
                break
        if found < 0 or match[found] >= 0:
            return 0
        match[found] = i  # match is filled backwards: match[j] = the corner whose lead is trail[j]
    fans = 0
    for i in range(d):
        if match[i] >= 0:
            fans += 1
            j = i
            while match[j] >= 0:
                k = match[j]
                match[j] = -1
                j = k
    return fans


@jit
def _sorted_fan(ring, x, u, scratch, spread):
    """Flags, distinct neighbours and longest edge of u from its halfedges sorted by other endpoint.

    The halfedges at u (leaving or arriving at each of its corners), sorted by other endpoint, are
    those of the edges (u, w), one per face. Any fan (a border, a non-manifold edge or vertex,
    faces of opposite orientation, a repeated index).

    Parameters
    ----------
    ring : (indptr, corners, indices, corner_next, corner_prev)
        As :func:`corner_pass` takes them.
    x : (n, 3) float64
    u : int
    scratch : (other, corner, parent)
        (>= 2 d,) int64 each, d the corners at u.
    spread : (2 h,) int or None
        Receives u's neighbours, sorted, from ``spread[2 * indptr[u]]`` on (None: not asked for).

    Returns
    -------
    nonmanifold, border, inconsistent : bool
    distinct : int
        Number of neighbours.
    far : float
        The longest edge (0 without one).
    """
    indptr, corners, indices, corner_next, corner_prev = ring
    other, corner, parent = scratch
    first, last = indptr[u], indptr[u + 1]
    # corner[k] = 2 (position of the corner at u) + (1 if the halfedge leaves u)
    k = 0
    for i in range(last - first):
        c = corners[first + i]
        w = indices[next_corner(c, corner_next)]
        if w != u:
            other[k], corner[k] = w, 2 * i + 1
            k += 1
        w = indices[prev_corner(c, corner_prev)]
        if w != u:
            other[k], corner[k] = w, 2 * i
            k += 1
        parent[i] = i
    sort_pairs(other, corner, k)
    fans = last - first
    on_border = on_nonmanifold_edge = on_inconsistent_edge = False
    distinct = 0
    far = 0.0
    start = 0
    for i in range(1, k + 1):
        if i < k and other[i] == other[start]:
            continue
        # halfedges start .. i-1 are those of edge (u, w): one per face
        w = other[start]
        if spread is not None:
            spread[2 * first + distinct] = w
        distinct += 1
        far = _farther(x, u, w, far)
        faces = i - start
        if faces == 2:
            # the two faces are one fan at u; opposite orientation if both run the same way
            a, b = find_root(parent, corner[start] >> 1), find_root(parent, corner[start + 1] >> 1)
            if a != b:
                parent[max(a, b)] = min(a, b)
                fans -= 1
            if (corner[start] & 1) == (corner[start + 1] & 1):
                on_inconsistent_edge = True
        elif faces == 1:
            on_border = True
        else:
            on_nonmanifold_edge = True
        start = i
    return fans > 1 or on_nonmanifold_edge, on_border or on_nonmanifold_edge, on_inconsistent_edge, distinct, far


@jit
def _farther(x, u, w, far):
    """The larger of ``far`` and the length of edge (u, w)."""
    # squares do not see the sign: the same length as Mesh.edge_lengths, to the bit
    dx = x[w, 0] - x[u, 0]
    dy = x[w, 1] - x[u, 1]
    dz = x[w, 2] - x[u, 2]
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    return length if length > far else far


@jit_parallel
def _walk_fans(ring, x, width, parts, flags, extras):
    """The walk of :func:`corner_pass` and :func:`fan_flags`: ``flags = (nonmanifold, border,
    inconsistent)`` (n,) bool; ``extras = (counts (n,), spread (2 h,), longest (n,), normals (n, 3))``,
    or None for the flags alone (numba compiles that case without the rest)."""
    indptr, corners, indices, corner_next, corner_prev = ring
    nonmanifold, border, inconsistent = flags
    n = indptr.size - 1
    for t in prange(parts):
        other, corner, parent = np.empty(width, np.int64), np.empty(width, np.int64), np.empty(width, np.int64)
        lead, trail = np.empty(width, np.int64), np.empty(width, np.int64)
        lo, hi = thread_slice(n, t, parts)
        for u in range(lo, hi):
            first, last = indptr[u], indptr[u + 1]
            d = last - first
            # the next and previous vertex of each corner, and the Max normal from them
            sx, sy, sz = 0.0, 0.0, 0.0
            far2 = 0.0  # the longest squared edge to a next vertex
            for i in range(d):
                c = corners[first + i]
                b, q = indices[next_corner(c, corner_next)], indices[prev_corner(c, corner_prev)]
                lead[i], trail[i] = b, q
                if extras is not None:
                    wx, wy, wz, lead2 = corner_terms(x, u, b, q)
                    sx += wx
                    sy += wy
                    sz += wz
                    far2 = lead2 if lead2 > far2 else far2
            if extras is not None:
                normals = extras[3]
                normals[u, 0], normals[u, 1], normals[u, 2] = unit(sx, sy, sz)
            fans = _one_fan(u, d, lead, trail, parent)
            if fans > 0:
                nonmanifold[u] = fans > 1
                border[u] = inconsistent[u] = False
                if extras is not None:
                    # the usual vertex: its neighbours are the next vertices of its corners, each once; the
                    # longest edge is the root of the longest square (sqrt is monotonic and correctly
                    # rounded: the same value, to the bit, as the longest of the roots, _farther)
                    insertion_sort(lead, d)
                    spread = extras[1]
                    for i in range(d):
                        spread[2 * first + i] = lead[i]
                    extras[0][u] = d
                    extras[2][u] = math.sqrt(far2)
            else:
                nonmanifold[u], border[u], inconsistent[u], distinct, far = _sorted_fan(
                    ring, x, u, (other, corner, parent), _spread(extras))
                if extras is not None:
                    extras[0][u] = distinct
                    extras[2][u] = far


@jit
def _spread(extras):
    """The neighbours' slots of :func:`_walk_fans`' extras, or None without them."""
    if extras is None:
        return None
    return extras[1]


def fan_flags(indptr: np.ndarray, corners: np.ndarray, indices: np.ndarray, corner_next: np.ndarray,
              corner_prev: np.ndarray, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The vertex flags of :func:`corner_pass` alone (the same arrays, to the bit), for a caller that
    needs neither the neighbours nor the normals (meyer computes its own normals from the corners).

    Parameters as in :func:`corner_pass`.

    Returns
    -------
    nonmanifold, border, inconsistent : (n,) bool
    """
    n = indptr.size - 1
    nonmanifold, border, inconsistent = np.empty(n, np.bool_), np.empty(n, np.bool_), np.empty(n, np.bool_)
    launch(_walk_fans, (indptr, corners, indices, corner_next, corner_prev), vertices, ring_width(indptr),
           max(1, min(threads(), n)), (nonmanifold, border, inconsistent), None)
    return nonmanifold, border, inconsistent


@jit_parallel
def _gather_neighbours(indptr, spread, out_ptr, out):
    for u in prange(indptr.size - 1):
        source = 2 * indptr[u]
        for i in range(out_ptr[u + 1] - out_ptr[u]):
            out[out_ptr[u] + i] = spread[source + i]


class CornerPass(NamedTuple):
    """What one walk over the corners around each vertex gives (:func:`corner_pass`)."""

    nonmanifold: np.ndarray
    """(n,) bool: on an edge with more than two faces, or the faces around the vertex form several fans
    (two corners are in one fan when their faces share an edge at the vertex that has exactly two faces)."""
    border: np.ndarray
    """(n,) bool: on an edge with one face or more than two."""
    inconsistent: np.ndarray
    """(n,) bool: on an edge with two faces that run it the same way (faces of opposite orientation)."""
    neighbour_ptr: np.ndarray
    """(n + 1,) int64 row pointers of ``neighbours``."""
    neighbours: np.ndarray
    """(a,) int64 the distinct edge neighbours of each vertex, sorted: the endpoints of its edges."""
    longest_edge: np.ndarray
    """(n,) float64 the longest edge at each vertex (0 without one)."""
    max_normals: np.ndarray
    """(n, 3) float64, column-major: unit Max (1999) vertex normals (:func:`curv.geometry.normals.max_normal`);
    NaN rows where the corner terms cancel or there is no corner."""


def corner_pass(indptr: np.ndarray, corners: np.ndarray, indices: np.ndarray, corner_next: np.ndarray,
                corner_prev: np.ndarray, vertices: np.ndarray) -> CornerPass:
    """Vertex flags, edge neighbours, longest 1-ring edge and Max normals in one walk over the corners.

    The halfedges at u (leaving or arriving at one of its corners), sorted by their other endpoint w,
    are exactly those of the edges (u, w), one per face: their distinct w are the neighbours, their
    group sizes give border and non-manifold edges, and linking the corners whose faces share an edge
    counts the fans. Everything is local to u (no edge table), so vertices run in parallel.

    Parameters
    ----------
    indptr, corners : (n + 1,), (h,) int64
        Corners grouped by vertex (:func:`group_corners`).
    indices : (h,) int64
        Vertex of each corner.
    corner_next, corner_prev : (h,) int32 or int64, or both None
        Next and previous corner in its face; None on a triangle mesh
        (:func:`~curv.core.connectivity.corners.next_corner`).
    vertices : (n, 3) float64

    Returns
    -------
    CornerPass
    """
    n = indptr.size - 1
    h = indices.size
    nonmanifold, border, inconsistent = np.empty(n, np.bool_), np.empty(n, np.bool_), np.empty(n, np.bool_)
    counts = np.empty(n, np.int64)
    # a vertex has at most two neighbours per corner: each writes into its own slot of this
    spread = np.empty(2 * h, np.int32 if n < 2**31 else np.int64)
    # column-major: the fit kernels read each coordinate as a contiguous column
    # (curv.geometry.normals.cached_max_normals)
    longest, normals = np.empty(n), np.empty((n, 3), order="F")
    launch(_walk_fans, (indptr, corners, indices, corner_next, corner_prev), vertices, ring_width(indptr),
           max(1, min(threads(), n)), (nonmanifold, border, inconsistent), (counts, spread, longest, normals))
    out_ptr = np.zeros(n + 1, np.int64)
    np.cumsum(counts, out=out_ptr[1:])
    out = np.empty(out_ptr[-1], np.int64)
    launch(_gather_neighbours, indptr, spread, out_ptr, out)
    return CornerPass(nonmanifold, border, inconsistent, out_ptr, out, longest, normals)


KERNELS = (_walk_fans, _gather_neighbours)
"""The numba dispatchers of this module (for :func:`curv.core.jit.compile_pending`)."""
