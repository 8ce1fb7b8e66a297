"""Cohen-Steiner & Morvan (2003): the normal-cycle curvature tensor averaged over a ball (R1-R4).

For vertex p and the ball B of radius ``r(p)`` around it (``k * mesh.longest_edge[p]`` at range
Rk, or a fixed radius: :func:`curv.core.ranges.ball_radii`)::

    T(p) = 1 / area(B ∩ mesh) * sum_e beta(e) |e ∩ B| ê êᵀ

with ``beta(e)`` the signed dihedral angle of edge e (positive on convex edges for outward normals),
``|e ∩ B|`` the exact length of the edge inside the ball and ê its unit direction. The eigenvector
of T closest to the vertex normal is dropped; the other two eigenvalues are the principal
curvatures, each with the *other* eigenvector as its direction (the edge tensor of a cylinder has
its eigenvalue 1/r along the axis, the direction of zero curvature).

The module reads in that order:

1. **support**: the vertices reachable from p along edges without leaving B, walked by the pass
   that runs csm and icc (:mod:`curv.estimators.clipping_pair`), which also clips the faces
   crossing the sphere (:mod:`curv.estimators._ball_clipping`);
2. **rows**: the edge term ``beta(e) |e ∩ B| ê êᵀ`` (:func:`dihedral_scale`, :func:`add_edge_term`)
   and every vertex's share of the terms of its edges and faces (:func:`star_terms`);
3. **sum**: over the support, the star rows corrected at the sphere (:func:`add_crossings`), or,
   where a star row is not exact, the edges and faces one by one (:func:`walk_sums`);
4. **tensor**: T, the sum over the area (:func:`finish`);
5. **principal curvatures**: T's eigenpairs with the normal's dropped (:func:`principal_from_tensor`).

What is approximated
--------------------
The edges and faces considered are those touching p or a vertex of its support
(:func:`curv.geometry.neighbourhood.ball_support`). Edges and faces whose vertices all lie outside
that support are ignored even when they graze B (e.g. a long edge passing through the rim of the
ball, or a part of the surface that re-enters the ball without a path inside it). Everything else
is exact: ``|e ∩ B|`` is the segment/sphere intersection and ``area(B ∩ face)`` the exact area of
the triangle within the disc ``B ∩ plane of the face``.

How the sums run
----------------
Summed over a support, the star rows hold every edge inside the (convex) ball twice by halves and
every face thrice by thirds; only the elements crossing the sphere are corrected, each found once
(:func:`~curv.estimators._ball_mesh.crossing_faces`). A support holding a vertex whose star row is
not exact (a non-manifold or inconsistently oriented edge, a degenerate face; with ``features``, a
face touching a crease) is summed edge by edge over the mesh's edge table, built only then.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..core.jit import jit, jit_inlined, jit_parallel, launch, prange, threads
from ..core.mesh import Mesh
from ..geometry.neighbourhood import coordinate_columns
from ._ball_clipping import face_in_ball_area, offset, segment_in_ball
from ._ball_mesh import corner_width, element_list
from ._ball_sums import CLIPPING_PASS, DEGENERATE_BIT, support_reason, touched_elements, touches, vertex_normal
from ._output_rows import nan_row
from ..core.small_linalg import sym3_eigen
from .registry import SHARED_PASSES, EstimatorSpec, register

__all__ = ["iter_csm", "csm_terms", "CsmTerms", "edge_beta_scale", "star_terms", "dihedral_scale", "add_edge_term",
           "walk_sums", "add_crossings", "finish", "principal_from_tensor", "SUMS"]

SUMS = 7
"""A centre's sums: T's upper triangle (xx, xy, xz, yy, yz, zz) before the division, then area(B ∩ mesh)."""


# ---------------------------------------------------------------------------- 2. rows: the edge term
@jit
def dihedral_scale(vector_area, area, f0, f1, d, length):
    """``beta / |e|`` of the edge ``d`` (3-tuple, of length ``length``) from face f0 (where the edge runs
    along d) to f1: ``beta(e) |e| ê êᵀ = (beta / |e|) d dᵀ``, beta the signed angle between their normals."""
    n0x, n0y, n0z = vector_area[f0, 0] / area[f0], vector_area[f0, 1] / area[f0], vector_area[f0, 2] / area[f0]
    n1x, n1y, n1z = vector_area[f1, 0] / area[f1], vector_area[f1, 1] / area[f1], vector_area[f1, 2] / area[f1]
    sx = n0y * n1z - n0z * n1y
    sy = n0z * n1x - n0x * n1z
    sz = n0x * n1y - n0y * n1x
    beta = math.atan2((sx * d[0] + sy * d[1] + sz * d[2]) / length, n0x * n1x + n0y * n1y + n0z * n1z)
    return beta / length


@jit
def _add_outer(sums, w, d):
    """Add ``w d dᵀ`` (upper triangle: xx, xy, xz, yy, yz, zz) to ``sums[:6]``."""
    wx, wy = w * d[0], w * d[1]
    sums[0] += wx * d[0]
    sums[1] += wx * d[1]
    sums[2] += wx * d[2]
    sums[3] += wy * d[1]
    sums[4] += wy * d[2]
    sums[5] += w * d[2] * d[2]


@jit
def add_edge_term(sums, a, b, r2, scale):
    """Add ``beta(e) |e ∩ B| ê êᵀ`` (``scale * frac * d dᵀ``) of the edge a -> b to ``sums[:6]``.

    ``a`` and ``b`` are the ends' offsets from the ball's centre (3-tuples), ``a`` inside the ball
    of squared radius ``r2``; ``scale`` is ``beta(e) / |e|``.
    """
    d = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    frac = 1.0  # both ends in the (convex) ball: all of e
    if b[0] * b[0] + b[1] * b[1] + b[2] * b[2] > r2:
        frac = segment_in_ball(a, d, r2)
    _add_outer(sums, scale * frac, d)


@jit
def _kept_share(e, edge_faces, crease, tri):
    """The share of edge e's dihedral term that belongs to the faces kept next to a crease.

    Each of its two faces carries half of it (the dual strip of an edge is half in each face);
    a face touching a crease vertex is left out, and so is its half: 1, 1/2 or 0.
    """
    share = 0.0
    for side in range(2):
        if not touches(crease, tri, edge_faces[e, side]):
            share += 0.5
    return share


@jit_parallel
def _edge_beta_scale(ids, edge_table, coords, faces, out):
    edges, edge_faces, face_count = edge_table
    x, y, z = coords
    vector_area, area, degenerate = faces
    for i in prange(ids.size):
        e = ids[i]
        out[e] = 0.0
        f0, f1 = edge_faces[e, 0], edge_faces[e, 1]
        if face_count[e] != 2 or f1 < 0:
            continue
        if degenerate[f0] or degenerate[f1]:
            continue  # next to a degenerate face: its vertices are invalid anyway
        a, b = edges[e, 0], edges[e, 1]
        d = (x[b] - x[a], y[b] - y[a], z[b] - z[a])
        length = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        if not length > 0.0:
            continue
        # slot 0: the face where the edge runs a -> b
        scale = dihedral_scale(vector_area, area, f0, f1, d, length)
        if math.isfinite(scale):
            out[e] = scale


def edge_beta_scale(mesh: Mesh, ids: np.ndarray | None = None) -> np.ndarray:
    """(e,) ``beta(e) / |e|`` per edge (:func:`dihedral_scale`); 0 without exactly two faces or next to
    a degenerate face. ``ids`` (k,) int64: only these edges (a region's; the others left unset)."""
    count = mesh.edges.shape[0]
    out = np.empty(count)
    launch(_edge_beta_scale, element_list(count, ids), (mesh.edges, mesh.edge_faces, mesh.edge_face_count),
           coordinate_columns(mesh), (mesh.face_vector_areas, mesh.face_areas, mesh.degenerate_faces), out)
    return out


# ---------------------------------------------------------------------------- 2. rows: every vertex's share
STAR = 8
"""Columns of the per-vertex star terms: half of each edge's ``beta |e| ê êᵀ`` (xx, xy, xz, yy, yz, zz), a third
of each face's area, and a pad to one cache line."""


@jit_parallel
def _star_terms(ids, parts, width, corners, coords, faces, flags, out):
    vc_ptr, vc, tri = corners
    x, y, z = coords
    vector_area, area, degenerate = faces
    nonmanifold, inconsistent, crease = flags
    half_scale, star, clean = out
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
                d = (x[w] - x[v], y[w] - y[v], z[w] - z[v])
                length = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
                if not length > 0.0:
                    continue
                scale = dihedral_scale(vector_area, area, f, g, d, length)
                if not math.isfinite(scale):
                    continue
                half_scale[h] = scale
                wt = 0.5 * scale
                wx, wy = wt * d[0], wt * d[1]
                t00 += wx * d[0]
                t01 += wx * d[1]
                t02 += wx * d[2]
                t11 += wy * d[1]
                t12 += wy * d[2]
                t22 += wt * d[2] * d[2]
            star[v, 0], star[v, 1], star[v, 2] = t00, t01, t02
            star[v, 3], star[v, 4], star[v, 5] = t11, t12, t22
            star[v, 6] = third
            clean[v] = ok


def star_terms(mesh: Mesh, ids: np.ndarray | None = None, crease: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What every centre whose support holds vertex v shares: v's half of its edges and third of its faces.

    ``ids`` (k,) int64: only these vertices (a region's supports; the other rows left unset);
    ``crease`` (n,) bool: a vertex with a face touching one is not clean.

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
    ids = element_list(n, ids)
    parts = max(1, min(8 * threads(), ids.size))  # slices of vertices, each with its own scratch
    launch(_star_terms, ids, parts, corner_width(mesh), (vc_ptr, vc, tri), coordinate_columns(mesh),
           (mesh.face_vector_areas, mesh.face_areas, mesh.degenerate_faces),
           (mesh.nonmanifold_vertices, mesh.inconsistent_vertices, crease), (half_scale, star, clean))
    return half_scale, star, clean


class CsmTerms(NamedTuple):
    """csm's per-mesh terms (:func:`csm_terms`)."""

    half_scale: np.ndarray
    """(3 m,) float64: ``beta(e) / |e|`` per halfedge (:func:`star_terms`)."""
    star: np.ndarray
    """(n, 8) float64: per-vertex halves of the edge terms and thirds of the face areas."""
    clean: np.ndarray
    """(n,) bool: the vertex's star terms are exact."""
    walk: bool
    """Some support is summed edge by edge: the edge table below is set."""
    halfedge_edge: np.ndarray
    """(3 m,) int64 or empty: :attr:`curv.Mesh.halfedge_edge`."""
    beta_scale: np.ndarray
    """(e,) float64 or empty: :func:`edge_beta_scale`."""
    edge_faces: np.ndarray
    """(e, 2) int64 or empty: :attr:`curv.Mesh.edge_faces`."""


def csm_terms(mesh: Mesh, centres: np.ndarray, radii: np.ndarray, walk, touched: np.ndarray | None):
    """csm's per-mesh terms for the supports of ``centres`` (c,) at ``radii`` (levels, n), a generator
    (yields 0.0 after each pass): :func:`star_terms` of the vertices ``touched`` (None: all), and
    the edge table only where a support is not clean (``walk``: :func:`~curv.estimators._ball_sums.ball_inputs`)."""
    half_scale, star, clean = star_terms(mesh, touched, walk.crease)
    yield 0.0
    edge_walk = not (clean.all() if touched is None else clean[touched].all())
    if edge_walk:
        edge_ids = None if touched is None else touched_elements(mesh, centres, radii[-1], walk.indptr, walk.indices,
                                                                 edges=True)[2]
        beta_scale = edge_beta_scale(mesh, edge_ids)
        halfedge_edge, edge_faces = mesh.halfedge_edge, mesh.edge_faces
        yield 0.0
    else:
        beta_scale, halfedge_edge, edge_faces = np.empty(0), np.empty(0, np.int64), np.empty((0, 2), np.int64)
    return CsmTerms(half_scale, star, clean, edge_walk, halfedge_edge, beta_scale, edge_faces)


# ---------------------------------------------------------------------------- 3. the sums over a support
@jit
def walk_sums(centre, support, mesh, walk, terms, stamps, sums):
    """Add to ``sums`` (7,) the terms of a support that is not clean (or stops at creases), face by face
    and edge by edge; returns the DEGENERATE_BIT if a degenerate face was met.

    ``centre = (p, r2, mark)``: the centre, its squared radius and this walk's stamp
    (:func:`~curv.estimators._ball_sums.level_mark`); ``support = (queue, count)``; ``mesh`` a
    :class:`~curv.estimators._ball_mesh.BallMesh`, ``walk`` a
    :class:`~curv.estimators._ball_sums.BallWalk` (its creases); ``terms`` :class:`CsmTerms` (or
    the pass's bundle of its fields); ``stamps = (estamp (e,), fstamp (m,))`` the thread's, zeroed at first.
    """
    p, r2, mark = centre
    queue, count = support
    estamp, fstamp = stamps
    cut, crease, tri = walk.cut, walk.crease, mesh.tri
    at = (mesh.x[p], mesh.y[p], mesh.z[p])
    hit = 0
    for i in range(count):
        v = queue[i]
        a = offset(mesh, v, at)
        for j in range(mesh.vc_ptr[v], mesh.vc_ptr[v + 1]):
            h = mesh.vc[j]
            f = h // 3  # the corners of triangle f are 3f, 3f + 1, 3f + 2
            if cut and crease[v]:
                if mesh.degenerate[f]:
                    hit |= DEGENERATE_BIT
                continue
            if fstamp[f] != mark:
                fstamp[f] = mark
                if mesh.degenerate[f]:
                    hit |= DEGENERATE_BIT
                elif not (cut and touches(crease, tri, f)):
                    sums[6] += face_in_ball_area(mesh, f, at, r2)
            # the edge out of v in triangle f: on a consistently oriented mesh every interior
            # edge of v is one (border and non-manifold edges have no dihedral term)
            e = terms.halfedge_edge[h]
            if e < 0 or estamp[e] == mark:
                continue
            estamp[e] = mark
            s = terms.beta_scale[e]
            if cut and s != 0.0:
                s *= _kept_share(e, terms.edge_faces, crease, tri)
            if s != 0.0:
                w = tri[f, (h - 3 * f + 1) % 3]  # the edge runs from v to the next corner of f
                add_edge_term(sums, a, offset(mesh, w, at), r2, s)
    return hit


@jit_inlined
def add_crossings(sums, v, centre, crossings, leaving, mesh, half_scale):
    """Correct a support's star sums (7,) for the ``leaving`` faces that cross the sphere around
    ``centre`` out of v (:func:`~curv.estimators._ball_mesh.crossing_faces`' scratch ``crossings``):
    an edge v -> w leaving the ball has one half in the sums (replaced by its part inside, the exit
    fraction) and its face one or two thirds (replaced by the face's area inside). ``half_scale``
    is :attr:`CsmTerms.half_scale`."""
    out_h, out_w, out_t, out_area, out_in, _ = crossings
    for a in range(leaving):
        h, w = out_h[a], out_w[a]
        f = h // 3
        s = half_scale[h]
        if s != 0.0:
            vx, vy, vz = offset(mesh, v, centre)
            wx, wy, wz = offset(mesh, w, centre)
            _add_outer(sums, s * (out_t[a] - 0.5), (wx - vx, wy - vy, wz - vz))
        sums[6] += out_area[a] - out_in[a] * (mesh.area[f] / 3.0)


# ---------------------------------------------------------------------------- 4. tensor, 5. principal curvatures
@jit
def principal_from_tensor(tensor, normal, vectors, out):
    """Curvatures and directions of a normal-cycle tensor T at a vertex with unit normal n.

    Drops the eigenvector closest to n; of the other two (ascending), each eigenvector is the
    principal direction of the *other* eigenvalue. ``tensor`` (3, 3) is overwritten, ``vectors``
    (4, 3) is scratch for :func:`~curv.core.small_linalg.sym3_eigen`. Writes
    ``out[:] = ka, kb, da (3), db (3)`` with ``ka <= kb``, ``db`` the tangent-projected
    eigenvector of ka and ``da = n x db``.
    """
    nx, ny, nz = normal
    sym3_eigen(tensor, vectors)  # vectors[:3, j]: eigenvector of the eigenvalue vectors[3, j]
    drop = 0
    best = -1.0
    for j in range(3):
        along = abs(vectors[0, j] * nx + vectors[1, j] * ny + vectors[2, j] * nz)
        if along > best:
            best = along
            drop = j
    ia = 1 if drop == 0 else 0
    ib = 1 if drop == 2 else 2
    bx, by, bz = vectors[0, ia], vectors[1, ia], vectors[2, ia]
    dn = bx * nx + by * ny + bz * nz
    bx -= dn * nx
    by -= dn * ny
    bz -= dn * nz
    norm = math.sqrt(bx * bx + by * by + bz * bz)
    bx /= norm
    by /= norm
    bz /= norm
    out[0] = vectors[3, ia]
    out[1] = vectors[3, ib]
    out[2] = ny * bz - nz * by
    out[3] = nz * bx - nx * bz
    out[4] = nx * by - ny * bx
    out[5] = bx
    out[6] = by
    out[7] = bz


@jit
def finish(at, sums, hit, normals, work, rows):
    """Centre p's principal curvatures from its sums (7,: T's upper triangle, the area) into row
    ``row`` of ``rows = (k1, k2, d1, d2, reason)``, ``at = (p, row)`` (the pass's outputs hold every
    level's rows: :class:`~curv.estimators.clipping_pair.CsmPass`); ``hit`` the support's flags
    (:func:`~curv.estimators._ball_sums.support_reason`), ``work = (tensor (3, 3), vectors (4, 3),
    res (8,))`` the thread's scratch."""
    p, row = at
    k1, k2, d1, d2, reason = rows
    tensor, vectors, res = work
    nx, ny, nz, normal_ok = vertex_normal(normals, p)
    area = sums[6]
    singular = not (area > 0.0 and math.isfinite(sums[0] + sums[1] + sums[2] + sums[3] + sums[4] + sums[5]))
    if not singular and normal_ok:
        inv = 1.0 / area
        tensor[0, 0], tensor[1, 1], tensor[2, 2] = sums[0] * inv, sums[3] * inv, sums[5] * inv
        tensor[0, 1] = tensor[1, 0] = sums[1] * inv
        tensor[0, 2] = tensor[2, 0] = sums[2] * inv
        tensor[1, 2] = tensor[2, 1] = sums[4] * inv
        principal_from_tensor(tensor, (nx, ny, nz), vectors, res)
        k1[row], k2[row] = res[0], res[1]
        for c in range(3):
            d1[row, c] = res[2 + c]
            d2[row, c] = res[5 + c]
        if not (math.isfinite(res[2]) and math.isfinite(res[3]) and math.isfinite(res[4])):
            singular = True
    else:
        nan_row(row, k1, k2, d1, d2)
    reason[row] = support_reason(singular, hit, normal_ok)


# ---------------------------------------------------------------------------- the estimator
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
        or at each of several levels, ascending per vertex (:func:`curv.estimate_ranges`): one walk
        per centre serves them all, a level's star sums are the last one's plus the vertices it
        added (results to rounding of the single-radius calls').
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
    out = yield from SHARED_PASSES[CLIPPING_PASS](mesh, normals, radii, ("csm",), chunk=chunk, centres=centres,
                                                  features=features)
    return out["csm"] if np.ndim(radii) == 2 else out["csm"][0]


register(EstimatorSpec(
    name="csm", title="Cohen-Steiner & Morvan normal cycle", ranges=(1, 2, 3, 4), function=iter_csm,
    # `curv estimate torus10M.ply -m csm -r 2`: 7.02 GB peak, 334 B a unit above the base and stamps; +35 % as mru
    extra_bytes_per_unit=100.0,
    triangles_only=True, uses_normals=False, closed_ring=True,
    reference="Cohen-Steiner & Morvan 2003, Restricted Delaunay triangulations and normal cycle",
    summary="signed dihedral angle x clipped edge length x ê êᵀ summed in a ball, over the area in it",
    kernels=(_star_terms, _edge_beta_scale), takes_levels=True,
    shared_pass=CLIPPING_PASS,
))
