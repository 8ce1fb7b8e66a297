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

The measures of the triangles are computed once per call, and a third of them summed at each vertex
(:func:`star_measures`; the kernel is csm's too, :mod:`curv.estimators._clipped_sums`, and run
together, :mod:`curv.estimators.clipping_pair`, the two share the search and the clips); summed over a support, these hold every triangle inside the ball whole,
by thirds. Only the triangles that cross the sphere are clipped: each is found once, as its one
halfedge v -> w leaving the ball (v in the support; each vertex's ring read once,
:func:`curv.estimators._ball_clipping.corner_rings`), and its thirds in the sum are replaced by its
area fraction (:func:`curv.estimators._ball_clipping.crossing_area`). Support vertices whose
every edge stays inside the ball are not walked. A support holding a non-manifold vertex, a
degenerate triangle or one without measures (with ``features``, one touching a crease) is summed
the long way, face by face. For a region of less than 5 % of the mesh
(:data:`~curv.estimators._ball_clipping.REGION_WALK_SHARE`), the measures and the thirds are
computed only for the triangles and vertices its supports touch.
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

import numpy as np

from ..core.jit import jit_parallel, launch, prange, run_to_end
from ..core.mesh import Mesh
from ..geometry.neighbourhood import coordinate_columns
from ..core.validity import Reason
from ._ball_clipping import _corner_rings, clipping_inputs, corner_rings, element_list, touches
from ._clipped_sums import CLIPPING_PASS, MEASURES, IccTerms, _clip_chunk, _row_is_finite, run_clipping
from .registry import EstimatorSpec, register

__all__ = ["iter_icc", "icc_terms", "icc_mean_gaussian", "face_measures", "star_measures"]


@jit_parallel
def _face_measures(ids, tri, x, y, z, normals, degenerate, out):
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
    x, y, z = coordinate_columns(mesh)
    out = np.empty((tri.shape[0], MEASURES))
    launch(_face_measures, element_list(tri.shape[0], ids), tri, x, y, z,
           np.asarray(normals, dtype=np.float64), mesh.degenerate_faces, out)
    return out


@jit_parallel
def _star_measures(ids, vc_ptr, vc, tri, measures, degenerate, nonmanifold, crease, star, clean):
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
    launch(_star_measures, element_list(n, ids), vc_ptr, vc, np.ascontiguousarray(mesh.triangles), measures,
           mesh.degenerate_faces, mesh.nonmanifold_vertices, crease, star, clean)
    return star, clean


def icc_terms(mesh: Mesh, normals: np.ndarray, touched: tuple, crease: np.ndarray, from_measures: bool = True
              ) -> IccTerms:
    """icc's per-mesh terms: :func:`face_measures` and :func:`star_measures` (a region's only,
    ``touched``: :func:`~curv.estimators._ball_clipping.clipping_inputs`), and whether a support is
    summed face by face. ``normals`` (n, 3) float64 C-contiguous."""
    measures = face_measures(mesh, normals, touched[1])
    star, clean = star_measures(mesh, measures, touched[0], crease)
    walk = not (clean.all() if touched[0] is None else clean[touched[0]].all())
    return IccTerms(measures, star, clean, walk, from_measures)


def _iter_measures(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, chunk: int | None,
                   from_measures: bool = True, centres: np.ndarray | None = None, features=None):
    """Run the kernel over chunks of vertices at one or several levels of radii (``radii`` (n,) or
    (levels, n), :func:`iter_icc`); returns ``(LevelOutputs, mean (levels, n), gaussian (levels, n))``."""
    tri, centres, x, y, z, indptr, indices, cut, crease, radii, touched = yield from clipping_inputs(
        mesh, centres, radii, features)
    normals = np.asarray(normals, dtype=np.float64)  # the cached normals are column-major: read as they are
    terms = icc_terms(mesh, normals, touched, crease, from_measures)
    after, link = corner_rings(mesh, touched[0])
    yield 0.0
    _, out = yield from run_clipping(mesh, centres, radii, (tri, x, y, z, indptr, indices, cut, crease, after, link),
                                     normals, icc=terms, chunk=chunk)
    return out


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

    It yields the fraction done and returns the :class:`~curv.core.result.Principal` (:data:`~curv.estimators.registry.EstimatorFunction`):
    ``k1 >= k2``, reasons as in the module notes.
    """
    out, _, _ = yield from _iter_measures(mesh, normals, radii, chunk, from_measures, centres, features)
    if np.ndim(radii) == 2:
        return [out.principal(level) for level in range(out.k1.shape[0])]
    return out.principal(0)


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
    out, mean, gaussian = run_to_end(_iter_measures(mesh, normals, radii, None))
    principal, mean, gaussian = out.principal(0), mean[0], gaussian[0]
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
    kernels=(_face_measures, _star_measures, _corner_rings, _clip_chunk), takes_levels=True,
    shared_pass=CLIPPING_PASS,
    options={"from_measures": (True, False)},
))
