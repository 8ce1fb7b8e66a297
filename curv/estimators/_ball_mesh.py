"""A triangle mesh as the ball estimators read it, and its faces that cross a ball's sphere.

An estimate summing over the ball around a centre holds the elements inside the ball whole and
clips those that cross its sphere (:mod:`curv.estimators._ball_clipping`). They are found from the
support's side: each face that crosses the sphere from inside has exactly one halfedge v -> w
from a corner inside (v in the support) to one outside, and :func:`crossing_faces` lists those of
one support vertex, reading its ring once (:func:`corner_rings`: a neighbour's offset, distance and
exit serve both faces at its edge). :func:`may_leave` skips the vertices whose every edge stays
inside. The mesh travels as one flat :class:`BallMesh`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..core.jit import jit, jit_inlined, jit_parallel, launch, prange
from ..core.mesh import Mesh
from ..geometry.neighbourhood import cached_with_mesh, coordinate_columns
from ._ball_clipping import crossing_area, dot3, exit_fraction, offset

__all__ = ["BallMesh", "ball_mesh", "corner_rings", "corner_width", "element_list", "new_crossings", "may_leave",
           "crossing_faces", "KERNELS"]


class BallMesh(NamedTuple):
    """A triangle mesh as the ball estimators read it (:func:`ball_mesh`)."""

    x: np.ndarray
    """(n,) float64 vertex coordinates, one column each (:func:`~curv.geometry.neighbourhood.coordinate_columns`)."""
    y: np.ndarray
    z: np.ndarray
    tri: np.ndarray
    """(m, 3) int64 triangles, counter-clockwise."""
    vector_area: np.ndarray
    """(m, 3) float64 :attr:`curv.Mesh.face_vector_areas`."""
    area: np.ndarray
    """(m,) float64 :attr:`curv.Mesh.face_areas`."""
    degenerate: np.ndarray
    """(m,) bool :attr:`curv.Mesh.degenerate_faces`."""
    vc_ptr: np.ndarray
    """(n + 1,) int64 and (3 m,) int64: :attr:`curv.Mesh.vertex_corners`."""
    vc: np.ndarray
    after: np.ndarray
    """(3 m,) int: :func:`corner_rings`, the far end of each corner's outgoing edge."""
    link: np.ndarray
    """(3 m,) int32: :func:`corner_rings`, the slot of the face's other edge at the same vertex."""
    longest: np.ndarray
    """(n,) float64 :attr:`curv.Mesh.longest_edge`."""
    border: np.ndarray
    """(n,) bool :attr:`curv.Mesh.border_vertices`."""
    nonmanifold: np.ndarray
    """(n,) bool :attr:`curv.Mesh.nonmanifold_vertices`."""


def ball_mesh(mesh: Mesh, ids: np.ndarray | None = None) -> BallMesh:
    """``mesh`` as the ball estimators read it, its corner rings filled at ``ids`` (default every vertex)."""
    after, link = corner_rings(mesh, ids)
    return BallMesh(*coordinate_columns(mesh), np.ascontiguousarray(mesh.triangles), mesh.face_vector_areas,
                    mesh.face_areas, mesh.degenerate_faces, *mesh.vertex_corners, after, link, mesh.longest_edge,
                    mesh.border_vertices, mesh.nonmanifold_vertices)


@jit_parallel
def _corner_rings(ids, vc_ptr, vc, tri, after, link):
    for i in prange(ids.size):
        v = ids[i]
        first, last = vc_ptr[v], vc_ptr[v + 1]
        for j in range(first, last):
            h = vc[j]
            f = h // 3
            c = h - 3 * f
            after[j] = tri[f, c + 1 if c < 2 else 0]
        for j in range(first, last):
            h = vc[j]
            f = h // 3
            c = h - 3 * f
            u = tri[f, c - 1 if c > 0 else 2]
            m = -1
            for k in range(first, last):
                if after[k] == u:
                    m = k - first
                    break
            link[j] = m


def corner_rings(mesh: Mesh, ids: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The far end of each corner's outgoing edge and the corner that shares its face's other edge.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    ids : (k,) int64, optional
        Fill only the corners of these vertices (a region's supports); the other entries are unset.

    Returns
    -------
    after : (3 m,) int32 (int64 beyond 2**31 vertices)
        Aligned with ``mesh.vertex_corners[1]``: for corner slot j of vertex v (halfedge v -> w of
        face f), w.
    link : (3 m,) int32
        For the same slot, the slot (counted from v's first) whose ``after`` is u, the third corner
        of f (so the face's edge v -> u is that slot's edge); -1 where there is none (the edge v -> u
        is a border edge). The first such slot where several are (a non-manifold vertex).

    Notes
    -----
    With them :func:`crossing_faces` reads a vertex's ring once: each neighbour's offset from the
    centre, its squared distance and its exit are computed once and shared by the two faces at the
    edge, without looking up the triangles.
    """
    vc_ptr, vc = mesh.vertex_corners
    kind = np.int32 if mesh.n_vertices < 2**31 else np.int64
    after = np.empty(vc.size, kind)
    link = np.empty(vc.size, np.int32)
    launch(_corner_rings, element_list(mesh.n_vertices, ids), vc_ptr, vc, np.ascontiguousarray(mesh.triangles), after,
           link)
    return after, link


def element_list(count: int, touched: np.ndarray | None) -> np.ndarray:
    """(k,) int64 the elements a per-face or per-edge pass must compute: ``touched``, or all ``count``."""
    return np.arange(count, dtype=np.int64) if touched is None else touched


def corner_width(mesh: Mesh) -> int:
    """The most corners at one vertex (at least 1): the length of a kernel's per-thread row for a
    vertex's corners. Cached with the mesh, so a region's estimate does no O(n) work for it."""
    def build():
        indptr = mesh.vertex_corners[0]
        return max(1, int(np.diff(indptr).max(initial=0)))

    return cached_with_mesh(mesh, "corner width", build)


@jit
def new_crossings(width):
    """Per-thread scratch of :func:`crossing_faces` for vertices of at most ``width`` corners:
    ``(out_h, out_w, out_t, out_area, out_in, ring)``, ``ring`` (5, width) float64."""
    return (np.empty(width, np.int64), np.empty(width, np.int64), np.empty(width), np.empty(width),
            np.empty(width, np.int64), np.empty((5, width)))


@jit_inlined
def may_leave(mesh, v, centre, radius):
    """Whether an edge at vertex v may leave the ball of ``centre`` and ``radius``: not when
    ``|v - p| + longest[v] <= radius`` (less rounding). A test cheap enough to run at every
    support vertex before the call of :func:`crossing_faces`."""
    vx, vy, vz = offset(mesh, v, centre)
    reach = radius * (1.0 - 1e-12) - mesh.longest[v]
    return not (reach > 0.0 and vx * vx + vy * vy + vz * vz <= reach * reach)


@jit_inlined
def crossing_faces(mesh, v, centre, radius, crossings):
    """The faces that cross the sphere along a halfedge leaving it from support vertex v, each found
    once (its one halfedge from inside to outside), with what a sum of per-vertex shares must trade
    for them.

    Parameters
    ----------
    mesh : BallMesh
    v : int
        A vertex inside the ball of ``centre`` (3-tuple) and ``radius`` whose edges may leave it
        (:func:`may_leave`).
    crossings : tuple
        :func:`new_crossings`: ``(out_h, out_w, out_t, out_area, out_in, ring)``. Entry a of the
        result: the halfedge ``out_h[a]`` (face ``out_h[a] // 3``) leaving towards ``out_w[a]`` at
        the fraction ``out_t[a]`` (:func:`exit_fraction`), the face's exact area inside the ball
        ``out_area[a]`` (:func:`crossing_area`) and how many of its corners are inside,
        ``out_in[a]`` (1 or 2: the thirds of it a sum of per-vertex thirds holds). ``ring`` holds
        v's neighbours' offsets, squared distances and exits.

    Returns
    -------
    int
        How many faces.

    Notes
    -----
    v's ring is read once: each neighbour w's offset, squared distance and (outside) exit along
    v -> w. A face (v, w, u) leaving along v -> w finds u's in the slot ``link`` names; only where
    v -> u is a border edge are they computed from u itself.
    """
    out_h, out_w, out_t, out_area, out_in, ring = crossings
    radius2 = radius ** 2
    a = offset(mesh, v, centre)
    qv = dot3(a, a)
    first = mesh.vc_ptr[v]
    corners = mesh.vc_ptr[v + 1] - first
    for s in range(corners):
        b = offset(mesh, mesh.after[first + s], centre)
        qw = dot3(b, b)
        ring[0, s], ring[1, s], ring[2, s], ring[3, s] = b[0], b[1], b[2], qw
        if qw > radius2:
            ring[4, s] = exit_fraction(a, qv, b, radius2)
    leaving = 0
    for s in range(corners):
        qw = ring[3, s]
        if not qw > radius2:
            continue
        j = first + s
        h = mesh.vc[j]
        f = h // 3
        b, tp = (ring[0, s], ring[1, s], ring[2, s]), ring[4, s]
        m = mesh.link[j]
        if m >= 0:
            c, qu = (ring[0, m], ring[1, m], ring[2, m]), ring[3, m]
            tu = ring[4, m] if qu > radius2 else 0.0
        else:  # v -> u is a border edge: no slot of v has u
            k = h - 3 * f
            c = offset(mesh, mesh.tri[f, k - 1 if k > 0 else 2], centre)
            qu = dot3(c, c)
            tu = exit_fraction(a, qv, c, radius2) if qu > radius2 else 0.0
        out_h[leaving] = h
        out_w[leaving] = mesh.after[j]
        out_t[leaving] = tp
        face = ((mesh.vector_area[f, 0], mesh.vector_area[f, 1], mesh.vector_area[f, 2]), mesh.area[f])
        out_area[leaving] = crossing_area(face, (a, qv), (b, qw), (c, qu), tp, tu, radius2)
        out_in[leaving] = 2 if qu <= radius2 else 1
        leaving += 1
    return leaving


KERNELS = (_corner_rings,)
"""The parallel kernels of this module (:attr:`~curv.estimators.EstimatorSpec.kernels`)."""
