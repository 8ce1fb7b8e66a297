"""Sums of per-vertex shares over a ball: what the estimators that sum a mesh's elements in a ball share.

An estimator of this kind gives every vertex v a share of the elements around it (a half of each
edge, a third of each face: its *star* row), so that the sum of the star rows over a support holds
every element inside the (convex) ball whole; it then corrects the elements that cross the sphere
(:mod:`curv.estimators._ball_clipping`). This module holds the support's side of that: the set-up
(:func:`ball_inputs`: the supports' walk, the radii of every level, a small region's touched
elements), the flags a support collects and their reason code (:func:`support_reason`, in the one
precedence of :mod:`curv.core.validity`), and the addition of the star rows (:func:`add_star_rows`).
It names no estimator.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..core.jit import jit, jit_inlined
from ..core.mesh import Mesh
from ..core.validity import precedence
from ..geometry.neighbourhood import (all_centres, ball_support, blocked_vertices, coordinate_columns,
                                      expansion_adjacency)

__all__ = ["CLIPPING_PASS", "REGION_WALK_SHARE", "BORDER_BIT", "NONMANIFOLD_BIT", "DEGENERATE_BIT", "BallWalk",
           "ball_inputs", "support_reason", "support_bits", "add_star_rows", "add_row", "level_mark",
           "level_radii", "vertex_normal", "touches", "touched_elements"]

CLIPPING_PASS = "ball clipping"
"""The shared pass the estimators that sum over balls and clip at the sphere name
(:attr:`~curv.estimators.EstimatorSpec.shared_pass`), run by :mod:`curv.estimators.clipping_pair`."""

REGION_WALK_SHARE = 0.05
"""A region of fewer vertices than this share of the mesh walks its supports first, so that the
per-triangle and per-vertex terms are computed only where its supports read them. For a larger
region the walk (a second search per centre) costs more than the terms it saves, and the terms
are computed for the whole mesh (the same values). Measured at R4, one thread, a slab of a torus:
at 1M vertices the walk wins up to 3 % (the edge sums 0.20 s against 0.54 s at 1 %) and loses at 10 %
(1.85 s against 1.72 s); at 12k vertices it already loses at 10 % (0.022 s against 0.019 s)."""

BORDER_BIT, NONMANIFOLD_BIT, DEGENERATE_BIT = 1, 2, 4
"""Bits of what a support may hit: a border or non-manifold vertex (:func:`support_bits`), a degenerate triangle."""


class BallWalk(NamedTuple):
    """How the supports grow (:func:`~curv.geometry.neighbourhood.widen_ball_support`) and where they stop."""

    indptr: np.ndarray
    """(n + 1,) int64 and (a,) int64: :func:`~curv.geometry.neighbourhood.expansion_adjacency`
    through the vertices not blocked."""
    indices: np.ndarray
    cut: bool
    """Some vertices are blocked (``features``): the faces touching them are left out of the sums."""
    crease: np.ndarray
    """(n,) bool the blocked vertices (all False without ``features``)."""


@jit
def support_reason(singular, hit, normal_ok):
    """Reason code of an estimate over a ball, from what its support touched.

    ``hit`` holds the flags of the support's vertices (BORDER_BIT, NONMANIFOLD_BIT, DEGENERATE_BIT:
    a degenerate face touches it), in the one precedence (:func:`curv.core.validity.precedence`):
    NONMANIFOLD, then DEGENERATE (also for a missing normal), BORDER, SINGULAR, else OK.
    """
    return precedence(hit & NONMANIFOLD_BIT != 0, hit & DEGENERATE_BIT != 0 or not normal_ok,
                      hit & BORDER_BIT != 0, singular)


@jit_inlined
def support_bits(mesh, queue, lo, hi, hit):
    """``hit`` with the flags of the support rows ``queue[lo:hi]`` added (BORDER_BIT, NONMANIFOLD_BIT;
    ``mesh`` a :class:`~curv.estimators._ball_clipping.BallMesh`)."""
    for i in range(lo, hi):
        v = queue[i]
        if mesh.border[v]:
            hit |= BORDER_BIT
        if mesh.nonmanifold[v]:
            hit |= NONMANIFOLD_BIT
    return hit


@jit
def add_star_rows(queue, lo, hi, star, clean, exact, sums):
    """Add the star rows of the support rows ``queue[lo:hi]`` (the vertices a level added) to ``sums``.

    Parameters
    ----------
    queue : (>= hi,) int64
    lo, hi : int
    star : (n, K) float64
        Per-vertex shares of the elements around each vertex, exact for the elements inside the ball.
    clean : (n,) bool
        The vertex's star row is exact.
    exact : bool
        Every vertex of ``queue[:lo]`` is ``clean``.
    sums : (k,) float64, 7 <= k <= min(K, 9)
        The sum of ``star[v, :k]`` over ``queue[:lo]`` while ``exact``; added to in queue order,
        row by row (each row one cache line or two), every column in a register of its own.
        From the first vertex that is not clean it is no longer read (the caller walks face by face).

    Returns
    -------
    bool
        Every vertex of ``queue[:hi]`` is clean.
    """
    for i in range(lo, hi):
        if not clean[queue[i]]:
            exact = False
    if exact:
        k = sums.size
        s0, s1, s2, s3, s4, s5, s6 = sums[0], sums[1], sums[2], sums[3], sums[4], sums[5], sums[6]
        s7 = sums[7] if k > 7 else 0.0
        s8 = sums[8] if k > 8 else 0.0
        for i in range(lo, hi):
            v = queue[i]
            s0 += star[v, 0]
            s1 += star[v, 1]
            s2 += star[v, 2]
            s3 += star[v, 3]
            s4 += star[v, 4]
            s5 += star[v, 5]
            s6 += star[v, 6]
            if k > 7:
                s7 += star[v, 7]
                if k > 8:
                    s8 += star[v, 8]
        sums[0], sums[1], sums[2], sums[3], sums[4], sums[5], sums[6] = s0, s1, s2, s3, s4, s5, s6
        if k > 7:
            sums[7] = s7
        if k > 8:
            sums[8] = s8
    return exact


@jit
def add_row(sums, weight, rows, r):
    """``sums += weight * rows[r, :sums.size]``."""
    for c in range(sums.size):
        sums[c] += weight * rows[r, c]


@jit
def level_mark(p, level, levels):
    """The face (and edge) stamp of centre p's walk at ``level`` of ``levels`` radii: a new mark per
    level (``p + 1`` with one level)."""
    return p * levels + level + 1


def level_radii(radii: np.ndarray) -> np.ndarray:
    """``radii`` as (levels, n) float64, C-contiguous: a (n,) array is one level."""
    radii = np.asarray(radii, dtype=np.float64)
    return np.ascontiguousarray(radii[None] if radii.ndim == 1 else radii)


@jit
def vertex_normal(normals, p):
    """Row p of ``normals`` and whether it is finite: ``(nx, ny, nz, ok)``."""
    nx, ny, nz = normals[p, 0], normals[p, 1], normals[p, 2]
    return nx, ny, nz, math.isfinite(nx) and math.isfinite(ny) and math.isfinite(nz)


@jit
def touches(crease, tri, f):
    """Whether triangle f has a corner on a crease (``crease`` (n,) bool)."""
    return crease[tri[f, 0]] or crease[tri[f, 1]] or crease[tri[f, 2]]


# ---------------------------------------------------------------------------- a region's elements
@jit
def _grow(a, count):
    if count < a.size:
        return a
    b = np.empty(2 * a.size, a.dtype)
    b[:a.size] = a
    return b


@jit
def _touched(centres, radii, walk, coords, corners, halfedge_edge, search, seen):
    """The vertices, faces and (with ``halfedge_edge``, else None) edges the supports of ``centres``
    touch, each once (:func:`touched_elements`)."""
    indptr, indices = walk
    x, y, z = coords
    vc_ptr, vc = corners
    vstamp, queue = search
    vseen, fseen, eseen = seen
    vertices = np.empty(64, np.int64)
    faces = np.empty(64, np.int64)
    edges = np.empty(64, np.int64)
    nv = nf = ne = 0
    for p in centres:
        count, queue = ball_support(p, radii[p] ** 2, indptr, indices, x, y, z, vstamp, queue)
        for i in range(count):
            v = queue[i]
            if not vseen[v]:
                vseen[v] = True
                vertices = _grow(vertices, nv)
                vertices[nv] = v
                nv += 1
            for j in range(vc_ptr[v], vc_ptr[v + 1]):
                h = vc[j]
                f = h // 3
                if not fseen[f]:
                    fseen[f] = True
                    faces = _grow(faces, nf)
                    faces[nf] = f
                    nf += 1
                if halfedge_edge is None:
                    continue
                for g in (h, 3 * f + (h + 2) % 3):  # the edges out of and into v
                    e = halfedge_edge[g]
                    if e >= 0 and not eseen[e]:
                        eseen[e] = True
                        edges = _grow(edges, ne)
                        edges[ne] = e
                        ne += 1
    return vertices[:nv], faces[:nf], edges[:ne]


def touched_elements(mesh: Mesh, centres: np.ndarray, radii: np.ndarray, indptr: np.ndarray,
                     indices: np.ndarray, *, edges: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The vertices, triangles (and edges) the supports of ``centres`` touch: what a region's estimate reads.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    centres : (c,) int64
        The vertices to estimate.
    radii : (n,) float64
        Ball radius of every vertex.
    indptr, indices : (n+1,), (a,) int64
        :func:`curv.geometry.neighbourhood.expansion_adjacency`.
    edges : bool
        Collect the edges too (they need the mesh's edge table).

    Returns
    -------
    vertices : (j,) int64
        Every vertex of a support, once.
    faces : (k,) int64
        Every triangle with a corner in a support, once.
    edges : (l,) int64 or None
        Every edge of those corners, once (None unless asked).

    Notes
    -----
    A sequential walk over the supports: its cost follows the region, and the seen-masks are
    zeroed pages that only the region touches.
    """
    n = mesh.n_vertices
    halfedge = mesh.halfedge_edge if edges else None
    seen = (np.zeros(n, np.bool_), np.zeros(mesh.n_faces, np.bool_), np.zeros(mesh.edges.shape[0] if edges else 0,
                                                                                np.bool_))
    vertices, faces, edge_ids = _touched(centres, radii, (indptr, indices), coordinate_columns(mesh),
                                         mesh.vertex_corners, halfedge, (np.zeros(n, np.int64), np.empty(n, np.int64)),
                                         seen)
    return vertices, faces, (edge_ids if edges else None)


def ball_inputs(mesh: Mesh, centres: np.ndarray | None, radii: np.ndarray, features):
    """What an estimate summing over balls reads before its per-vertex sums, a generator: it yields 0.0
    after each piece of connectivity the mesh builds (one per step, so that cancel stays prompt).

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh (:class:`~curv.core.errors.MeshError` on polygons).
    centres : (c,) int64 or None
        The vertices to estimate (None: all).
    radii : (n,) or (levels, n) float64
        Ball radius of every vertex, or of every vertex at each level (ascending per vertex).
    features : curv.core.features.FeatureSet or None
        The supports stop at its vertices.

    Returns
    -------
    centres : (c,) int64
    radii : (levels, n) float64
        Contiguous (:func:`level_radii`).
    walk : BallWalk
    touched : tuple
        For a region of fewer than :data:`REGION_WALK_SHARE` of the vertices, :func:`touched_elements`
        without the edges; else ``(None, None, None)`` (every triangle's and vertex's terms).
    """
    mesh.triangles  # the MeshError that names the polygon sizes
    n = mesh.n_vertices
    region = centres is not None
    centres = all_centres(n, centres)
    for name in ("degenerate_faces", "face_vector_areas", "adjacency", "vertex_corners", "border_vertices",
                 "nonmanifold_vertices"):
        getattr(mesh, name)
        yield 0.0
    blocked = blocked_vertices(features)
    indptr, indices = expansion_adjacency(mesh, blocked)
    walk = BallWalk(indptr, indices, blocked is not None, np.zeros(n, np.bool_) if blocked is None else blocked)
    radii = level_radii(radii)
    small = region and centres.size < REGION_WALK_SHARE * n
    # the widest level's supports hold every narrower one's
    touched = touched_elements(mesh, centres, radii[-1], indptr, indices, edges=False) if small else (None, None, None)
    return centres, radii, walk, touched
