"""The edges of a mesh from its corners: the edge table, the incidences, dihedral angles and the report's counts.

Every table is built in linear time (plus tiny sorts of the few halfedges that share a low vertex),
without hashing or sorting global keys: :func:`edge_table` lists the halfedges around each vertex u
(from its corners), sorts that small list by the other endpoint w and numbers the distinct w > u,
so edges come out in lexicographic order; :func:`vertex_incidence` lists, per vertex, its edges in
increasing edge order, which is also increasing neighbour order (all edges ``(q, p)`` with
``q < p`` precede the edges ``(p, r)``). :func:`edge_counts` counts what the report needs with the
same walk, without the table.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import jit, jit_parallel, launch, prange, threads
from .corners import face_of, find_root, next_corner, prev_corner, ring_width, sort_pairs, thread_slice

__all__ = ["edge_table", "vertex_incidence", "vertex_face_incidence", "dihedral_angles", "component_labels",
           "edge_counts", "EDGE_COUNTS", "KERNELS"]

EDGE_COUNTS = ("edges", "border", "nonmanifold", "inconsistent", "sharp")
"""The columns of :func:`edge_counts`."""


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
    sort_pairs(key, halfedge, k)
    return k


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
        lo, hi = thread_slice(n, t, parts)
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
                            edge_faces[e, j - start] = face_of(h, corner_face)
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
                        f, g = face_of(halfedge[start], corner_face), face_of(halfedge[start + 1], corner_face)
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
    width, parts = ring_width(indptr), threads()
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
    corner_next, corner_prev, corner_face : (h,) int32 or int64, or all three None
        None on a triangle mesh: its corners and faces follow by arithmetic
        (:func:`~curv.core.connectivity.corners.next_corner`), so the report builds neither the
        corner links nor the corner-to-face array.
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
    launch(_walk_edges, ring, ring_width(indptr), parts, None, None, shape, totals)
    return dict(zip(EDGE_COUNTS, (int(c) for c in totals.sum(axis=0))))


KERNELS = (_walk_edges, vertex_incidence, vertex_face_incidence, dihedral_angles, component_labels)
"""The numba dispatchers of this module (for :func:`curv.core.jit.compile_pending`)."""
