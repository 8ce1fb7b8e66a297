"""The per-centre sums of ``csm`` and ``icc``, and the one kernel that runs either or both.

Both estimators sum per-vertex star terms over the support of a ball and correct the faces that
cross its sphere (:mod:`curv.estimators.csm` and :mod:`curv.estimators.icc` say what they sum). At the
same radii the search, the rim and the exact clip of every crossing face
(:func:`~curv.estimators._ball_clipping.crossing_faces`: its exit along the edge leaving the ball
and its area inside) are the same for both, so :func:`_clip_chunk` does them once per centre and
level and feeds each estimator asked for: csm replaces the halves of the leaving edges by their
exits and the thirds of the faces' areas by the areas inside (:func:`add_edge_crossings`), icc
the thirds of the faces' measures by their area fractions (:func:`add_face_crossings`). Each
estimator's sums are added in the order of a run of it alone, so running both together gives
each the same bits. :func:`run_clipping` drives the kernel over chunks of centres.

The estimator modules do not import each other; they and the pass that runs both
(:mod:`curv.estimators.clipping_pair`) import this one.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..core.jit import iter_chunks, jit, jit_parallel, launch, prange, slice_bounds, threads
from ._ball_clipping import (DEGENERATE_BIT, LevelOutputs, add_row, add_star_rows, corner_width, crossing_faces,
                             crossing_scratch, face_in_ball_area, level_mark, may_leave, start_ball_support,
                             support_reason, touches, vertex_normal, widen_ball_support)
from ..geometry.neighbourhood import new_queues, new_scratch
from ..core.small_linalg import sym3_bilinear, sym3_eigen
from ._frames import tangent_frame
from ._principal import store_principal

__all__ = ["segment_in_ball", "csm_walk_sums", "csm_finish", "icc_walk_sums", "icc_finish", "add_edge_crossings",
           "add_face_crossings", "run_clipping", "CsmTerms", "IccTerms", "MEASURES", "EPS", "CLIPPING_PASS"]

CLIPPING_PASS = "ball clipping"
"""The shared pass ``csm`` and ``icc`` name (:attr:`~curv.estimators.EstimatorSpec.shared_pass`), run by
:func:`curv.estimators.clipping_pair.iter_csm_icc`."""


# ---------------------------------------------------------------------------- csm: the normal-cycle tensor
@jit
def segment_in_ball(sx, sy, sz, dx, dy, dz, radius2):
    """Fraction of the segment ``s + t d``, t in [0, 1], inside the ball of squared radius ``radius2`` at 0.

    Solves ``|s + t d|^2 = radius2`` for t and clips the root interval to [0, 1]; 0 when the line
    misses the ball.
    """
    a = dx * dx + dy * dy + dz * dz
    b = dx * sx + dy * sy + dz * sz
    c = sx * sx + sy * sy + sz * sz - radius2
    disc = b * b - a * c
    if not (disc > 0.0 and a > 0.0):
        return 0.0
    sq = math.sqrt(disc)
    t1 = min(max((-b - sq) / a, 0.0), 1.0)
    t2 = min(max((-b + sq) / a, 0.0), 1.0)
    return t2 - t1


@jit
def _principal_from_normal_cycle(tensor, nx, ny, nz, vectors, out):
    """Curvatures and directions of a normal-cycle tensor T at a vertex with unit normal n.

    Drops the eigenvector closest to n; of the other two (ascending), each eigenvector is the
    principal direction of the *other* eigenvalue. ``tensor`` (3, 3) is overwritten, ``vectors``
    (4, 3) is scratch for :func:`sym3_eigen`. Writes ``out[:] = ka, kb, da (3), db (3)`` with
    ``ka <= kb``, ``db`` the tangent-projected eigenvector of ka and ``da = n x db``.
    """
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
def _add_outer(sums, w, dx, dy, dz):
    """Add ``w d dᵀ`` (upper triangle: xx, xy, xz, yy, yz, zz) to ``sums[:6]``."""
    wx, wy = w * dx, w * dy
    sums[0] += wx * dx
    sums[1] += wx * dy
    sums[2] += wx * dz
    sums[3] += wy * dy
    sums[4] += wy * dz
    sums[5] += w * dz * dz


@jit
def _add_edge_term(sums, ax, ay, az, bx, by, bz, r2, scale):
    """Add ``beta(e) |e ∩ B| ê êᵀ`` (``scale * frac * d dᵀ``, :func:`_add_outer`) of the edge a -> b.

    ``a`` and ``b`` are the ends' offsets from the ball's centre, ``a`` inside the ball; ``scale``
    is ``beta(e) / |e|``.
    """
    dx, dy, dz = bx - ax, by - ay, bz - az
    frac = 1.0  # both ends in the (convex) ball: all of e
    if bx * bx + by * by + bz * bz > r2:
        frac = segment_in_ball(ax, ay, az, dx, dy, dz, r2)
    _add_outer(sums, scale * frac, dx, dy, dz)


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


@jit
def _unset(level, p, k1, k2, d1, d2):
    """NaN curvatures and directions in row ``(level, p)`` of the outputs."""
    k1[level, p] = k2[level, p] = math.nan
    for c in range(3):
        d1[level, p, c] = d2[level, p, c] = math.nan


@jit
def csm_walk_sums(p, mark, count, queue, r2, x, y, z, vc_ptr, vc, halfedge_edge, beta_scale, edge_faces, tri,
               vector_area, face_area, degenerate, cut, crease, estamp, fstamp, sums):
    """The sums of a centre whose support is not clean (or that stops at creases), face by face and edge by edge.

    Adds the upper triangle of T and the area to ``sums`` (as :func:`_clip_chunk` has them); returns
    the DEGENERATE_BIT if a degenerate face was met. ``mark``: this walk's stamp
    (:func:`~curv.estimators._ball_clipping.level_mark`; the stamps start zeroed).
    """
    px, py, pz = x[p], y[p], z[p]
    hit = 0
    for i in range(count):
        v = queue[i]
        vx, vy, vz = x[v] - px, y[v] - py, z[v] - pz
        for j in range(vc_ptr[v], vc_ptr[v + 1]):
            h = vc[j]
            f = h // 3  # the corners of triangle f are 3f, 3f + 1, 3f + 2
            if cut and crease[v]:
                if degenerate[f]:
                    hit |= DEGENERATE_BIT
                continue
            if fstamp[f] != mark:
                fstamp[f] = mark
                if degenerate[f]:
                    hit |= DEGENERATE_BIT
                elif not (cut and touches(crease, tri, f)):
                    sums[6] += face_in_ball_area(tri, f, x, y, z, vector_area, face_area, px, py, pz, r2)
            # the edge out of v in triangle f: on a consistently oriented mesh every interior
            # edge of v is one (border and non-manifold edges have no dihedral term)
            e = halfedge_edge[h]
            if e < 0 or estamp[e] == mark:
                continue
            estamp[e] = mark
            s = beta_scale[e]
            if cut and s != 0.0:
                s *= _kept_share(e, edge_faces, crease, tri)
            if s != 0.0:
                w = tri[f, (h - 3 * f + 1) % 3]  # the edge runs from v to the next corner of f
                _add_edge_term(sums, vx, vy, vz, x[w] - px, y[w] - py, z[w] - pz, r2, s)
    return hit


@jit
def csm_finish(p, level, sums, hit, normals, tensor, vectors, res, k1, k2, d1, d2, reason):
    """Centre p's principal curvatures at ``level`` from its sums (upper triangle of T, area), into
    row ``(level, p)`` of the outputs."""
    nx, ny, nz, normal_ok = vertex_normal(normals, p)
    area = sums[6]
    singular = not (area > 0.0 and math.isfinite(sums[0] + sums[1] + sums[2] + sums[3] + sums[4] + sums[5]))
    if not singular and normal_ok:
        inv = 1.0 / area
        tensor[0, 0], tensor[1, 1], tensor[2, 2] = sums[0] * inv, sums[3] * inv, sums[5] * inv
        tensor[0, 1] = tensor[1, 0] = sums[1] * inv
        tensor[0, 2] = tensor[2, 0] = sums[2] * inv
        tensor[1, 2] = tensor[2, 1] = sums[4] * inv
        _principal_from_normal_cycle(tensor, nx, ny, nz, vectors, res)
        k1[level, p], k2[level, p] = res[0], res[1]
        for c in range(3):
            d1[level, p, c] = res[2 + c]
            d2[level, p, c] = res[5 + c]
        if not (math.isfinite(res[2]) and math.isfinite(res[3]) and math.isfinite(res[4])):
            singular = True
    else:
        _unset(level, p, k1, k2, d1, d2)
    reason[level, p] = support_reason(singular, hit, normal_ok)


# ---------------------------------------------------------------------------- icc: the corrected measures
EPS = float(np.finfo(np.float64).eps)

MEASURES = 9
"""Columns of :func:`face_measures`: mu0, mu1, mu2 and the symmetric part of M (xx, xy, xz, yy, yz, zz)."""


@jit
def _row_is_finite(a, r):
    for c in range(a.shape[1]):
        if not math.isfinite(a[r, c]):
            return False
    return True


@jit
def icc_walk_sums(p, mark, count, queue, r2, x, y, z, vc_ptr, vc, tri, vector_area, face_area, degenerate, measures, cut,
               crease, fstamp, sums):
    """The nine sums of a centre whose support is not clean (or that stops at creases), face by face.

    Adds them to ``sums`` (9,); returns the DEGENERATE_BIT if a degenerate face or a face without
    measures was met. ``mark``: this walk's stamp (:func:`~curv.estimators._ball_clipping.level_mark`;
    the stamps start zeroed).
    """
    px, py, pz = x[p], y[p], z[p]
    hit = 0
    for i in range(count):
        v = queue[i]
        for j in range(vc_ptr[v], vc_ptr[v + 1]):
            f = vc[j] // 3  # the corners of triangle f are 3f, 3f + 1, 3f + 2
            if fstamp[f] == mark:
                continue
            fstamp[f] = mark
            if degenerate[f]:
                hit |= DEGENERATE_BIT
                continue
            if cut and touches(crease, tri, f):
                continue  # the surface ends at a crease for this centre: its faces are left out
            if not _row_is_finite(measures, f):
                hit |= DEGENERATE_BIT  # a corner without a normal
                continue
            # weight: the fraction of the face's area inside B
            inside = face_in_ball_area(tri, f, x, y, z, vector_area, face_area, px, py, pz, r2)
            w = min(inside / face_area[f], 1.0)
            if w > 0.0:
                add_row(sums, w, measures, f)
    return hit


@jit
def icc_finish(p, level, sums, hit, normals, from_measures, k1, k2, d1, d2, mean, gaussian, reason):
    """Centre p's curvatures at ``level`` from its nine sums, into row ``(level, p)`` of the outputs."""
    nx, ny, nz, normal_ok = vertex_normal(normals, p)
    mean[level, p] = gaussian[level, p] = math.nan
    mu0, s1, s2 = sums[0], sums[1], sums[2]
    total = 0.0
    for c in range(MEASURES):
        total += sums[c]
    singular = not (mu0 > 0.0 and math.isfinite(total))
    if not singular and normal_ok:
        h = mean[level, p] = 0.5 * s1 / mu0
        kk = gaussian[level, p] = s2 / mu0
        # W = M / mu0 in the tangent frame (U, V) of the vertex normal
        ux, uy, uz, vx, vy, vz = tangent_frame(nx, ny, nz)
        m = sums[3], sums[4], sums[5], sums[6], sums[7], sums[8]
        e = sym3_bilinear(m, (ux, uy, uz), (ux, uy, uz)) / mu0
        f_ = sym3_bilinear(m, (ux, uy, uz), (vx, vy, vz)) / mu0
        g = sym3_bilinear(m, (vx, vy, vz), (vx, vy, vz)) / mu0
        store_principal(p, (e, f_, g), (ux, uy, uz, vx, vy, vz), k1[level], k2[level], d1[level], d2[level])
        if from_measures:
            # k = H ± sqrt(H² - K); the directions stay those of M. A discriminant within
            # rounding of H² and K is an umbilic: its square root would turn 1e-16 into 1e-8.
            # H and K are sums of a few hundred clipped terms, rounded to tens of EPS.
            disc = h * h - kk
            if disc <= 64.0 * EPS * (h * h + abs(kk)):
                disc = 0.0
            rad = math.sqrt(disc)
            k1[level, p] = h + rad
            k2[level, p] = h - rad
        if not (math.isfinite(k1[level, p]) and math.isfinite(k2[level, p])):
            singular = True
    else:
        _unset(level, p, k1, k2, d1, d2)
    reason[level, p] = support_reason(singular, hit, normal_ok)


# ---------------------------------------------------------------------------- the crossing faces
@jit
def add_edge_crossings(sums, v, px, py, pz, leaving, out_h, out_w, out_t, out_area, out_in, x, y, z, half_scale,
                       face_area):
    """csm: correct a support's star sums for the ``leaving`` faces that cross the sphere out of v.

    The star sums hold each edge twice by halves and each face thrice by thirds; an edge v -> w
    leaving the ball has one half in (replaced by the part inside, ``out_t``:
    :func:`~curv.estimators._ball_clipping.exit_fraction`) and its face one or two thirds
    (``out_in``, replaced by ``out_area``). ``sums`` (7,): upper triangle of T, area.
    """
    for a in range(leaving):
        h, w = out_h[a], out_w[a]
        f = h // 3
        s = half_scale[h]
        if s != 0.0:
            vx, vy, vz = x[v] - px, y[v] - py, z[v] - pz
            _add_outer(sums, s * (out_t[a] - 0.5), (x[w] - px) - vx, (y[w] - py) - vy, (z[w] - pz) - vz)
        sums[6] += out_area[a] - out_in[a] * (face_area[f] / 3.0)


@jit
def add_face_crossings(sums, leaving, out_h, out_area, out_in, face_area, measures):
    """icc: correct a support's star sums (9,) for the ``leaving`` faces that cross the sphere out of
    a vertex: each face's one or two thirds of its measures (``out_in``) become the fraction of its
    area inside the ball."""
    for a in range(leaving):
        f = out_h[a] // 3
        add_row(sums, min(out_area[a] / face_area[f], 1.0) - out_in[a] * (1.0 / 3.0), measures, f)


# ---------------------------------------------------------------------------- the kernel
@jit_parallel
def _clip_chunk(centres, lo, hi, radii, indptr, indices, x, y, z, longest, vc_ptr, vc, after, link, tri, vector_area,
                face_area, degenerate, border, nonmanifold, cut, crease, normals, width, vstamps, queues, rims,
                outside, outside_d2, with_csm, csm_in, csm_out, with_icc, icc_in, icc_out):
    half_scale, c_star, c_clean, halfedge_edge, beta_scale, edge_faces, c_fstamps, c_estamps = csm_in
    c_k1, c_k2, c_d1, c_d2, c_reason = csm_out
    measures, i_star, i_clean, from_measures, i_fstamps = icc_in
    i_k1, i_k2, i_d1, i_d2, mean, gaussian, i_reason = icc_out
    parts = vstamps.shape[0]
    levels = radii.shape[0]
    for t in prange(parts):
        vectors = np.empty((4, 3))
        tensor = np.empty((3, 3))
        res = np.empty(8)
        c_acc = np.empty(7)  # csm: the support's star sums so far
        c_sums = np.empty(7)  # T = sum_e beta(e) |e ∩ B| ê êᵀ (upper triangle), area(B ∩ mesh)
        i_acc = np.empty(MEASURES)  # icc: the same for its nine measures
        i_sums = np.empty(MEASURES)
        out_h, out_w, out_t, out_area, out_in, ring = crossing_scratch(width)
        queue, vstamp, rim = queues[t], vstamps[t], rims[t]
        waiting, waiting_d2 = outside[t], outside_d2[t]
        start, stop = slice_bounds(lo, hi, t, parts)
        for k in range(start, stop):
            p = centres[k]
            px, py, pz = x[p], y[p], z[p]
            # one walk for every level: each level's support is the single search's at its radius
            # (widen_ball_support), its star sums the last level's plus the rows it added
            count = start_ball_support(p, vstamp, queue)
            head = pending = done = rim_count = 0
            hit = 0
            c_exact, i_exact = with_csm, with_icc
            c_acc[:] = 0.0
            i_acc[:] = 0.0
            for level in range(levels):
                r = radii[level, p]
                count, head, pending = widen_ball_support(p, r ** 2, level + 1 < levels, indptr, indices, x, y, z,
                                                          vstamp, queue, count, head, waiting, waiting_d2, pending)
                before = hit  # the flags are the vertices', the same for both
                if with_csm:
                    hit, c_exact = add_star_rows(queue, done, count, border, nonmanifold, c_clean, c_star, before,
                                                 c_exact, c_acc)
                if with_icc:
                    hit, i_exact = add_star_rows(queue, done, count, border, nonmanifold, i_clean, i_star, before,
                                                 i_exact, i_acc)
                if c_exact or i_exact:
                    # every element inside the ball whole is in the star sums; only the last level's rim
                    # and the new vertices may have edges leaving it: their crossing faces are clipped
                    # once and corrected in each estimator's sums
                    c_sums[:] = c_acc
                    i_sums[:] = i_acc
                    kept = 0
                    for i in range(rim_count + count - done):
                        v = rim[i] if i < rim_count else queue[done + i - rim_count]
                        if not may_leave(v, px, py, pz, r, x, y, z, longest):
                            continue
                        rim[kept] = v
                        kept += 1
                        leaving = crossing_faces(v, px, py, pz, r, x, y, z, vc_ptr, vc, after, link, tri,
                                                 vector_area, face_area, out_h, out_w, out_t, out_area, out_in, ring)
                        if c_exact:
                            add_edge_crossings(c_sums, v, px, py, pz, leaving, out_h, out_w, out_t, out_area, out_in,
                                               x, y, z, half_scale, face_area)
                        if i_exact:
                            add_face_crossings(i_sums, leaving, out_h, out_area, out_in, face_area, measures)
                    rim_count = kept
                mark = level_mark(p, level, levels)
                if with_csm:
                    level_hit = hit
                    if not c_exact:
                        c_sums[:] = 0.0
                        level_hit |= csm_walk_sums(p, mark, count, queue, r ** 2, x, y, z, vc_ptr, vc, halfedge_edge,
                                                   beta_scale, edge_faces, tri, vector_area, face_area, degenerate,
                                                   cut, crease, c_estamps[t], c_fstamps[t], c_sums)
                    csm_finish(p, level, c_sums, level_hit, normals, tensor, vectors, res, c_k1, c_k2, c_d1, c_d2,
                               c_reason)
                if with_icc:
                    level_hit = hit
                    if not i_exact:
                        i_sums[:] = 0.0
                        level_hit |= icc_walk_sums(p, mark, count, queue, r ** 2, x, y, z, vc_ptr, vc, tri,
                                                   vector_area, face_area, degenerate, measures, cut, crease,
                                                   i_fstamps[t], i_sums)
                    icc_finish(p, level, i_sums, level_hit, normals, from_measures, i_k1, i_k2, i_d1, i_d2, mean,
                               gaussian, i_reason)
                done = count


# ---------------------------------------------------------------------------- the driver
class CsmTerms(NamedTuple):
    """csm's per-mesh terms (:func:`curv.estimators.csm.csm_terms`)."""

    half_scale: np.ndarray
    """(3 m,) float64: ``beta(e) / |e|`` per halfedge (:func:`curv.estimators.csm.star_terms`)."""
    star: np.ndarray
    """(n, 8) float64: per-vertex halves of the edge terms and thirds of the face areas."""
    clean: np.ndarray
    """(n,) bool: the vertex's star terms are exact."""
    walk: bool
    """Some support is summed edge by edge: the edge table below is set."""
    halfedge_edge: np.ndarray
    """(3 m,) int64 or empty: :attr:`curv.Mesh.halfedge_edge`."""
    beta_scale: np.ndarray
    """(e,) float64 or empty: :func:`curv.estimators.csm.edge_beta_scale`."""
    edge_faces: np.ndarray
    """(e, 2) int64 or empty: :attr:`curv.Mesh.edge_faces`."""


class IccTerms(NamedTuple):
    """icc's per-mesh terms (:func:`curv.estimators.icc.icc_terms`)."""

    measures: np.ndarray
    """(m, 9) float64: :func:`curv.estimators.icc.face_measures`."""
    star: np.ndarray
    """(n, 9) float64: :func:`curv.estimators.icc.star_measures`."""
    clean: np.ndarray
    """(n,) bool: the vertex's star sums are exact."""
    walk: bool
    """Some support is summed face by face."""
    from_measures: bool
    """k1, k2 from mu1 and mu2 (else from M's eigenvalues)."""


def _stamps(parts: int, count: int, levels: int, n: int) -> np.ndarray:
    """(parts, count) zeroed stamps of a face-by-face (or edge-by-edge) walk; int32 where every
    :func:`~curv.estimators._ball_clipping.level_mark` fits (half the cache lines)."""
    return np.zeros((parts, count), np.int32 if (n + 1) * levels < 2**31 else np.int64)


def run_clipping(mesh, centres: np.ndarray, radii: np.ndarray, inputs: tuple, normals: np.ndarray,
                 csm: CsmTerms | None = None, icc: IccTerms | None = None, *, chunk: int | None = None):
    """Run :func:`_clip_chunk` over ``centres`` for csm, icc or both (a generator of the fraction done).

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    centres : (c,) int64
        The vertices to estimate.
    radii : (levels, n) float64
        Ascending per vertex (:func:`~curv.estimators._ball_clipping.level_radii`).
    inputs : tuple
        ``(tri, x, y, z, indptr, indices, cut, crease, after, link)``:
        :func:`~curv.estimators._ball_clipping.clipping_inputs` and
        :func:`~curv.estimators._ball_clipping.corner_rings`.
    normals : (n, 3) float64
        Unit vertex normals (read as they are).
    csm, icc : CsmTerms, IccTerms, optional
        The estimators to run (at least one).
    chunk : int, optional
        Vertices per kernel call (:func:`curv.core.jit.iter_chunks`).

    Returns
    -------
    csm_out : LevelOutputs or None
    icc_out : tuple of (LevelOutputs, mean (levels, n), gaussian (levels, n)) or None
    """
    tri, x, y, z, indptr, indices, cut, crease, after, link = inputs
    vc_ptr, vc = mesh.vertex_corners
    n = mesh.n_vertices
    levels = radii.shape[0]
    parts = max(1, min(threads(), centres.size))
    wide = n if levels > 1 else 0  # widen_ball_support's waiting vertices
    vstamps, queues, rims = new_scratch(n, parts), new_queues(n, parts), new_queues(n, parts)
    outside, outside_d2 = new_queues(wide, parts), np.empty((parts, wide))
    no_rows = np.empty((0, levels))  # an estimator not run: its arrays are empty, its branch skipped
    if csm is None:
        csm_in = (np.empty(0), np.empty((0, 8)), np.empty(0, np.bool_), np.empty(0, np.int64), np.empty(0),
                  np.empty((0, 2), np.int64), _stamps(parts, 0, levels, n), _stamps(parts, 0, levels, n))
        c_out = None
        csm_out = (no_rows, no_rows, np.empty((0, 0, 3)), np.empty((0, 0, 3)), np.empty((0, 0), np.uint8))
    else:
        c_faces = mesh.n_faces if csm.walk else 0
        csm_in = (csm.half_scale, csm.star, csm.clean, csm.halfedge_edge, csm.beta_scale, csm.edge_faces,
                  _stamps(parts, c_faces, levels, n), _stamps(parts, csm.beta_scale.size, levels, n))
        c_out = LevelOutputs(levels, n)
        csm_out = (c_out.k1, c_out.k2, c_out.d1, c_out.d2, c_out.reason)
    if icc is None:
        icc_in = (np.empty((0, MEASURES)), np.empty((0, MEASURES)), np.empty(0, np.bool_), True,
                  _stamps(parts, 0, levels, n))
        i_out = None
        icc_out = (no_rows, no_rows, np.empty((0, 0, 3)), np.empty((0, 0, 3)), no_rows, no_rows,
                   np.empty((0, 0), np.uint8))
    else:
        icc_in = (icc.measures, icc.star, icc.clean, bool(icc.from_measures),
                  _stamps(parts, mesh.n_faces if icc.walk else 0, levels, n))
        out = LevelOutputs(levels, n)
        mean = np.empty((levels, n))  # NaN at each centre before its sums (a region touches only its own pages)
        gaussian = np.empty((levels, n))
        i_out = (out, mean, gaussian)
        icc_out = (out.k1, out.k2, out.d1, out.d2, mean, gaussian, out.reason)

    def run(lo: int, hi: int) -> None:
        launch(_clip_chunk, centres, lo, hi, radii, indptr, indices, x, y, z, mesh.longest_edge, vc_ptr, vc, after,
               link, tri, mesh.face_vector_areas, mesh.face_areas, mesh.degenerate_faces, mesh.border_vertices,
               mesh.nonmanifold_vertices, cut, crease, normals, corner_width(mesh), vstamps, queues, rims, outside,
               outside_d2, csm is not None, csm_in, csm_out, icc is not None, icc_in, icc_out)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return c_out, i_out
