"""Interpolated corrected curvature measures (Lachaud, Romon, Thibert, Coeurjolly, SGP 2020).

The vertex normals u are interpolated linearly over each triangle (x_i, x_j, x_k), the *corrected
normal field*, and the curvature measures of the triangle with that field have closed forms. With
``ū = (u_i + u_j + u_k) / 3`` (the integral of u over the parameter triangle is half of it)::

    mu0 = 1/2 <ū | (x_j - x_i) x (x_k - x_i)>                                  area
    mu1 = 1/2 <ū | (u_j - u_i) x (x_k - x_i) + (x_j - x_i) x (u_k - u_i)>      mean (2 H dA)
    mu2 = 1/2 <u_i | u_j x u_k>                                                 Gaussian (K dA)
    M   = 1/2 [ ((x_k - x_i) x ū) (u_j - u_i)ᵀ - ((x_j - x_i) x ū) (u_k - u_i)ᵀ ]   anisotropic

``M`` is the measure ``mu^{X,Y} = Xᵀ M Y``: the integral over the triangle of
``<u | <Y|∂s u> X x ∂t x - <Y|∂t u> X x ∂s x>``; where ``∂u = W ∂x`` with W the shape operator
(``dN = W t``, curvlab's sign), it is ``∫ Xᵀ W Y dA``, so ``M / mu0`` is W and an outward sphere
of radius r gives ``+1/r``.

At vertex p with the ball B of radius ``r(p)`` (range Rk: ``k * mesh.longest_edge[p]``, as csm;
or a fixed radius), every measure is summed over the triangles touching p or a vertex of its
support (:func:`curv.geometry.neighbourhood.ball_support`), each weighted by the **fraction of its area
inside B**, ``area(t ∩ B) / area(t)``, computed exactly (triangle ∩ disc of B in its plane, as
in :mod:`curv.estimators.csm`). Then

    H = mu1 / (2 mu0),   K = mu2 / mu0,   k1, k2 = H ± sqrt(max(H² - K, 0)),
    d1, d2: eigenvectors of the symmetric part of M / mu0 in the tangent plane of the vertex normal.

The principal curvatures come from mu1 and mu2 by default, not from the eigenvalues of M (CGAL's
choice; ``from_measures=False`` here): M is a sum of tensors that lie in the planes of the faces,
and projecting it onto one tangent plane loses the part of each face tensor that the tilt of the
face turns away from it, a bias that grows with the ball (median e_rel at R4 on a torus 0.060
from M, 0.006 from mu1 and mu2; on an icosphere 0.026 and 0.0000: mu1 and mu2 are exact on a
sphere with exact normals). On the paper's clean Monge patches the two agree within 15 %. With
vertex noise the eigenvalues of M are the more robust (K from mu2 is the noisier): with Gaussian
noise of 0.1 mean edge lengths on the 3169-vertex patches, median e_rel at R4 0.09-0.25 from M
against 0.15-0.68 from mu1 and mu2. :func:`icc_mean_gaussian` returns H and K themselves.

The module reads as the paper's steps:

1. **support**: the triangles touching p or a vertex of its support, walked by the pass that runs
   csm and icc (:mod:`curv.estimators.clipping_pair`), which also clips the triangles crossing the
   sphere (:mod:`curv.estimators._ball_clipping`);
2. **rows**: each triangle's measures (:func:`face_measures`) and every vertex's third of the
   measures of its triangles (:func:`star_measures`);
3. **sum**: over the support, the thirds corrected at the sphere (:func:`add_crossings`), or, where
   a vertex's thirds are not exact, the triangles one by one (:func:`walk_sums`);
4. **measures to curvatures**: H, K and the tensor M / mu0 in the vertex's tangent plane (:func:`finish`).

Summed over a support, the thirds hold every triangle inside the ball whole. Only the triangles
that cross the sphere are clipped: each is found once, as its one halfedge v -> w leaving the ball
(:func:`~curv.estimators._ball_mesh.crossing_faces`), and its thirds in the sum are replaced by
its area fraction. A support holding a non-manifold vertex, a degenerate triangle or one without
measures (with ``features``, one touching a crease) is summed the long way, face by face. For a
region of less than 5 % of the mesh (:data:`~curv.estimators._ball_sums.REGION_WALK_SHARE`), the
measures and the thirds are computed only for the triangles and vertices its supports touch.
With ``features``, the triangles touching a crease vertex are left out of the sums: their normal
field would use the crease vertex's normal (or its side's), tilted by O(h) from the surface's,
which the normal differences turn into an O(1) error next to the crease.

Validity: a ball that reaches a border sees one side of the surface only, so vertices whose
support holds a border vertex are BORDER (as csm); a degenerate triangle or a vertex without
normal in a touched triangle makes the centre DEGENERATE; non-manifold vertices in the support
NONMANIFOLD; an empty or non-finite sum SINGULAR. Triangle meshes only (the paper's polygon form
is not implemented).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..core.jit import jit, jit_inlined, jit_parallel, launch, prange, run_to_end
from ..core.mesh import Mesh
from ..core.result import Principal
from ..core.validity import Reason
from ..geometry.neighbourhood import coordinate_columns
from ._ball_clipping import face_in_ball_area
from ._ball_mesh import element_list
from ._ball_sums import CLIPPING_PASS, DEGENERATE_BIT, add_row, support_reason, touches, vertex_normal
from ..core.small_linalg import sym3_bilinear
from ._frames import tangent_frame
from ._principal import store_principal
from ._output_rows import LevelOutputs, flat_levels, nan_row
from .registry import SHARED_PASSES, EstimatorSpec, register

__all__ = ["iter_icc", "icc_terms", "IccTerms", "icc_mean_gaussian", "face_measures", "star_measures", "walk_sums",
           "add_crossings", "finish", "IccPrincipal", "IccOutputs", "MEASURES"]

EPS = float(np.finfo(np.float64).eps)

MEASURES = 9
"""Columns of :func:`face_measures`: mu0, mu1, mu2 and the symmetric part of M (xx, xy, xz, yy, yz, zz)."""


# ---------------------------------------------------------------------------- 2. rows: the measures of a triangle
@jit_parallel
def _face_measures(ids, tri, coords, normals, degenerate, out):
    x, y, z = coords
    for index in prange(ids.size):
        f = ids[index]
        i, j, k = tri[f, 0], tri[f, 1], tri[f, 2]
        # edges e = x_j - x_i, g = x_k - x_i and the normal differences du = u_j - u_i, dv = u_k - u_i
        ex, ey, ez = x[j] - x[i], y[j] - y[i], z[j] - z[i]
        gx, gy, gz = x[k] - x[i], y[k] - y[i], z[k] - z[i]
        uix, uiy, uiz = normals[i, 0], normals[i, 1], normals[i, 2]
        ujx, ujy, ujz = normals[j, 0], normals[j, 1], normals[j, 2]
        ukx, uky, ukz = normals[k, 0], normals[k, 1], normals[k, 2]
        dux, duy, duz = ujx - uix, ujy - uiy, ujz - uiz
        dvx, dvy, dvz = ukx - uix, uky - uiy, ukz - uiz
        bx = (uix + ujx + ukx) / 3.0  # ū
        by = (uiy + ujy + uky) / 3.0
        bz = (uiz + ujz + ukz) / 3.0
        # mu0 = 1/2 <ū | e x g>
        cx, cy, cz = ey * gz - ez * gy, ez * gx - ex * gz, ex * gy - ey * gx
        mu0 = 0.5 * (bx * cx + by * cy + bz * cz)
        # mu1 = 1/2 <ū | du x g + e x dv>
        sx = duy * gz - duz * gy + ey * dvz - ez * dvy
        sy = duz * gx - dux * gz + ez * dvx - ex * dvz
        sz = dux * gy - duy * gx + ex * dvy - ey * dvx
        mu1 = 0.5 * (bx * sx + by * sy + bz * sz)
        # mu2 = 1/2 det(u_i, u_j, u_k)
        mu2 = 0.5 * (uix * (ujy * ukz - ujz * uky) + uiy * (ujz * ukx - ujx * ukz) + uiz * (ujx * uky - ujy * ukx))
        # M = 1/2 [(g x ū) duᵀ - (e x ū) dvᵀ]
        px, py, pz = gy * bz - gz * by, gz * bx - gx * bz, gx * by - gy * bx
        qx, qy, qz = ey * bz - ez * by, ez * bx - ex * bz, ex * by - ey * bx
        m00 = 0.5 * (px * dux - qx * dvx)
        m11 = 0.5 * (py * duy - qy * dvy)
        m22 = 0.5 * (pz * duz - qz * dvz)
        m01 = 0.25 * (px * duy - qx * dvy + py * dux - qy * dvx)  # symmetric part
        m02 = 0.25 * (px * duz - qx * dvz + pz * dux - qz * dvx)
        m12 = 0.25 * (py * duz - qy * dvz + pz * duy - qz * dvy)
        out[f, 0], out[f, 1], out[f, 2] = mu0, mu1, mu2
        out[f, 3], out[f, 4], out[f, 5] = m00, m01, m02
        out[f, 6], out[f, 7], out[f, 8] = m11, m12, m22
        if degenerate[f]:
            out[f, 0] = math.nan  # a degenerate face makes every centre touching it DEGENERATE


def face_measures(mesh: Mesh, normals: np.ndarray, ids: np.ndarray | None = None) -> np.ndarray:
    """The corrected curvature measures of every triangle with the vertex normals interpolated.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    normals : (n, 3) float64
        Unit vertex normals (NaN rows allowed: their triangles get NaN measures).
    ids : (k,) int64, optional
        Compute only these triangles (a region's); the other rows are left unset.

    Returns
    -------
    (m, 9) float64
        mu0, mu1, mu2, then the symmetric part of the anisotropic measure M as xx, xy, xz, yy, yz,
        zz (see the module notes). NaN rows where a corner has no normal or the face is
        degenerate.
    """
    tri = np.ascontiguousarray(mesh.triangles)
    out = np.empty((tri.shape[0], MEASURES))
    launch(_face_measures, element_list(tri.shape[0], ids), tri, coordinate_columns(mesh),
           np.asarray(normals, dtype=np.float64), mesh.degenerate_faces, out)
    return out


@jit
def _row_is_finite(a, r):
    for c in range(a.shape[1]):
        if not math.isfinite(a[r, c]):
            return False
    return True


# ---------------------------------------------------------------------------- 2. rows: every vertex's third
@jit_parallel
def _star_measures(ids, corners, measures, flags, out):
    vc_ptr, vc, tri = corners
    degenerate, nonmanifold, crease = flags
    star, clean = out
    for i in prange(ids.size):
        v = ids[i]
        ok = not nonmanifold[v]
        # the nine sums in registers, each added to in corner order (as a row of the output would be)
        s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = s8 = 0.0
        for j in range(vc_ptr[v], vc_ptr[v + 1]):
            f = vc[j] // 3
            if degenerate[f] or not _row_is_finite(measures, f):
                ok = False
                continue
            if touches(crease, tri, f):
                ok = False  # the feature path leaves this face out
            s0 += measures[f, 0] / 3.0
            s1 += measures[f, 1] / 3.0
            s2 += measures[f, 2] / 3.0
            s3 += measures[f, 3] / 3.0
            s4 += measures[f, 4] / 3.0
            s5 += measures[f, 5] / 3.0
            s6 += measures[f, 6] / 3.0
            s7 += measures[f, 7] / 3.0
            s8 += measures[f, 8] / 3.0
        star[v, 0], star[v, 1], star[v, 2] = s0, s1, s2
        star[v, 3], star[v, 4], star[v, 5] = s3, s4, s5
        star[v, 6], star[v, 7], star[v, 8] = s6, s7, s8
        clean[v] = ok


def star_measures(mesh: Mesh, measures: np.ndarray, ids: np.ndarray | None = None,
                  crease: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A third of the measures of every face at each vertex: what the centres whose support holds it share.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    measures : (m, 9) float64
        :func:`face_measures`.
    ids, crease : optional
        A region's vertices, the crease vertices: as in :func:`curv.estimators.csm.star_terms`.

    Returns
    -------
    star : (n, 9) float64
        The sum over the faces at v of a third of their measures.
    clean : (n,) bool
        v's sums are exact: v is manifold (its support search expands through it, so every face
        at v inside the ball has all its corners in the support) and no face at v is degenerate
        or without measures, or touching a crease vertex.
    """
    n = mesh.n_vertices
    vc_ptr, vc = mesh.vertex_corners
    star = np.empty((n, MEASURES))
    clean = np.empty(n, np.bool_)
    crease = np.zeros(n, np.bool_) if crease is None else crease
    launch(_star_measures, element_list(n, ids), (vc_ptr, vc, np.ascontiguousarray(mesh.triangles)), measures,
           (mesh.degenerate_faces, mesh.nonmanifold_vertices, crease), (star, clean))
    return star, clean


class IccTerms(NamedTuple):
    """icc's per-mesh terms (:func:`icc_terms`)."""

    measures: np.ndarray
    """(m, 9) float64: :func:`face_measures`."""
    star: np.ndarray
    """(n, 9) float64: :func:`star_measures`."""
    clean: np.ndarray
    """(n,) bool: the vertex's star sums are exact."""
    walk: bool
    """Some support is summed face by face."""
    from_measures: bool
    """k1, k2 from mu1 and mu2 (else from M's eigenvalues)."""


def icc_terms(mesh: Mesh, normals: np.ndarray, touched: tuple, crease: np.ndarray, from_measures: bool = True
              ) -> IccTerms:
    """icc's per-mesh terms: :func:`face_measures` and :func:`star_measures` (a region's only,
    ``touched``: :func:`~curv.estimators._ball_sums.ball_inputs`), and whether a support is
    summed face by face. ``normals`` (n, 3) float64 C-contiguous."""
    measures = face_measures(mesh, normals, touched[1])
    star, clean = star_measures(mesh, measures, touched[0], crease)
    walk = not (clean.all() if touched[0] is None else clean[touched[0]].all())
    return IccTerms(measures, star, clean, walk, bool(from_measures))


# ---------------------------------------------------------------------------- 3. the sums over a support
@jit
def walk_sums(centre, support, mesh, walk, measures, fstamp, sums):
    """The nine sums of a centre whose support is not clean (or that stops at creases), face by face.

    Parameters
    ----------
    centre : (p, r2, mark)
        The centre vertex, its squared radius and this walk's stamp
        (:func:`~curv.estimators._ball_sums.level_mark`; the stamps start zeroed).
    support : (queue, count)
        ``queue[:count]`` the support.
    mesh : BallMesh
    walk : BallWalk
        Its creases.
    measures : (m, 9) float64
    fstamp : (m,) int
        The thread's face stamps.
    sums : (9,) float64
        Added to.

    Returns
    -------
    int
        The DEGENERATE_BIT if a degenerate face or a face without measures was met.
    """
    p, r2, mark = centre
    queue, count = support
    at = (mesh.x[p], mesh.y[p], mesh.z[p])
    hit = 0
    for i in range(count):
        v = queue[i]
        for j in range(mesh.vc_ptr[v], mesh.vc_ptr[v + 1]):
            f = mesh.vc[j] // 3  # the corners of triangle f are 3f, 3f + 1, 3f + 2
            if fstamp[f] == mark:
                continue
            fstamp[f] = mark
            if mesh.degenerate[f]:
                hit |= DEGENERATE_BIT
                continue
            if walk.cut and touches(walk.crease, mesh.tri, f):
                continue  # the surface ends at a crease for this centre: its faces are left out
            if not _row_is_finite(measures, f):
                hit |= DEGENERATE_BIT  # a corner without a normal
                continue
            # weight: the fraction of the face's area inside B
            inside = face_in_ball_area(mesh, f, at, r2)
            w = min(inside / mesh.area[f], 1.0)
            if w > 0.0:
                add_row(sums, w, measures, f)
    return hit


@jit_inlined
def add_crossings(sums, crossings, leaving, mesh, measures):
    """Correct a support's star sums (9,) for the ``leaving`` faces that cross the sphere out of a
    vertex (:func:`~curv.estimators._ball_mesh.crossing_faces`'s scratch and count): each face's
    one or two thirds of its measures become the fraction of its area inside the ball."""
    out_h, _, _, out_area, out_in, _ = crossings
    for a in range(leaving):
        f = out_h[a] // 3
        add_row(sums, min(out_area[a] / mesh.area[f], 1.0) - out_in[a] * (1.0 / 3.0), measures, f)


# ---------------------------------------------------------------------------- 4. measures to curvatures
@jit
def finish(at, sums, hit, normals, from_measures, rows):
    """Centre p's curvatures from its nine sums, into row ``row`` of ``rows``.

    Parameters
    ----------
    at : (p, row)
        The centre and its row in ``rows`` (the pass's outputs hold every level's rows:
        :class:`~curv.estimators.clipping_pair.IccPass`).
    sums : (9,) float64
        mu0, mu1, mu2 and M's upper triangle, summed over the ball.
    hit : int
        The support's flags (:func:`~curv.estimators._ball_sums.support_reason`).
    normals : (n, 3) float64
    from_measures : bool
        k1, k2 from H and K (else M's eigenvalues).
    rows : (k1, k2, d1, d2, mean, gaussian, reason)
        The outputs (:attr:`IccOutputs.flat_rows`).
    """
    p, row = at
    k1, k2, d1, d2, mean, gaussian, reason = rows
    nx, ny, nz, normal_ok = vertex_normal(normals, p)
    mean[row] = gaussian[row] = math.nan
    mu0, s1, s2 = sums[0], sums[1], sums[2]
    total = 0.0
    for c in range(MEASURES):
        total += sums[c]
    singular = not (mu0 > 0.0 and math.isfinite(total))
    if not singular and normal_ok:
        h = mean[row] = 0.5 * s1 / mu0
        kk = gaussian[row] = s2 / mu0
        # W = M / mu0 in the tangent frame (U, V) of the vertex normal
        ux, uy, uz, vx, vy, vz = tangent_frame(nx, ny, nz)
        m = (sums[3], sums[4], sums[5], sums[6], sums[7], sums[8])  # M's upper triangle
        e = sym3_bilinear(m, (ux, uy, uz), (ux, uy, uz)) / mu0
        f_ = sym3_bilinear(m, (ux, uy, uz), (vx, vy, vz)) / mu0
        g = sym3_bilinear(m, (vx, vy, vz), (vx, vy, vz)) / mu0
        store_principal(row, (e, f_, g), (ux, uy, uz, vx, vy, vz), k1, k2, d1, d2)
        if from_measures:
            # k = H ± sqrt(H² - K); the directions stay those of M. A discriminant within
            # rounding of H² and K is an umbilic: its square root would turn 1e-16 into 1e-8.
            # H and K are sums of a few hundred clipped terms, rounded to tens of EPS.
            disc = h * h - kk
            if disc <= 64.0 * EPS * (h * h + abs(kk)):
                disc = 0.0
            rad = math.sqrt(disc)
            k1[row] = h + rad
            k2[row] = h - rad
        if not (math.isfinite(k1[row]) and math.isfinite(k2[row])):
            singular = True
    else:
        nan_row(row, k1, k2, d1, d2)
    reason[row] = support_reason(singular, hit, normal_ok)


@dataclass
class IccPrincipal(Principal):
    """icc's :class:`~curv.core.result.Principal` with its mean and Gaussian curvature from the
    measures (``mu1 / (2 mu0)``, ``mu2 / mu0``; NaN where the estimate is not usable)."""

    mean: np.ndarray | None = None
    gaussian: np.ndarray | None = None


class IccOutputs(LevelOutputs):
    """icc's outputs for ``levels`` radii: :class:`~curv.estimators._output_rows.LevelOutputs` and
    ``mean``, ``gaussian`` (levels, n), uninitialised (written at each centre before its sums)."""

    def __init__(self, levels: int, n: int):
        super().__init__(levels, n)
        self.mean, self.gaussian = np.empty((levels, n)), np.empty((levels, n))

    @property
    def rows(self) -> tuple:
        """``(k1, k2, d1, d2, mean, gaussian, reason)``."""
        return self.k1, self.k2, self.d1, self.d2, self.mean, self.gaussian, self.reason

    @property
    def flat_rows(self) -> tuple:
        """:attr:`rows` with the levels' rows one after another (views)."""
        return flat_levels(self.rows)

    def principal(self, level: int) -> IccPrincipal:
        return IccPrincipal(k1=self.k1[level], k2=self.k2[level], d1=self.d1[level], d2=self.d2[level],
                            reason=self.reason[level], mean=self.mean[level], gaussian=self.gaussian[level])


# ---------------------------------------------------------------------------- the estimator
def iter_icc(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
             from_measures: bool = True, centres: np.ndarray | None = None, features=None):
    """Principal curvatures from the interpolated corrected curvature measures in a ball per vertex.

    Parameters
    ----------
    mesh : Mesh
        Consistently oriented triangle mesh.
    normals : (n, 3) float64
        Unit vertex normals: the corrected normal field interpolates them over each triangle.
    radii : (n,) or (levels, n) float64
        Ball radius of every vertex (:func:`curv.core.ranges.ball_radii` with ``uses_normals=False``),
        or of every vertex at each of several levels, ascending per vertex: one walk per centre
        serves them all, as in :func:`curv.estimators.csm.iter_csm` (results to rounding of the
        single-radius calls'; a list of one Principal per level).
    chunk : int, optional
        Vertices per kernel call; default adaptive (:func:`curv.core.jit.iter_chunks`).
    from_measures : bool
        k1, k2 from H and K (mu1, mu2; default) or from the eigenvalues of M (as CGAL).
    centres : (c,) int64, optional
        The vertices to estimate (default all).
    features : curv.core.features.FeatureSet, optional
        The ball stops at creases, and the faces touching a crease vertex are left out of the sums
        (a crease vertex's normal, or its side's, tilts them: an error that does not shrink with
        the mesh).

    It yields the fraction done and returns the :class:`IccPrincipal`
    (:data:`~curv.estimators.registry.EstimatorFunction`):
    ``k1 >= k2``, reasons as in the module notes.
    """
    out = yield from SHARED_PASSES[CLIPPING_PASS](mesh, normals, radii, ("icc",), chunk=chunk, centres=centres,
                                                  features=features, options={"icc": {"from_measures": from_measures}})
    return out["icc"] if np.ndim(radii) == 2 else out["icc"][0]


def icc_mean_gaussian(mesh: Mesh, normals: np.ndarray, radii: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean and Gaussian curvature from the corrected measures mu1 and mu2 (not from M).

    Parameters as in :func:`iter_icc`.

    Returns
    -------
    mean, gaussian : (n,) float64
        ``H = mu1 / (2 mu0)`` and ``K = mu2 / mu0``; NaN where ``reason`` is not OK.
    reason : (n,) uint8
    """
    principal = run_to_end(iter_icc(mesh, normals, radii))
    mean, gaussian = principal.mean, principal.gaussian
    bad = principal.reason != Reason.OK
    mean[bad] = np.nan
    gaussian[bad] = np.nan
    return mean, gaussian, principal.reason


register(EstimatorSpec(
    name="icc", in_paper=False, title="Interpolated corrected curvature measures", ranges=(1, 2, 3, 4),
    # `curv estimate torus10M.ply -m icc -r 2`: 8.22 GB peak, 394 B a unit above the base and stamps; +35 % as mru
    function=iter_icc, extra_bytes_per_unit=180.0,
    triangles_only=True, uses_normals=False, closed_ring=True,
    reference="Lachaud, Romon, Thibert & Coeurjolly 2020, Interpolated corrected curvature measures for "
              "polygonal surfaces (SGP)",
    summary="curvature measures of the linearly interpolated vertex normals, summed over the area "
            "fraction of each triangle in a ball; H, K from the mean and Gaussian measures, directions "
            "from the anisotropic one",
    kernels=(_face_measures, _star_measures), takes_levels=True,
    shared_pass=CLIPPING_PASS,
    options={"from_measures": (True, False)},
))
