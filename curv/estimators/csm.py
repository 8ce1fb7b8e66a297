"""Cohen-Steiner & Morvan (2003): the normal-cycle curvature tensor averaged over a ball (R1-R4).

For vertex p and the ball B of radius ``r(p)`` around it (``k * mesh.longest_edge[p]`` at range
Rk, or a fixed radius: :func:`curv.core.ranges.ball_radii`)::

    T(p) = 1 / area(B ∩ mesh) * sum_e beta(e) |e ∩ B| ê êᵀ

with ``beta(e)`` the signed dihedral angle of edge e (positive on convex edges for outward normals),
``|e ∩ B|`` the exact length of the edge inside the ball and ê its unit direction. The eigenvector
of T closest to the vertex normal is dropped; the other two eigenvalues are the principal
curvatures, each with the *other* eigenvector as its direction (the edge tensor of a cylinder has
its eigenvalue 1/r along the axis, the direction of zero curvature).

What is approximated
--------------------
The edges and faces considered are those touching p or a vertex of its support
(:func:`curv.geometry.neighbourhood.ball_support`: vertices reachable from p along edges without leaving
B). Edges and faces whose vertices all lie outside that support are ignored even when they graze B
(e.g. a long edge passing through the rim of the ball, or a part of the surface that re-enters the
ball without a path inside it). Everything else is exact: ``|e ∩ B|`` is the segment/sphere
intersection and ``area(B ∩ face)`` the exact area of the triangle within the disc
``B ∩ plane of the face`` (circular sectors plus triangles, per edge).

How it runs
-----------
One parallel kernel per chunk of vertices (:func:`curv.core.jit.iter_chunks`), the one icc runs too
(:mod:`curv.estimators._clipped_sums`: run together, :mod:`curv.estimators.clipping_pair`, the two
share the search and the clips below); per vertex it searches the support. What neighbouring centres share is computed once per call (:func:`star_terms`): for
every vertex v, half of ``beta(e) |e| ê êᵀ`` summed over its edges and a third of the area of its
faces. Summed over a support, these hold every edge and face inside the (convex) ball whole, each
edge twice by halves and each face thrice by thirds; the only elements left to correct are those
that cross the sphere. They are found as the halfedges v -> w leaving the ball (v in the support,
w outside): each crossing edge once, and each crossing face (v, w, u) once, its one halfedge that
goes from inside to outside (each vertex's ring read once, :func:`curv.estimators._ball_clipping.corner_rings`:
a neighbour's offset, distance and exit serve both faces at its edge). The edge's half is replaced by its
exact part ``|e ∩ B|``
(:func:`curv.estimators._ball_clipping.exit_fraction`) and the face's thirds by its exact area
in the ball (:func:`curv.estimators._ball_clipping.crossing_area`, which reuses the edge's exit).
Support vertices whose every edge stays inside the ball (``|v - p| + longest edge <= r``) are not
walked at all. A support holding a vertex whose terms are not exact (a non-manifold or
inconsistently oriented edge, a degenerate face; with ``features``, a face touching a crease) is
summed the long way, face by face and edge by edge over the mesh's edge table, which is only built then
(:func:`edge_beta_scale`). With ``centres`` (a region of less than 5 % of the mesh,
:data:`~curv.estimators._ball_clipping.REGION_WALK_SHARE`), the star terms are computed only for the
vertices the region's supports hold, so the cost follows the region.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit, jit_parallel, launch, prange, threads
from ..core.mesh import Mesh
from ..geometry.neighbourhood import coordinate_columns
from ._ball_clipping import (_corner_rings, clipping_inputs, corner_rings, corner_width, element_list, touched_elements,
                             touches)
from ._clipped_sums import CLIPPING_PASS, CsmTerms, _clip_chunk, run_clipping, segment_in_ball
from .registry import EstimatorSpec, register

__all__ = ["iter_csm", "csm_terms", "segment_in_ball", "edge_beta_scale", "star_terms"]


# ---------------------------------------------------------------------------- per-mesh arrays
@jit
def _dihedral_scale(f0, f1, dx, dy, dz, length, vector_area, area):
    """``beta / |e|`` of the edge d = (dx, dy, dz) of length ``length`` between faces f0 and f1, with
    beta the signed angle from f0's normal to f1's about d (f0: the face where the edge runs along d)."""
    n0x, n0y, n0z = vector_area[f0, 0] / area[f0], vector_area[f0, 1] / area[f0], vector_area[f0, 2] / area[f0]
    n1x, n1y, n1z = vector_area[f1, 0] / area[f1], vector_area[f1, 1] / area[f1], vector_area[f1, 2] / area[f1]
    sx = n0y * n1z - n0z * n1y
    sy = n0z * n1x - n0x * n1z
    sz = n0x * n1y - n0y * n1x
    beta = math.atan2((sx * dx + sy * dy + sz * dz) / length, n0x * n1x + n0y * n1y + n0z * n1z)
    return beta / length


@jit_parallel
def _edge_beta_scale(ids, edges, edge_faces, face_count, x, y, z, vector_area, area, degenerate, out):
    for i in prange(ids.size):
        e = ids[i]
        out[e] = 0.0
        f0, f1 = edge_faces[e, 0], edge_faces[e, 1]
        if face_count[e] != 2 or f1 < 0:
            continue
        if degenerate[f0] or degenerate[f1]:
            continue  # next to a degenerate face: its vertices are invalid anyway
        a, b = edges[e, 0], edges[e, 1]
        dx, dy, dz = x[b] - x[a], y[b] - y[a], z[b] - z[a]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not length > 0.0:
            continue
        # slot 0: the face where the edge runs a -> b; beta |e| ê êᵀ = beta / |e| d dᵀ
        scale = _dihedral_scale(f0, f1, dx, dy, dz, length, vector_area, area)
        if math.isfinite(scale):
            out[e] = scale


def edge_beta_scale(mesh: Mesh, ids: np.ndarray | None = None) -> np.ndarray:
    """(e,) ``beta(e) / |e|`` per edge, so that ``beta |e| ê êᵀ = scale * d dᵀ`` with d the edge vector.

    Zero for edges without exactly two faces or next to a degenerate face (their vertices are
    invalid anyway). ``ids`` (k,) int64: compute only these edges (a region's); the other entries
    are left unset.
    """
    count = mesh.edges.shape[0]
    out = np.empty(count)
    x, y, z = coordinate_columns(mesh)
    launch(_edge_beta_scale, element_list(count, ids), mesh.edges, mesh.edge_faces, mesh.edge_face_count, x, y, z,
           mesh.face_vector_areas, mesh.face_areas, mesh.degenerate_faces, out)
    return out


# ---------------------------------------------------------------------------- the star terms
STAR = 8
"""Columns of the per-vertex star terms: half of each edge's ``beta |e| ê êᵀ`` (xx, xy, xz, yy, yz, zz), a third
of each face's area, and a pad to one cache line."""


@jit_parallel
def _star_terms(ids, parts, width, vc_ptr, vc, tri, x, y, z, vector_area, area, degenerate, nonmanifold, inconsistent,
                crease, half_scale, star, clean):
    for t in prange(parts):
        previous = np.empty(width, np.int64)  # the vertex before v in each face at v
        for i in range((t * ids.size) // parts, ((t + 1) * ids.size) // parts):
            v = ids[i]
            ok = not (nonmanifold[v] or inconsistent[v])
            t00 = t01 = t02 = t11 = t12 = t22 = 0.0
            third = 0.0
            first, last = vc_ptr[v], vc_ptr[v + 1]
            for j in range(first, last):
                h = vc[j]
                f = h // 3
                c = h - 3 * f
                previous[j - first] = tri[f, c - 1 if c > 0 else 2]
            for j in range(first, last):
                h = vc[j]
                f = h // 3
                c = h - 3 * f
                half_scale[h] = 0.0
                if degenerate[f]:
                    ok = False
                    continue
                if touches(crease, tri, f):
                    ok = False  # the feature path leaves this face out and halves its edges' terms
                third += area[f] / 3.0
                w = tri[f, c + 1 if c < 2 else 0]
                # the face across v -> w: the face at v where w precedes v (one at most on a clean vertex)
                g = -1
                for k in range(last - first):
                    if previous[k] == w:
                        g = vc[first + k] // 3
                if g < 0:
                    continue  # a border edge: no dihedral term
                # beta / |e| as _edge_beta_scale has it (its two orientations give the same bits)
                dx, dy, dz = x[w] - x[v], y[w] - y[v], z[w] - z[v]
                length = math.sqrt(dx * dx + dy * dy + dz * dz)
                if not length > 0.0:
                    continue
                scale = _dihedral_scale(f, g, dx, dy, dz, length, vector_area, area)
                if not math.isfinite(scale):
                    continue
                half_scale[h] = scale
                wt = 0.5 * scale
                wx, wy = wt * dx, wt * dy
                t00 += wx * dx
                t01 += wx * dy
                t02 += wx * dz
                t11 += wy * dy
                t12 += wy * dz
                t22 += wt * dz * dz
            star[v, 0], star[v, 1], star[v, 2] = t00, t01, t02
            star[v, 3], star[v, 4], star[v, 5] = t11, t12, t22
            star[v, 6] = third
            clean[v] = ok


def star_terms(mesh: Mesh, ids: np.ndarray | None = None, crease: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What every centre whose support holds vertex v shares: v's half of its edges and third of its faces.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    ids : (k,) int64, optional
        Compute only these vertices (a region's supports); the other rows are left unset.
    crease : (n,) bool, optional
        Crease vertices (``features``): a vertex with a face touching one is not clean.

    Returns
    -------
    half_scale : (3 m,) float64
        ``beta(e) / |e|`` of the edge of each halfedge (corner h to the next corner of its face), as
        :func:`edge_beta_scale` has it; 0 on a border edge.
    star : (n, 8) float64
        Half of ``beta(e) |e| ê êᵀ`` summed over the edges out of v (upper triangle, xx xy xz yy yz
        zz), then a third of the area of each face at v (column 7 is padding).
    clean : (n,) bool
        v's terms are exact for the sums: no non-manifold or inconsistent edge at v and no
        degenerate face (then the edges out of v are all its edges, each once), and no face at v
        touching a crease vertex.

    Notes
    -----
    The face across a halfedge v -> w is found among v's own corners (the one where w precedes v),
    so no edge table is built; on a clean vertex there is exactly one, or none on a border edge.
    """
    tri = np.ascontiguousarray(mesh.triangles)
    n = mesh.n_vertices
    vc_ptr, vc = mesh.vertex_corners
    half_scale = np.empty(3 * tri.shape[0])
    star = np.empty((n, STAR))
    clean = np.empty(n, np.bool_)
    crease = np.zeros(n, np.bool_) if crease is None else crease
    x, y, z = coordinate_columns(mesh)
    ids = element_list(n, ids)
    width = corner_width(mesh)  # corners at a vertex, at most
    parts = max(1, min(8 * threads(), ids.size))  # slices of vertices, each with its own scratch
    launch(_star_terms, ids, parts, width, vc_ptr, vc, tri, x, y, z, mesh.face_vector_areas, mesh.face_areas,
           mesh.degenerate_faces, mesh.nonmanifold_vertices, mesh.inconsistent_vertices, crease, half_scale, star,
           clean)
    return half_scale, star, clean


def iter_csm(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
             centres: np.ndarray | None = None, features=None):
    """Normal-cycle tensor over the ball of radius ``radii[p]`` around every vertex p.

    Parameters
    ----------
    mesh : Mesh
        Closed, consistently oriented triangle mesh (vertices whose support reaches a border,
        a non-manifold vertex or a degenerate face are marked invalid).
    normals : (n, 3) float64
        Unit vertex normals; they only pick which eigenvector of T is the normal.
    radii : (n,) or (levels, n) float64
        Ball radius of every vertex (:func:`curv.core.ranges.ball_radii` with ``uses_normals=False``),
        or of every vertex at each of several levels, ascending per vertex (several ranges in one
        call, :func:`curv.estimate_ranges`): one walk per centre serves them all
        (:func:`~curv.geometry.neighbourhood.widen_ball_support`; each level's support is exactly the
        single search's), the star sums of a level are the last one's plus the vertices it added,
        and only the crossing faces are clipped per level. The sums are added in another order than
        a call with that radius alone: the results agree to rounding.
    chunk : int, optional
        Vertices per kernel call; default adaptive (:func:`curv.core.jit.iter_chunks`).
    centres : (c,) int64, optional
        The vertices to estimate (default all). The per-edge dihedral angles are then computed
        only for the edges their supports touch.
    features : curv.core.features.FeatureSet, optional
        The ball stops at creases, and the faces touching a crease vertex are left out (as icc and
        ru do). Each face carries half of the dihedral term of each of its edges (an edge's dual
        strip lies half in each face), so an edge next to a left-out face keeps half of its term
        and an edge between two left-out faces none: the curvature summed and the area divided by
        cover the same part of the surface. (Taking the faces touching the crease and leaving out
        the feature edges' terms instead lost the dome's curvature across the rim of a hemisphere
        on a disc while keeping the area: mean ring-1 error 0.134 / 0.114 at 1,500 / 4,000
        vertices against the interior's 0.052; now 0.069 / 0.088. On the capped cylinder's side
        0.100 before, 0.049 now, the interior's 0.048: tests/test_crease_accuracy.py.)

    Yields
    ------
    float
        Fraction done (the points where a caller may cancel).

    Returns
    -------
    Principal, or a list of one per level
        ``k1 <= k2`` as the tensor gives them; ``reason`` BORDER, DEGENERATE, NONMANIFOLD or
        SINGULAR where the estimate is not usable.
    """
    levels = np.ndim(radii) == 2
    tri, centres, x, y, z, indptr, indices, cut, crease, radii, touched = yield from clipping_inputs(
        mesh, centres, radii, features)
    terms = yield from csm_terms(mesh, centres, radii, indptr, indices, touched[0], crease)
    after, link = corner_rings(mesh, touched[0])
    normals = np.asarray(normals, dtype=np.float64)  # the cached normals are column-major: read as they are
    out, _ = yield from run_clipping(mesh, centres, radii, (tri, x, y, z, indptr, indices, cut, crease, after, link),
                                     normals, csm=terms, chunk=chunk)
    if levels:
        return [out.principal(level) for level in range(radii.shape[0])]
    return out.principal(0)


def csm_terms(mesh: Mesh, centres: np.ndarray, radii: np.ndarray, indptr: np.ndarray, indices: np.ndarray,
              touched: np.ndarray | None, crease: np.ndarray):
    """csm's per-mesh terms for the supports of ``centres``, a generator (yields 0.0 after each pass).

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    centres : (c,) int64
    radii : (levels, n) float64
    indptr, indices, crease :
        :func:`~curv.estimators._ball_clipping.clipping_inputs`.
    touched : (k,) int64 or None
        The vertices a region's supports hold (None: every vertex).

    Returns
    -------
    CsmTerms
        :func:`star_terms`, and the edge table only where a support is not clean (or near a crease):
        those supports are summed edge by edge.
    """
    half_scale, star, clean = star_terms(mesh, touched, crease)
    yield 0.0
    walk = not (clean.all() if touched is None else clean[touched].all())
    if walk:
        edge_ids = None if touched is None else touched_elements(mesh, centres, radii[-1], indptr, indices,
                                                                 edges=True)[2]
        beta_scale = edge_beta_scale(mesh, edge_ids)
        halfedge_edge, edge_faces = mesh.halfedge_edge, mesh.edge_faces
        yield 0.0
    else:
        beta_scale, halfedge_edge, edge_faces = np.empty(0), np.empty(0, np.int64), np.empty((0, 2), np.int64)
    return CsmTerms(half_scale, star, clean, walk, halfedge_edge, beta_scale, edge_faces)


register(EstimatorSpec(
    name="csm", title="Cohen-Steiner & Morvan normal cycle", ranges=(1, 2, 3, 4), function=iter_csm,
    # `curv estimate torus10M.ply -m csm -r 2`: 7.02 GB peak, 334 B a unit above the base and stamps; +35 % as mru
    extra_bytes_per_unit=100.0,
    triangles_only=True, uses_normals=False, closed_ring=True,
    reference="Cohen-Steiner & Morvan 2003, Restricted Delaunay triangulations and normal cycle",
    summary="signed dihedral angle x clipped edge length x ê êᵀ summed in a ball, over the area in it",
    kernels=(_star_terms, _corner_rings, _edge_beta_scale, _clip_chunk), takes_levels=True,
    shared_pass=CLIPPING_PASS,
))
