"""Connectivity kernels behind :class:`curv.Mesh`: counting sorts over corners, halfedges and edges.

Every table is built in linear time (plus tiny sorts of the few halfedges that share a low vertex),
without hashing or sorting global keys:

- :func:`group_corners` groups the corners by their vertex (a stable counting sort);
- :func:`edge_table` lists the halfedges around each vertex u (from its corners), sorts that small
  list by the other endpoint w and numbers the distinct w > u: edges come out in lexicographic order;
- :func:`vertex_incidence` lists, per vertex, its edges in increasing edge order, which is also
  increasing neighbour order (all edges ``(q, p)`` with ``q < p`` precede the edges ``(p, r)``);
- :func:`corner_pass` walks the corners around each vertex once, without the edge table, for the
  border, non-manifold and inconsistently oriented vertices (counting the fans of faces around each
  vertex), the edge neighbours, the longest 1-ring edge and the Max vertex normals: what a fresh
  estimate needs;
- :func:`triangle_geometry` gives the vector area, area and degeneracy of every triangle.

The :class:`curv.Mesh` properties wrap them; their meaning is documented there.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .jit import jit, jit_parallel, launch, prange, threads
from .corner_normals import corner_terms, unit

__all__ = ["group_corners", "edge_table", "vertex_incidence", "vertex_face_incidence",
           "corner_pass", "CornerPass", "fan_flags", "next_corner", "prev_corner", "triangle_geometry", "duplicate_positions", "dihedral_angles",
           "corner_links", "component_labels", "edge_counts", "EDGE_COUNTS", "KERNELS"]

SMALL_GROUP = 32
"""The halfedges around a vertex are sorted by insertion up to this many; more (a vertex with a
huge fan) by a heap sort, so that no vertex costs quadratic time."""


def group_corners(vertex_of: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Stable counting sort of items by their vertex, a slice of the items per thread.

    Each thread counts its slice's items per vertex; a thread's items at v go after those of the
    earlier slices, so the order within a vertex stays increasing.

    Parameters
    ----------
    vertex_of : (h,) int64
        Vertex of each item (corner), in ``0 .. n-1``.
    n : int

    Returns
    -------
    indptr : (n + 1,) int64
    items : (h,) int64
        The items of vertex v are ``items[indptr[v]:indptr[v + 1]]``, in increasing order.
    """
    parts = max(1, min(threads(), vertex_of.size // 65536))
    slots = np.zeros((parts, n), np.int64)
    launch(_count_by_vertex, vertex_of, slots)
    indptr = np.empty(n + 1, np.int64)
    _first_slots(slots, indptr)
    items = np.empty(vertex_of.size, np.int64)
    launch(_place_by_vertex, vertex_of, slots, items)
    return indptr, items


@jit_parallel
def _count_by_vertex(vertex_of, counts):
    parts = counts.shape[0]
    for t in prange(parts):
        lo, hi = _slice(vertex_of.size, t, parts)
        row = counts[t]
        for c in range(lo, hi):
            row[vertex_of[c]] += 1


@jit
def _first_slots(counts, indptr):
    """Turn the per-slice counts (parts, n) into each slice's first slot at each vertex, in place; fill indptr."""
    parts, n = counts.shape
    total = 0
    for v in range(n):
        indptr[v] = total
        for t in range(parts):
            k = counts[t, v]
            counts[t, v] = total
            total += k
    indptr[n] = total


@jit_parallel
def _place_by_vertex(vertex_of, slots, items):
    parts = slots.shape[0]
    for t in prange(parts):
        lo, hi = _slice(vertex_of.size, t, parts)
        row = slots[t]
        for c in range(lo, hi):
            v = vertex_of[c]
            items[row[v]] = c
            row[v] += 1


@jit
def _before(key, value, i, j):
    return key[i] < key[j] or (key[i] == key[j] and value[i] < value[j])


@jit
def _sift_down(key, value, root, end):
    while 2 * root + 1 < end:
        child = 2 * root + 1
        if child + 1 < end and _before(key, value, child, child + 1):
            child += 1
        if not _before(key, value, root, child):
            return
        key[root], key[child] = key[child], key[root]
        value[root], value[child] = value[child], value[root]
        root = child


@jit
def _sort_pairs(key, value, k):
    """Sort the pairs ``(key[i], value[i])``, ``i < k``, in increasing order (key first).

    By insertion when short; a heap sort beyond :data:`SMALL_GROUP`, so that a vertex with a
    huge fan does not cost quadratic time.
    """
    if k <= SMALL_GROUP:
        for i in range(1, k):
            kk, v = key[i], value[i]
            j = i - 1
            while j >= 0 and (key[j] > kk or (key[j] == kk and value[j] > v)):
                key[j + 1], value[j + 1] = key[j], value[j]
                j -= 1
            key[j + 1], value[j + 1] = kk, v
        return
    for root in range(k // 2 - 1, -1, -1):
        _sift_down(key, value, root, k)
    for end in range(k - 1, 0, -1):
        key[0], key[end] = key[end], key[0]
        value[0], value[end] = value[end], value[0]
        _sift_down(key, value, 0, end)


@jit
def _upper_halfedges(u, corners_u, indices, corner_next, corner_prev, key, halfedge):
    """The halfedges between u and a higher vertex, sorted by (other endpoint, backward, id).

    Every halfedge with u at one end is either the one leaving a corner c at u (c itself) or the
    one arriving at it (``corner_prev[c]``): gathering both over u's corners lists each such
    halfedge once.

    Parameters
    ----------
    corners_u : (k,) int64
        The corners at u.
    key, halfedge : (>= 2k,) int64
        Scratch that receives, per halfedge, the sort key ``2 w + backward`` (w its other endpoint;
        backward: it runs from w down to u) and its id.

    Returns
    -------
    int
        Number of halfedges written. Those of one edge (u, w) are consecutive, as many as the edge
        has faces, the ones running u -> w first.
    """
    k = 0
    for i in range(corners_u.size):
        c = corners_u[i]
        w = indices[next_corner(c, corner_next)]
        if w > u:  # leaving u: u -> w
            key[k], halfedge[k] = 2 * w, c
            k += 1
        h = prev_corner(c, corner_prev)
        w = indices[h]
        if w > u:  # arriving at u: w -> u
            key[k], halfedge[k] = 2 * w + 1, h
            k += 1
    _sort_pairs(key, halfedge, k)
    return k


@jit
def _slice(count, t, parts):
    return count * t // parts, count * (t + 1) // parts


@jit_parallel
def _walk_edges(ring, width, parts, low_edges, table, shape, totals):
    """Every edge (u, w), w > u, once, at u from the halfedges around u (a slice of vertices per thread).

    What it records depends on which outputs are given (None: not asked for; numba compiles each
    combination on its own, without the branches it does not take):

    - ``low_edges`` (n,): how many edges are numbered at u (the first pass of :func:`edge_table`);
    - ``table = (edge_start (n + 1,), edges, halfedge_edge, face_count, edge_faces, edge_halfedges,
      forward_count)``: the edge table, edges numbered from ``edge_start[u]`` at u (its second pass;
      ``forward_count`` zeroed, the rest preset as :func:`edge_table` returns them where nothing is
      written);
    - ``totals`` (parts, 5): each thread's counts of :data:`EDGE_COUNTS`, the sharp edges among them
      where ``shape = (vector_area, area, degenerate, sharp_angle)`` (as in :func:`edge_counts`) is given.

    ``ring = (indptr, corners, indices, corner_next, corner_prev, corner_face)`` as in :func:`edge_table`;
    ``width`` the scratch length (:func:`_ring_width`).
    """
    indptr, corners, indices, corner_next, corner_prev, corner_face = ring
    if table is not None:
        edge_start, edges, halfedge_edge, face_count, edge_faces, edge_halfedges, forward_count = table
    if shape is not None:
        vector_area, area, degenerate, sharp_angle = shape
        within2 = _within_squared(sharp_angle)
    n = indptr.size - 1
    for t in prange(parts):
        key, halfedge = np.empty(width, np.int64), np.empty(width, np.int64)
        counted = np.zeros(len(EDGE_COUNTS), np.int64)
        lo, hi = _slice(n, t, parts)
        for u in range(lo, hi):
            k = _upper_halfedges(u, corners[indptr[u]:indptr[u + 1]], indices, corner_next, corner_prev, key,
                                 halfedge)
            count, start = 0, 0
            for i in range(1, k + 1):
                if i < k and key[i] >> 1 == key[start] >> 1:
                    continue
                # halfedges start .. i-1 are those of the edge (u, w), w > u: one per face
                faces = i - start
                if table is not None:  # row e of the edge table
                    e = edge_start[u] + count
                    edges[e, 0] = u
                    edges[e, 1] = key[start] >> 1
                    face_count[e] = faces
                    for j in range(start, i):
                        h = halfedge[j]
                        halfedge_edge[h] = e
                        if j - start < 2:
                            edge_faces[e, j - start] = _face_of(h, corner_face)
                            edge_halfedges[e, j - start] = h
                        forward_count[e] += 1 - (key[j] & 1)
                if totals is not None:  # the counts of EDGE_COUNTS
                    counted[0] += 1
                    if faces == 1:
                        counted[1] += 1
                    elif faces > 2:
                        counted[2] += 1
                    else:
                        if (key[start] & 1) == (key[start + 1] & 1):  # both run the same way
                            counted[3] += 1
                        f, g = _face_of(halfedge[start], corner_face), _face_of(halfedge[start + 1], corner_face)
                        if (shape is not None and not (degenerate[f] or degenerate[g])
                                and not _clearly_within(vector_area, f, g, within2)):
                            # the unit normals as Mesh.face_normals divides them, without that (m, 3) array
                            af, ag = area[f], area[g]
                            nf = (vector_area[f, 0] / af, vector_area[f, 1] / af, vector_area[f, 2] / af)
                            ng = (vector_area[g, 0] / ag, vector_area[g, 1] / ag, vector_area[g, 2] / ag)
                            if _angle_between(nf, ng) > sharp_angle:
                                counted[4] += 1
                count += 1
                start = i
            if low_edges is not None:
                low_edges[u] = count
        if totals is not None:
            totals[t] = counted


def _ring_width(indptr: np.ndarray) -> int:
    """Scratch length for the halfedges around the busiest vertex: two per corner."""
    return int(2 * np.diff(indptr).max(initial=0)) + 1


def edge_table(indptr: np.ndarray, corners: np.ndarray, indices: np.ndarray, corner_next: np.ndarray,
               corner_prev: np.ndarray, corner_face: np.ndarray):
    """The undirected edges of the halfedges ``indices[c] -> indices[corner_next[c]]``.

    Each edge (u, w), u < w, is numbered at u, from the halfedges around u (:func:`_upper_halfedges`).

    Parameters
    ----------
    indptr, corners : (n + 1,), (h,) int64
        Corners grouped by vertex (:func:`group_corners`).
    indices, corner_next, corner_prev, corner_face : (h,) int64
        :attr:`Mesh.face_indices`, :attr:`Mesh.corner_next`, :attr:`Mesh.corner_prev`,
        :attr:`Mesh.corner_face`.

    Returns
    -------
    edges : (e, 2) int64
        Sorted unique pairs, ``edges[:, 0] < edges[:, 1]``.
    halfedge_edge : (h,) int64
        Edge of each halfedge; -1 where both ends are the same vertex.
    face_count : (e,) int64
        Halfedges (faces) per edge.
    edge_faces : (e, 2) int64
        Faces of the first two halfedges of each edge, the halfedges running low -> high first
        (then in corner order); -1 where there is none.
    edge_halfedges : (e, 2) int64
        Those two halfedges; -1 where there is none.
    forward_count : (e,) int64
        Halfedges of each edge running from ``edges[:, 0]`` to ``edges[:, 1]``.
    """
    n = indptr.size - 1
    width, parts = _ring_width(indptr), threads()
    ring = (indptr, corners, indices, corner_next, corner_prev, corner_face)
    low_edges = np.empty(n, np.int64)
    launch(_walk_edges, ring, width, parts, low_edges, None, None, None)
    edge_start = np.zeros(n + 1, np.int64)
    np.cumsum(low_edges, out=edge_start[1:])
    ne = int(edge_start[-1])
    edges = np.empty((ne, 2), np.int64)
    halfedge_edge = np.full(indices.size, -1, np.int64)
    face_count = np.zeros(ne, np.int64)
    edge_faces = np.full((ne, 2), -1, np.int64)
    edge_halfedges = np.full((ne, 2), -1, np.int64)
    forward_count = np.zeros(ne, np.int64)
    table = (edge_start, edges, halfedge_edge, face_count, edge_faces, edge_halfedges, forward_count)
    launch(_walk_edges, ring, width, parts, None, table, None, None)
    return edges, halfedge_edge, face_count, edge_faces, edge_halfedges, forward_count


@jit
def vertex_incidence(edges, n):
    """The edges of each vertex, in increasing edge order (which is increasing neighbour order).

    Parameters
    ----------
    edges : (e, 2) int64
        Sorted unique edges (:func:`edge_table`).
    n : int

    Returns
    -------
    indptr : (n + 1,) int64
    neighbours : (2e,) int64
        The other endpoint of each incident edge, sorted within each vertex.
    edge_ids : (2e,) int64
        The incident edges themselves.
    """
    indptr = np.zeros(n + 1, np.int64)
    for e in range(edges.shape[0]):
        indptr[edges[e, 0] + 1] += 1
        indptr[edges[e, 1] + 1] += 1
    for v in range(n):
        indptr[v + 1] += indptr[v]
    fill = indptr[:-1].copy()
    neighbours = np.empty(2 * edges.shape[0], np.int64)
    edge_ids = np.empty(2 * edges.shape[0], np.int64)
    for e in range(edges.shape[0]):
        p, q = edges[e, 0], edges[e, 1]
        neighbours[fill[p]] = q
        edge_ids[fill[p]] = e
        fill[p] += 1
        neighbours[fill[q]] = p
        edge_ids[fill[q]] = e
        fill[q] += 1
    return indptr, neighbours, edge_ids


@jit
def vertex_face_incidence(indptr, corners, corner_face):
    """CSR of the faces at each vertex with the number of the vertex's corners in each.

    Parameters
    ----------
    indptr, corners : (n + 1,), (h,) int64
        Corners grouped by vertex, in increasing order (:func:`group_corners`).
    corner_face : (h,) int64

    Returns
    -------
    face_ptr : (n + 1,) int64
    faces : (k,) int64
        Increasing within each vertex.
    counts : (k,) int32
    """
    n = indptr.size - 1
    face_ptr = np.zeros(n + 1, np.int64)
    # a face's corners at v are consecutive (corners increase, and a face's corners are contiguous):
    # one entry per run, at most one per corner
    faces = np.empty(corners.size, np.int64)
    counts = np.zeros(corners.size, np.int32)
    k = -1
    for v in range(n):
        last = -1
        for i in range(indptr[v], indptr[v + 1]):
            f = corner_face[corners[i]]
            if f != last:
                k += 1
                last = f
                faces[k] = f
            counts[k] += 1
        face_ptr[v + 1] = k + 1
    return face_ptr, faces[:k + 1], counts[:k + 1]


@jit
def find_root(parent, i):
    """The root of ``i`` in a union-find forest ``parent`` (path halving: the path is shortened on the way)."""
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@jit
def next_corner(c, corner_next):
    """The next corner of corner c in its face: ``corner_next[c]``, or by arithmetic when ``corner_next`` is
    empty (a triangle mesh, :attr:`curv.Mesh.corner_steps`: face f has the corners 3f, 3f + 1, 3f + 2)."""
    if corner_next.size:
        return np.int64(corner_next[c])
    return c - 2 if c % 3 == 2 else c + 1


@jit
def prev_corner(c, corner_prev):
    """The previous corner of corner c in its face (as :func:`next_corner`)."""
    if corner_prev.size:
        return np.int64(corner_prev[c])
    return c + 2 if c % 3 == 0 else c - 1


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
def _sorted_fan(u, first, last, corners, indices, corner_next, corner_prev, x, other, corner, parent, spread):
    """Flags, distinct neighbours and longest edge of u from its halfedges sorted by other endpoint.

    The halfedges at u (leaving or arriving at each of its corners), sorted by other endpoint, are
    those of the edges (u, w), one per face. Any fan (a border, a non-manifold edge or vertex,
    faces of opposite orientation, a repeated index).

    Returns
    -------
    nonmanifold, border, inconsistent : bool
    distinct : int
        Number of neighbours, written sorted to ``spread[2 * first:]`` (unless ``spread`` is empty).
    far : float
        The longest edge (0 without one).
    """
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
    _sort_pairs(other, corner, k)
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
        if spread.size:
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
def _corner_pass(indptr, corners, indices, corner_next, corner_prev, x, width, parts, nonmanifold, border,
                 inconsistent, counts, spread, longest, normals):
    n = indptr.size - 1
    for t in prange(parts):
        other, corner, parent = np.empty(width, np.int64), np.empty(width, np.int64), np.empty(width, np.int64)
        lead, trail = np.empty(width, np.int64), np.empty(width, np.int64)
        lo, hi = _slice(n, t, parts)
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
                wx, wy, wz, lead2 = corner_terms(x, u, b, q)
                sx += wx
                sy += wy
                sz += wz
                far2 = lead2 if lead2 > far2 else far2
            normals[u, 0], normals[u, 1], normals[u, 2] = unit(sx, sy, sz)
            fans = _one_fan(u, d, lead, trail, parent)
            if fans > 0:
                # the usual vertex: its neighbours are the next vertices of its corners, each once; the
                # longest edge is the root of the longest square (sqrt is monotonic and correctly
                # rounded: the same value, to the bit, as the longest of the roots, _farther)
                _insertion_sort(lead, d)
                for i in range(d):
                    spread[2 * first + i] = lead[i]
                nonmanifold[u] = fans > 1
                border[u] = inconsistent[u] = False
                counts[u] = d
                longest[u] = math.sqrt(far2)
            else:
                (nonmanifold[u], border[u], inconsistent[u], counts[u],
                 longest[u]) = _sorted_fan(u, first, last, corners, indices, corner_next, corner_prev, x, other,
                                           corner, parent, spread)


@jit_parallel
def _fan_flags(indptr, corners, indices, corner_next, corner_prev, x, width, parts, nonmanifold, border,
               inconsistent):
    n = indptr.size - 1
    nothing = np.empty(0, np.int64)
    for t in prange(parts):
        other, corner, parent = np.empty(width, np.int64), np.empty(width, np.int64), np.empty(width, np.int64)
        lead, trail = np.empty(width, np.int64), np.empty(width, np.int64)
        lo, hi = _slice(n, t, parts)
        for u in range(lo, hi):
            first, last = indptr[u], indptr[u + 1]
            d = last - first
            for i in range(d):
                c = corners[first + i]
                lead[i], trail[i] = indices[next_corner(c, corner_next)], indices[prev_corner(c, corner_prev)]
            fans = _one_fan(u, d, lead, trail, parent)
            if fans > 0:
                nonmanifold[u] = fans > 1
                border[u] = inconsistent[u] = False
            else:
                nonmanifold[u], border[u], inconsistent[u], _, _ = _sorted_fan(
                    u, first, last, corners, indices, corner_next, corner_prev, x, other, corner, parent, nothing)


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
    launch(_fan_flags, indptr, corners, indices, corner_next, corner_prev, vertices, _ring_width(indptr),
           max(1, min(threads(), n)), nonmanifold, border, inconsistent)
    return nonmanifold, border, inconsistent


@jit
def _insertion_sort(a, k):
    """Sort ``a[:k]`` in place (k small)."""
    for i in range(1, k):
        v = a[i]
        j = i - 1
        while j >= 0 and a[j] > v:
            a[j + 1] = a[j]
            j -= 1
        a[j + 1] = v


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
    """(n, 3) float64, column-major: unit Max (1999) vertex normals (:func:`curv.geometry.normals.max_normal`); NaN rows where
    the corner terms cancel or there is no corner."""


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
    corner_next, corner_prev : (h,) int32 or int64, or both empty
        Next and previous corner in its face; empty on a triangle mesh (:func:`next_corner`).
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
    # column-major: the fit kernels read each coordinate as a contiguous column (curv.geometry.normals.cached_max_normals)
    longest, normals = np.empty(n), np.empty((n, 3), order="F")
    launch(_corner_pass, indptr, corners, indices, corner_next, corner_prev, vertices, _ring_width(indptr),
           max(1, min(threads(), n)), nonmanifold, border, inconsistent, counts, spread, longest, normals)
    out_ptr = np.zeros(n + 1, np.int64)
    np.cumsum(counts, out=out_ptr[1:])
    out = np.empty(out_ptr[-1], np.int64)
    launch(_gather_neighbours, indptr, spread, out_ptr, out)
    return CornerPass(nonmanifold, border, inconsistent, out_ptr, out, longest, normals)


@jit_parallel
def triangle_geometry(tri, vertices, vector_area, area, degenerate):
    """Per triangle (p0, p1, p2): Newell vector area ``(p1 - p0) x (p2 - p0) / 2``, its norm, and
    degeneracy (a repeated index, or area <= 1e-12 times the squared longest side).

    ``vector_area`` (m, 3) and ``area`` (m,) may be empty (not asked for: a 1-ring estimator reads
    only ``degenerate`` (m,), and writing 32 bytes per face it never reads cost it more than the test).
    """
    shape = area.size > 0
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
        if shape:
            vector_area[f, 0] = nx
            vector_area[f, 1] = ny
            vector_area[f, 2] = nz
            area[f] = a
        cx = vertices[k, 0] - vertices[j, 0]
        cy = vertices[k, 1] - vertices[j, 1]
        cz = vertices[k, 2] - vertices[j, 2]
        longest2 = max(ax * ax + ay * ay + az * az, cx * cx + cy * cy + cz * cz, bx * bx + by * by + bz * bz)
        degenerate[f] = i == j or j == k or i == k or a <= 1e-12 * longest2


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


@jit
def _angle_between(a, b):
    """Degrees between unit vectors a and b (3-tuples): ``atan2(|a x b|, a . b)``, accurate at small and
    large angles alike."""
    ax, ay, az = a
    bx, by, bz = b
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    return math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz) * (180.0 / math.pi)


SHARP_TEST_MARGIN = 1e-6
"""The quick test of :func:`_clearly_within` clears an edge only below ``(1 - this)`` of the squared
tangent of the sharp angle: far above the rounding of either computation of the angle."""


@jit
def _within_squared(sharp_angle):
    """The bound of :func:`_clearly_within` for ``sharp_angle`` degrees: ``tan^2`` of it less the margin,
    or -1 (no quick test) outside (0, 90) degrees, where the tangent does not grow with the angle."""
    if not 0.0 < sharp_angle < 90.0:
        return -1.0
    t = math.tan(sharp_angle * (math.pi / 180.0))
    return t * t * (1.0 - SHARP_TEST_MARGIN)


@jit
def _clearly_within(vector_area, f, g, within2):
    """Whether the normals of faces f and g (rows of ``vector_area``, not degenerate) are clearly less
    than the sharp angle apart, from ``|a x b|^2 < within2 (a . b)^2``: no division, root or ``atan2``
    for the many edges of a smooth surface; the others take :func:`_angle_between` (the same count)."""
    ax, ay, az = vector_area[f, 0], vector_area[f, 1], vector_area[f, 2]
    bx, by, bz = vector_area[g, 0], vector_area[g, 1], vector_area[g, 2]
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    dot = ax * bx + ay * by + az * bz
    return dot > 0.0 and cx * cx + cy * cy + cz * cz < within2 * dot * dot


@jit
def _face_of(c, corner_face):
    """The face of corner c: ``corner_face[c]``, or ``c // 3`` when ``corner_face`` is empty (a triangle mesh,
    as :func:`next_corner`)."""
    if corner_face.size:
        return np.int64(corner_face[c])
    return c // 3


@jit
def _dihedral(face_normals, f, g):
    """Degrees between the unit normals of faces f and g (rows of ``face_normals``)."""
    return _angle_between((face_normals[f, 0], face_normals[f, 1], face_normals[f, 2]),
                          (face_normals[g, 0], face_normals[g, 1], face_normals[g, 2]))


@jit_parallel
def dihedral_angles(edge_faces, face_count, face_normals, out):
    """``out[e]``: degrees between the unit normals of edge e's two faces; NaN unless it has exactly two.

    ``atan2(|n0 x n1|, n0 . n1)``: accurate at small and large angles alike. NaN normals (degenerate
    faces) give NaN.

    Parameters
    ----------
    edge_faces : (e, 2) int64
    face_count : (e,) int64
    face_normals : (m, 3) float64
    out : (e,) float64
    """
    for e in prange(edge_faces.shape[0]):
        f, g = edge_faces[e, 0], edge_faces[e, 1]
        if face_count[e] != 2 or f < 0 or g < 0:
            out[e] = math.nan
            continue
        out[e] = _dihedral(face_normals, f, g)


@jit_parallel
def corner_links(offsets, corner_next, corner_prev):
    """The next and previous corner of every corner within its face (faces are contiguous runs).

    Parameters
    ----------
    offsets : (m + 1,) int64
        Face f's corners are ``offsets[f] .. offsets[f + 1] - 1``.
    corner_next, corner_prev : (h,) int64
        Filled.
    """
    for f in prange(offsets.size - 1):
        first, last = offsets[f], offsets[f + 1] - 1
        for c in range(first, last + 1):
            corner_next[c] = first if c == last else c + 1
            corner_prev[c] = last if c == first else c - 1


@jit
def component_labels(indptr, neighbours, labels):
    """Connected components of a graph given as neighbour lists; returns their count.

    Union-find over the edges, then labels numbered in order of each component's lowest vertex (as
    :func:`scipy.sparse.csgraph.connected_components` numbers them).

    Parameters
    ----------
    indptr, neighbours : (n + 1,), (a,) int64
        Symmetric neighbour lists.
    labels : (n,) int64
        Filled with the component of each vertex, ``0 .. count - 1``.
    """
    n = indptr.size - 1
    parent = np.arange(n)
    for u in range(n):
        for i in range(indptr[u], indptr[u + 1]):
            a, b = find_root(parent, u), find_root(parent, neighbours[i])
            if a != b:
                parent[max(a, b)] = min(a, b)
    count = 0
    for u in range(n):
        r = find_root(parent, u)
        if r == u:  # the root is the lowest vertex of its component, so it comes first
            labels[u] = count
            count += 1
        else:
            labels[u] = labels[r]
    return count


EDGE_COUNTS = ("edges", "border", "nonmanifold", "inconsistent", "sharp")
"""The columns of :func:`edge_counts`."""


def edge_counts(indptr: np.ndarray, corners: np.ndarray, indices: np.ndarray, corner_next: np.ndarray,
                corner_prev: np.ndarray, corner_face: np.ndarray, vector_area: np.ndarray, area: np.ndarray,
                degenerate: np.ndarray, sharp_angle: float) -> dict[str, int]:
    """How many edges, border, non-manifold, inconsistent and sharp edges, without the edge table.

    The same counts as :func:`edge_table` and :func:`dihedral_angles` give (an edge (u, w) is seen
    at u < w, from the halfedges around u), for a mesh report that needs no per-edge array.

    Parameters
    ----------
    indptr, corners : (n + 1,), (h,) int64
        Corners grouped by vertex.
    indices : (h,) int64
    corner_next, corner_prev, corner_face : (h,) int32 or int64, or all three empty
        Empty on a triangle mesh: its corners and faces follow by arithmetic (:func:`next_corner`),
        so the report builds neither the corner links nor the corner-to-face array.
    vector_area, area, degenerate : (m, 3) float64, (m,) float64, (m,) bool
        :attr:`Mesh.face_vector_areas`, :attr:`Mesh.face_areas`, :attr:`Mesh.degenerate_faces`: the unit
        normal is their quotient, none at a degenerate face (as :attr:`Mesh.face_normals`).
    sharp_angle : float
        Edges with two faces whose dihedral angle is above this (degrees) are sharp.

    Returns
    -------
    dict
        ``{name: count}`` for the names of :data:`EDGE_COUNTS`.
    """
    parts = max(1, min(threads(), indptr.size - 1))
    totals = np.zeros((parts, len(EDGE_COUNTS)), np.int64)
    ring = (indptr, corners, indices, corner_next, corner_prev, corner_face)
    shape = (vector_area, area, degenerate, float(sharp_angle))
    launch(_walk_edges, ring, _ring_width(indptr), parts, None, None, shape, totals)
    return dict(zip(EDGE_COUNTS, (int(c) for c in totals.sum(axis=0))))


KERNELS = (_count_by_vertex, _first_slots, _place_by_vertex, _walk_edges, vertex_incidence, vertex_face_incidence, _corner_pass, _fan_flags,
           _gather_neighbours,
           triangle_geometry, duplicate_positions, dihedral_angles, corner_links, component_labels)
"""The numba dispatchers of this module (for :func:`curv.core.jit.compile_pending`)."""
