"""Osculating jet fitting (Cazals & Pouget, SGP 2003), over the range support.

At each vertex p, with support S(p) = p and the vertices of its ball (:mod:`curv.geometry.neighbourhood`):

1. **Frame.** PCA of S(p): the eigenvector of the smallest eigenvalue of the covariance about the
   centroid is the height axis ``e3`` (turned to agree with the given vertex normal), the largest
   gives ``e1``, ``e2 = e3 x e1``. The origin is p.
2. **Fit.** In coordinates divided by ``h`` (the largest distance from p to its support, for
   conditioning), least squares of the height ``w = J(u, v) = sum_{i+j<=d} J_ij u^i v^j`` over S(p):
   ``N_d = (d+1)(d+2)/2`` unknowns, constant and linear terms included, so the jet finds its own
   tangent plane. With ``weights="smooth"`` a support point at distance d counts with
   ``w = (1 - d²/r²)^4`` (r the ball radius; 1 at the centre, 0 at the edge with its first three
   derivatives, as in MLS and APSS) in the PCA and in the fit (weighted least squares); the default
   ``"uniform"`` counts every point alike. Normal equations, Jacobi-scaled, Cholesky; fewer than ``N_d`` points is
   ``TOO_FEW_NEIGHBOURS``, an estimated reciprocal condition number below :data:`RCOND` is
   ``SINGULAR``.
3. **Differential quantities** of the graph ``(u, v, J(u, v))`` at ``(0, 0)``: the jet normal
   ``n = (-J_10, -J_01, 1) / sqrt(1 + J_10^2 + J_01^2)``, first fundamental form ``E = 1 + J_10^2``,
   ``F = J_10 J_01``, ``G = 1 + J_01^2``, second ``L = 2 J_20 / |.|``, ``M = J_11 / |.|``,
   ``N = 2 J_02 / |.|``; the shape operator ``I^-1 II`` in an orthonormal tangent basis, its
   eigenpairs the principal curvatures (sign of the house: ``W = -II`` for a graph along ``n``,
   so an outward sphere gives +1/r) and directions, mapped back to 3-D and to unscaled units.
4. **Standard errors** of k1, k2 from the fit's residuals, propagated through step 3 to first
   order (:func:`jet_se`, docs/UNCERTAINTY.md).

Which normal: the given vertex normal (Max by default) only orients the fit and is the normal the
result reports; k1, k2 are the jet's own (its normal ``n``). The directions are carried from the
jet's tangent plane to the reported normal's by the smallest rotation taking ``n`` to it, so they are
tangent to the reported normal. The angle between the two is about the Max normal's own error:
0.01-0.07 degrees (median) on the study's clean meshes, 5-9 degrees at its 100 % noise. :func:`curv.fitted_normals.fitted_normals` gives the jet normals.

Width: with ``width="adaptive"`` the given ball is the widest of several candidate fits (narrower
balls at the same degree, then the degree-2 smooth fit over the whole ball), chosen per vertex by
the intersection of their confidence intervals (:mod:`curv.estimators.jet_width`); the default
``"fixed"`` is the single fit above.

Works on any polygon mesh and on borders (a one-sided fit there).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.errors import EstimatorError
from ..core.filled import filled
from ..core.jit import iter_chunks, jit, jit_parallel, launch, prange, threads
from ..core.mesh import Mesh
from ..geometry.neighbourhood import (all_centres, ball_support, blocked_vertices, coordinate_columns, expansion_adjacency,
                                      new_scratch, start_ball_support, widen_ball_support)
from ..core.result import Principal
from ..core.validity import DEGENERATE, OK, SINGULAR, TOO_FEW
from ._local_fit import factor_whiten, noise_variance, principal_gradients, row_dot, slice_bounds
from ._small_linalg import solve_spd_scaled, sym2_eigen, sym3_eigen
from .jet_width import DEFAULT_WIDTH, WIDTHS, iter_adaptive_jet
from .registry import EstimatorSpec, register

__all__ = ["iter_jet", "DEFAULT_DEGREE", "DEGREES", "DEFAULT_WEIGHTS", "WEIGHTS", "DEFAULT_WIDTH", "WIDTHS", "RCOND",
           "unknowns", "jet_normals", "smooth_weight"]

DEGREES = (2, 3, 4)
"""The jet degrees offered."""

DEFAULT_DEGREE = 2
"""Degree of :func:`iter_jet` unless told otherwise (``curv.estimate(..., degree=d)``). Measured on
the study's protocol meshes (docs/ACCURACY.md): degree 2 is the only one that fits a triangle 1-ring
(R1), and on noisy meshes it is as accurate as degree 3 and 4x more than degree 4 at R4; on clean
meshes degree 4 at R2-R3 is 100-300x more accurate than degree 2."""

MAX_UNKNOWNS = 15
"""Unknowns of a degree-4 jet."""

RCOND = 1e-12
"""A fit whose scaled normal matrix has an estimated reciprocal condition number below this (a
least-squares matrix condition above 1e6) is ``SINGULAR``."""

MIN_NORMAL_COSINE = 0.2
"""The PCA normal and the jet's normal must be within about 78 degrees of the vertex normal, or the fit
does not describe the surface at the vertex (``DEGENERATE``)."""


WEIGHTS = ("uniform", "smooth")
"""The fit weightings offered (``curv.estimate(..., weights=...)``): ``"uniform"`` (the default)
counts every support point alike; ``"smooth"`` weighs a point at distance d from the centre by
``(1 - d²/r²)^4``, r the ball radius (:func:`smooth_weight`), as MLS and APSS fits do."""

DEFAULT_WEIGHTS = "uniform"


@jit
def smooth_weight(d2, r2):
    """Weight of a support point at squared distance ``d2``: 1 when ``r2 <= 0`` (uniform), else
    ``(1 - d2/r2)^4`` inside the ball and 0 outside it.

    The weight and its first three derivatives fall to zero at the ball's edge, so a point entering
    or leaving the ball does not jump the fit: a low-pass on noise that the uniform fit lacks.
    """
    if r2 <= 0.0:
        return 1.0
    t = 1.0 - d2 / r2
    if t <= 0.0:
        return 0.0
    t2 = t * t
    return t2 * t2


def unknowns(degree: int) -> int:
    """``N_d = (d+1)(d+2)/2``: coefficients of a bivariate polynomial of degree d."""
    return (degree + 1) * (degree + 2) // 2


@jit
def _scratch():
    """Per-thread scratch of :func:`fit_jet`: normal matrix, vectors, 3x3 work."""
    m = np.empty((MAX_UNKNOWNS, MAX_UNKNOWNS))
    vec = np.empty((5, MAX_UNKNOWNS))  # rhs, coefficients, scaling, 2 work rows
    cov = np.empty((3, 3))
    frame = np.empty((3, 3))
    evec = np.empty((4, 3))  # eigenvectors (columns of the first 3 rows), eigenvalues (last row)
    return m, vec, cov, frame, evec


@jit
def _monomials(u, v, degree, out):
    """``out[1, t(t+1)/2 + j] = u^(t-j) v^j`` for total degree t = 0..degree, j = 0..t."""
    out[1, 0] = 1.0
    idx = 1
    for t in range(1, degree + 1):
        # the monomials of degree t from those of degree t-1: times u, and the last one also times v
        prev = idx - t
        for j in range(t):
            out[1, idx + j] = out[1, prev + j] * u
        out[1, idx + t] = out[1, prev + t - 1] * v
        idx += t + 1


@jit
def fit_jet(p, count, queue, x, y, z, normals, degree, m, vec, cov, frame, evec, r2=0.0):
    """Fit the degree-``degree`` jet of the support of ``p`` (steps 1 and 2 of the module notes).

    Parameters
    ----------
    p : int
        Centre vertex; ``queue[:count]`` is its support with ``queue[0] == p``.
    x, y, z : (n,) float64
        Vertex coordinates.
    normals : (n, 3) float64
        ``normals[p]`` orients the fit (the vertex normal); NaN gives ``DEGENERATE``.
    degree : int
    m, vec, cov, frame, evec
        Per-thread scratch from :func:`_scratch`. On success ``frame`` rows are ``e1, e2, e3``
        (world coordinates) and ``vec[1, :N_d]`` holds the coefficients ``J`` in the order of
        :func:`_monomials`, for coordinates divided by the returned ``h``.
    r2 : float, optional
        0 (the default): every support point counts alike. Positive: the squared ball radius of the
        smooth weights ``w = (1 - d²/r2)^4`` (:func:`smooth_weight`), applied to the PCA (weighted
        centroid and covariance) and to the height fit.

    Returns
    -------
    reason : int
        ``Reason`` code (``OK`` when fitted).
    h : float
        The coordinate scale: largest distance from p to a support vertex.
    ww : float
        The sum of the (weighted) squared heights ``bᵀWb`` (scaled coordinates), for the residuals.
    """
    nd = (degree + 1) * (degree + 2) // 2  # unknowns(degree); the registry's min_neighbours is nd - 1
    if count < nd:
        return TOO_FEW, 0.0, 0.0
    rx, ry, rz = normals[p, 0], normals[p, 1], normals[p, 2]
    if not (math.isfinite(rx) and math.isfinite(ry) and math.isfinite(rz)):
        return DEGENERATE, 0.0, 0.0
    px, py, pz = x[p], y[p], z[p]
    # centroid c and covariance sum (q - c)(q - c)^T, from offsets to p for accuracy
    cx = cy = cz = 0.0
    h2 = 0.0
    total = 0.0
    for i in range(count):
        q = queue[i]
        dx, dy, dz = x[q] - px, y[q] - py, z[q] - pz
        d2 = dx * dx + dy * dy + dz * dz
        wt = smooth_weight(d2, r2)
        cx += wt * dx
        cy += wt * dy
        cz += wt * dz
        total += wt
        h2 = max(h2, d2)
    if not (h2 > 0.0 and total > 0.0):
        return DEGENERATE, 0.0, 0.0
    cx /= total
    cy /= total
    cz /= total
    for a in range(3):
        for b in range(3):
            cov[a, b] = 0.0
    for i in range(count):
        q = queue[i]
        dx, dy, dz = x[q] - px, y[q] - py, z[q] - pz
        wt = smooth_weight(dx * dx + dy * dy + dz * dz, r2)
        dx, dy, dz = dx - cx, dy - cy, dz - cz
        cov[0, 0] += wt * dx * dx
        cov[0, 1] += wt * dx * dy
        cov[0, 2] += wt * dx * dz
        cov[1, 1] += wt * dy * dy
        cov[1, 2] += wt * dy * dz
        cov[2, 2] += wt * dz * dz
    cov[1, 0] = cov[0, 1]
    cov[2, 0] = cov[0, 2]
    cov[2, 1] = cov[1, 2]
    sym3_eigen(cov, evec)
    # The support must be a height field over its PCA plane: a plane far from the vertex normal
    # (a support wrapping round a thin rim) gives an arbitrary fit whose sign flips with rounding.
    along = evec[0, 0] * rx + evec[1, 0] * ry + evec[2, 0] * rz
    if not abs(along) >= MIN_NORMAL_COSINE * math.sqrt(rx * rx + ry * ry + rz * rz):
        return DEGENERATE, 0.0, 0.0
    # e3: least variance (the height axis), turned towards the reference normal; e1: most variance
    sign = 1.0 if along >= 0.0 else -1.0
    for a in range(3):
        frame[2, a] = sign * evec[a, 0]
        frame[0, a] = evec[a, 2]
    frame[1, 0] = frame[2, 1] * frame[0, 2] - frame[2, 2] * frame[0, 1]
    frame[1, 1] = frame[2, 2] * frame[0, 0] - frame[2, 0] * frame[0, 2]
    frame[1, 2] = frame[2, 0] * frame[0, 1] - frame[2, 1] * frame[0, 0]
    # normal equations of the height fit in coordinates divided by h
    inv_h = 1.0 / math.sqrt(h2)
    ww = 0.0
    for a in range(nd):
        vec[0, a] = 0.0
        for b in range(a, nd):
            m[a, b] = 0.0
    for i in range(count):
        q = queue[i]
        dx, dy, dz = x[q] - px, y[q] - py, z[q] - pz
        wt = smooth_weight(dx * dx + dy * dy + dz * dz, r2)
        dx, dy, dz = dx * inv_h, dy * inv_h, dz * inv_h
        u = dx * frame[0, 0] + dy * frame[0, 1] + dz * frame[0, 2]
        v = dx * frame[1, 0] + dy * frame[1, 1] + dz * frame[1, 2]
        w = dx * frame[2, 0] + dy * frame[2, 1] + dz * frame[2, 2]
        _monomials(u, v, degree, vec)
        ww += wt * w * w
        for a in range(nd):
            ma = wt * vec[1, a]
            vec[0, a] += ma * w
            for b in range(a, nd):
                m[a, b] += ma * vec[1, b]
    rcond = solve_spd_scaled(m, vec, nd)
    if not rcond >= RCOND:
        return SINGULAR, 0.0, 0.0
    for a in range(nd):
        if not math.isfinite(vec[1, a]):
            return SINGULAR, 0.0, 0.0
    return OK, math.sqrt(h2), ww


@jit
def _to_world(frame, a, b, c, out, row):
    """``out[row] = a e1 + b e2 + c e3`` for the frame rows ``e1, e2, e3``."""
    for k in range(3):
        out[row, k] = a * frame[0, k] + b * frame[1, k] + c * frame[2, k]


@jit
def jet_normal(vec, frame, out, row):
    """Write the unit normal of the fitted jet (coefficients ``vec[1]``) at the origin to ``out[row]``."""
    ju, jv = vec[1, 1], vec[1, 2]
    inv = 1.0 / math.sqrt(1.0 + ju * ju + jv * jv)
    _to_world(frame, -ju * inv, -jv * inv, inv, out, row)


@jit
def _jet_frame(ju, jv):
    """The jet normal n and the orthonormal tangent basis (T1, T2) at the origin, in the PCA frame.

    The tangents are S_u = (1, 0, J_u), S_v = (0, 1, J_v); T1 = S_u / |S_u|, T2 = n x T1, so that
    S_u = s T1 and S_v = a T1 + b T2.

    Returns
    -------
    n0, n1, n2, t10, t11, t12, t20, t21, t22, s, a, b : float
    """
    wn = math.sqrt(1.0 + ju * ju + jv * jv)
    n0, n1, n2 = -ju / wn, -jv / wn, 1.0 / wn
    s = math.sqrt(1.0 + ju * ju)
    t10, t11, t12 = 1.0 / s, 0.0, ju / s
    t20, t21, t22 = n1 * t12 - n2 * t11, n2 * t10 - n0 * t12, n0 * t11 - n1 * t10
    a = jv * t12  # S_v . T1
    b = t21 + jv * t22  # S_v . T2
    return n0, n1, n2, t10, t11, t12, t20, t21, t22, s, a, b


@jit
def _jet_shape_operator(ju, jv, juu, juv, jvv):
    """The shape operator ``W = [[e, f], [f, g]]`` of the graph at the origin in the basis (T1, T2).

    ``II`` in the (S_u, S_v) basis is L, M, N = S_xy . n = J_xy / |(-J_u, -J_v, 1)|; in T it is
    ``P^-T II P^-1`` with ``P = [[s, a], [0, b]]``; W = -II (house sign).
    """
    wn = math.sqrt(1.0 + ju * ju + jv * jv)
    el, em, en = juu / wn, juv / wn, jvv / wn
    _, _, _, _, _, _, _, _, _, s, a, b = _jet_frame(ju, jv)
    i00, i01, i11 = 1.0 / s, -a / (s * b), 1.0 / b
    e = -(i00 * i00 * el)
    f = -(i00 * (i01 * el + i11 * em))
    g = -(i01 * i01 * el + 2.0 * i01 * i11 * em + i11 * i11 * en)
    return e, f, g


@jit
def jet_principal(vec, frame, h, normals, out_k, out_d1, out_d2, row):
    """Principal curvatures and directions of the jet at the origin (step 3 of the module notes).

    The jet's coefficients are ``vec[1]`` (:func:`fit_jet`). Writes ``out_k[0, row], out_k[1, row]``
    (k1 >= k2, in mesh units) and unit directions ``out_d1[row]``, ``out_d2[row]``, rotated into the
    tangent plane of ``normals[row]``.

    Returns
    -------
    int
        ``Reason.OK``, or ``DEGENERATE`` when the jet normal is about 78 degrees or more from ``normals[row]``.
    """
    ju, jv = vec[1, 1], vec[1, 2]
    e, f, g = _jet_shape_operator(ju, jv, 2.0 * vec[1, 3], vec[1, 4], 2.0 * vec[1, 5])
    n0, n1, n2, t10, t11, t12, t20, t21, t22, _, _, _ = _jet_frame(ju, jv)
    k1, k2, c, sn = sym2_eigen(e, f, g)
    out_k[0, row] = k1 / h
    out_k[1, row] = k2 / h
    # d1 = c T1 + s T2, d2 = n x d1 = -s T1 + c T2, then to world coordinates
    _to_world(frame, c * t10 + sn * t20, c * t11 + sn * t21, c * t12 + sn * t22, out_d1, row)
    _to_world(frame, -sn * t10 + c * t20, -sn * t11 + c * t21, -sn * t12 + c * t22, out_d2, row)
    # carry the directions to the tangent plane of the reference normal r: smallest rotation taking n to r
    nw0 = n0 * frame[0, 0] + n1 * frame[1, 0] + n2 * frame[2, 0]
    nw1 = n0 * frame[0, 1] + n1 * frame[1, 1] + n2 * frame[2, 1]
    nw2 = n0 * frame[0, 2] + n1 * frame[1, 2] + n2 * frame[2, 2]
    rx, ry, rz = normals[row, 0], normals[row, 1], normals[row, 2]
    cosine = nw0 * rx + nw1 * ry + nw2 * rz
    if not cosine >= MIN_NORMAL_COSINE:
        return DEGENERATE
    ax0, ax1, ax2 = nw1 * rz - nw2 * ry, nw2 * rx - nw0 * rz, nw0 * ry - nw1 * rx
    _rotate(out_d1, row, ax0, ax1, ax2, cosine)
    _rotate(out_d2, row, ax0, ax1, ax2, cosine)
    return OK


@jit
def _rotate(out, row, ax0, ax1, ax2, cosine):
    """Rotate ``out[row]`` by Rodrigues with the unnormalised axis ``a = n x r`` and ``c = n . r``:
    ``R v = c v + a x v + a (a . v) / (1 + c)``."""
    v0, v1, v2 = out[row, 0], out[row, 1], out[row, 2]
    dot = (ax0 * v0 + ax1 * v1 + ax2 * v2) / (1.0 + cosine)
    out[row, 0] = cosine * v0 + (ax1 * v2 - ax2 * v1) + ax0 * dot
    out[row, 1] = cosine * v1 + (ax2 * v0 - ax0 * v2) + ax1 * dot
    out[row, 2] = cosine * v2 + (ax0 * v1 - ax1 * v0) + ax2 * dot


SLOPE_STEP = 1e-6
"""Step of the central differences of W over the jet's slopes J_u, J_v (W is linear in the rest)."""


@jit
def jet_se(vec, m, h, count, nd, ww, grads, out_se, row):
    """Standard errors of the jet's k1, k2 at the origin (first order), after :func:`fit_jet`.

    ``sigma² = RSS / (count - N_d)`` with ``RSS = ww - Jᵀ(Aᵀb)``; the jet has its own constant and
    linear terms, so the centre's noise is one more independent equation. The covariance of the
    coefficients J is ``sigma² (AᵀA)⁻¹``, read from the Cholesky factor the fit left in ``m`` and
    its scaling in ``vec[2]``. Through the fundamental-forms step, ``dk_i = d_iᵀ dW d_i`` with
    ``dW`` the derivative of :func:`_jet_shape_operator` along each coefficient: exact for the
    second derivatives (W is linear in them), central differences for the slopes.
    Writes ``out_se[0, row], out_se[1, row]`` in mesh units; ``grads`` (2, K) is scratch.
    """
    xatb = 0.0
    for a in range(nd):
        xatb += vec[1, a] * vec[0, a]
    sigma2 = noise_variance(ww, xatb, count - nd)
    ju, jv, juu, juv, jvv = vec[1, 1], vec[1, 2], 2.0 * vec[1, 3], vec[1, 4], 2.0 * vec[1, 5]
    e, f, g = _jet_shape_operator(ju, jv, juu, juv, jvv)
    g10, g11, g12, g20, g21, g22 = principal_gradients(e, f, g)
    grads[:, :] = 0.0
    for index in range(1, 6):
        if index == 1:
            ep, fp, gp = _jet_shape_operator(ju + SLOPE_STEP, jv, juu, juv, jvv)
            em, fm, gm = _jet_shape_operator(ju - SLOPE_STEP, jv, juu, juv, jvv)
            de, df, dg = (ep - em) / (2.0 * SLOPE_STEP), (fp - fm) / (2.0 * SLOPE_STEP), (gp - gm) / (2.0 * SLOPE_STEP)
        elif index == 2:
            ep, fp, gp = _jet_shape_operator(ju, jv + SLOPE_STEP, juu, juv, jvv)
            em, fm, gm = _jet_shape_operator(ju, jv - SLOPE_STEP, juu, juv, jvv)
            de, df, dg = (ep - em) / (2.0 * SLOPE_STEP), (fp - fm) / (2.0 * SLOPE_STEP), (gp - gm) / (2.0 * SLOPE_STEP)
        elif index == 3:  # J_20 = J_uu / 2
            de, df, dg = _jet_shape_operator(ju, jv, 2.0, 0.0, 0.0)
        elif index == 4:  # J_11 = J_uv
            de, df, dg = _jet_shape_operator(ju, jv, 0.0, 1.0, 0.0)
        else:  # J_02 = J_vv / 2
            de, df, dg = _jet_shape_operator(ju, jv, 0.0, 0.0, 2.0)
        grads[0, index] = g10 * de + g11 * df + g12 * dg
        grads[1, index] = g20 * de + g21 * df + g22 * dg
    factor_whiten(m, vec, 2, nd, grads)
    out_se[0, row] = math.sqrt(sigma2 * row_dot(grads, 0, 0, nd)) / h
    out_se[1, row] = math.sqrt(sigma2 * row_dot(grads, 1, 1, nd)) / h


@jit_parallel
def _jet_kernel(centres, lo, hi, degree, smooth, radius, indptr, indices, x, y, z, normals, stamps, queues, k, d1, d2,
                reason, k_se):
    parts = stamps.shape[0]
    nd = (degree + 1) * (degree + 2) // 2
    for t in prange(parts):
        stamp = stamps[t]
        queue = queues[t]
        m, vec, cov, frame, evec = _scratch()
        grads = np.empty((2, MAX_UNKNOWNS))
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            r2 = radius[p] ** 2
            count, queue = ball_support(p, r2, indptr, indices, x, y, z, stamp, queue)
            code, h, ww = fit_jet(p, count, queue, x, y, z, normals, degree, m, vec, cov, frame, evec,
                                  r2 if smooth else 0.0)
            if code == OK:
                code = jet_principal(vec, frame, h, normals, k, d1, d2, p)
                jet_se(vec, m, h, count, nd, ww, grads, k_se, p)
            reason[p] = code


@jit_parallel
def _jet_levels_kernel(centres, lo, hi, degree, smooth, radii, indptr, indices, x, y, z, normals, stamps, queues,
                       outside, outside_d2, k, d1, d2, reason, k_se):
    """:func:`_jet_kernel` at every level of ``radii`` (levels, n), ascending per vertex, in one walk
    (:func:`~curv.geometry.neighbourhood.widen_ball_support`: each level's support is exactly the
    single search's). The PCA frame and the scale h follow the support, so every level fits its own
    support anew: the walk is what the levels share. Writes ``k[level]``, ``d1[level]``, ...,
    ``k_se[level]`` as :func:`_jet_kernel` writes its outputs."""
    parts = stamps.shape[0]
    levels = radii.shape[0]
    nd = (degree + 1) * (degree + 2) // 2
    for t in prange(parts):
        stamp, queue, waiting, waiting_d2 = stamps[t], queues[t], outside[t], outside_d2[t]
        m, vec, cov, frame, evec = _scratch()
        grads = np.empty((2, MAX_UNKNOWNS))
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            count = start_ball_support(p, stamp, queue)
            head = pending = 0
            for level in range(levels):
                r2 = radii[level, p] ** 2
                count, head, pending = widen_ball_support(p, r2, level + 1 < levels, indptr, indices, x, y, z, stamp,
                                                          queue, count, head, waiting, waiting_d2, pending)
                code, h, ww = fit_jet(p, count, queue, x, y, z, normals, degree, m, vec, cov, frame, evec,
                                      r2 if smooth else 0.0)
                if code == OK:
                    code = jet_principal(vec, frame, h, normals, k[level], d1[level], d2[level], p)
                    jet_se(vec, m, h, count, nd, ww, grads, k_se[level], p)
                reason[level, p] = code


@jit_parallel
def _jet_normal_kernel(centres, lo, hi, degree, smooth, radius, indptr, indices, x, y, z, normals, stamps, queues, out,
                       reason):
    parts = stamps.shape[0]
    for t in prange(parts):
        stamp = stamps[t]
        queue = queues[t]
        m, vec, cov, frame, evec = _scratch()
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            r2 = radius[p] ** 2
            count, queue = ball_support(p, r2, indptr, indices, x, y, z, stamp, queue)
            code, _, _ = fit_jet(p, count, queue, x, y, z, normals, degree, m, vec, cov, frame, evec, r2 if smooth else 0.0)
            if code == OK:
                jet_normal(vec, frame, out, p)
            reason[p] = code


def check_degree(degree) -> int:
    """The degree as an int; :class:`~curv.core.errors.EstimatorError` unless it is one of :data:`DEGREES`."""
    if isinstance(degree, (bool, np.bool_)) or degree not in DEGREES:
        raise EstimatorError(f"jet degree must be one of {', '.join(map(str, DEGREES))}; got {degree!r}")
    return int(degree)


def check_weights(weights) -> bool:
    """True for ``"smooth"``, False for ``"uniform"``; :class:`~curv.core.errors.EstimatorError` otherwise."""
    if not isinstance(weights, str) or weights not in WEIGHTS:
        raise EstimatorError(f"jet weights must be one of {', '.join(WEIGHTS)}; got {weights!r}")
    return weights == "smooth"


def check_width(width) -> bool:
    """True for ``"adaptive"``, False for ``"fixed"``; :class:`~curv.core.errors.EstimatorError` otherwise."""
    if not isinstance(width, str) or width not in WIDTHS:
        raise EstimatorError(f"jet width must be one of {', '.join(WIDTHS)}; got {width!r}")
    return width == "adaptive"


def _inputs(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, centres: np.ndarray, features):
    indptr, indices = expansion_adjacency(mesh, blocked_vertices(features), radii)
    x, y, z = coordinate_columns(mesh)
    radius = np.ascontiguousarray(radii, dtype=np.float64)
    # any layout: the cached normals are column-major, and a copy would cost the whole mesh per region
    ref = np.asarray(normals, dtype=np.float64)
    parts = max(1, min(threads(), centres.size))
    # A queue as long as the mesh per thread: ball_support never has to grow it. Growing it inside
    # the prange body (reassigning the array there) returned garbage supports on large balls.
    queues = np.empty((parts, mesh.n_vertices), np.int64)
    return radius, indptr, indices, x, y, z, ref, new_scratch(mesh.n_vertices, parts), queues


def iter_jet(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
             degree: int = DEFAULT_DEGREE, weights: str = DEFAULT_WEIGHTS, centres: np.ndarray | None = None,
             features=None, width: str = DEFAULT_WIDTH):
    """Osculating jet of degree ``degree`` over each vertex's ball support.

    Parameters
    ----------
    mesh : Mesh
        Any polygon mesh.
    normals : (n, 3) float64
        Unit vertex normals; they orient each fit and its curvature sign (NaN rows: ``DEGENERATE``).
    radii : (n,) or (levels, n) float64
        Ball radius of every vertex (:func:`curv.core.ranges.ball_radii`, ``uses_normals=False``), or
        of every vertex at each of several levels, ascending per vertex (several ranges in one call:
        on a mesh with the fixed width one walk serves them all, :func:`_jet_levels_kernel`; the
        values agree with a call per level to rounding, as the support's sums are added in the
        walk's order).
    chunk : int, optional
        Vertices per kernel call (default adaptive).
    degree : {2, 3, 4}
        Jet degree; the support must hold at least ``(d+1)(d+2)/2`` points, the centre included.
    weights : {"uniform", "smooth"}
        How the support points count in the PCA frame and the fit (:data:`WEIGHTS`). At a given
        range the smooth fit has less bias and more noise than the uniform one (about half the
        degree-2 bias on a sphere, 2.6-2.8x the spread under noise); its standard errors treat the
        weights as inverse variances (first order), which puts them about 20 % below the spread
        measured on a noisy sphere (within 10 % with uniform weights).
    centres : (c,) int64, optional
        The vertices to estimate (default all); other rows are left unset.
    features : curv.core.features.FeatureSet, optional
        The supports do not expand through feature vertices.
    width : {"fixed", "adaptive"}
        ``"fixed"`` (the default) fits over the given ball. ``"adaptive"`` chooses per vertex among
        the degree-``degree`` jets over narrower balls and the degree-2 smooth jet over the whole
        ball, by the intersection of their confidence intervals (:mod:`curv.estimators.jet_width`;
        7 fits, all within the given ball).

    Yields
    ------
    float
        Fraction of vertices done.

    Returns
    -------
    Principal, or a list of one per level
        k1 >= k2 of the jet, directions tangent to ``normals``; reasons ``TOO_FEW_NEIGHBOURS``,
        ``SINGULAR``, ``DEGENERATE`` where there is no fit.
    """
    degree = check_degree(degree)
    smooth = check_weights(weights)
    levels = np.ndim(radii) == 2
    if levels and (check_width(width) or not isinstance(mesh, Mesh)):
        # the adaptive width, and a point cloud's grid: a fit per level
        out = []
        for level in range(len(radii)):
            out.append((yield from iter_jet(mesh, normals, radii[level], chunk=chunk, degree=degree, weights=weights,
                                            centres=centres, features=features, width=width)))
        return out
    if check_width(width):
        return (yield from iter_adaptive_jet(mesh, normals, radii, chunk=chunk, degree=degree, weights=weights,
                                             centres=centres, features=features))
    n = mesh.n_vertices
    centres = all_centres(n, centres)
    whole = centres.size == n
    count = len(radii) if levels else 1
    k = filled((count, 2, n), np.nan, most_written=whole)
    k_se = filled((count, 2, n), np.nan, most_written=whole)
    d1, d2 = filled((count, n, 3), np.nan, most_written=whole), filled((count, n, 3), np.nan, most_written=whole)
    reason = np.zeros((count, n), np.uint8)
    radius, indptr, indices, x, y, z, ref, stamps, queues = _inputs(mesh, normals, radii, centres, features)
    if levels:
        # the walk's vertices met beyond a level, waiting for a wider one: never past the mesh's size
        outside, outside_d2 = np.empty_like(queues), np.empty(queues.shape)

    def run(lo, hi):
        if levels:
            launch(_jet_levels_kernel, centres, lo, hi, degree, smooth, radius, indptr, indices, x, y, z, ref, stamps,
                   queues, outside, outside_d2, k, d1, d2, reason, k_se)
        else:
            launch(_jet_kernel, centres, lo, hi, degree, smooth, radius, indptr,
                   indices, x, y, z, ref, stamps, queues, k[0], d1[0], d2[0], reason[0], k_se[0])

    yield from iter_chunks(centres.size, run, chunk=chunk)
    out = []
    for level in range(count):
        res = Principal(k1=k[level, 0], k2=k[level, 1], d1=d1[level], d2=d2[level], reason=reason[level],
                        k1_se=k_se[level, 0], k2_se=k_se[level, 1])
        bad = centres[res.reason[centres] != OK]
        for arr in (res.k1, res.k2, res.d1, res.d2, res.k1_se, res.k2_se):
            arr[bad] = np.nan
        out.append(res)
    return out if levels else out[0]


def jet_normals(mesh: Mesh, reference: np.ndarray, radii: np.ndarray, *, degree: int = DEFAULT_DEGREE,
                weights: str = DEFAULT_WEIGHTS, chunk: int | None = None, features=None):
    """Unit normals of the jets fitted over each vertex's ball support, a generator.

    Parameters as in :func:`iter_jet` (``reference`` orients each fit; with ``features`` the fits
    do not reach across a crease).

    Returns
    -------
    normals : (n, 3) float64
        NaN where there is no fit.
    reason : (n,) uint8
    """
    degree = check_degree(degree)
    smooth = check_weights(weights)
    n = mesh.n_vertices
    out = np.full((n, 3), np.nan)
    reason = np.zeros(n, np.uint8)
    centres = all_centres(n, None)
    radius, indptr, indices, x, y, z, ref, stamps, queues = _inputs(mesh, reference, radii, centres, features)

    def run(lo, hi):
        launch(_jet_normal_kernel, centres, lo, hi, degree, smooth, radius, indptr, indices, x, y, z, ref, stamps, queues, out, reason)

    yield from iter_chunks(n, run, chunk=chunk)
    out[reason != OK] = np.nan
    return out, reason


register(EstimatorSpec(
    name="jet", in_paper=False, title="Osculating jet fitting", ranges=(1, 2, 3, 4), function=iter_jet,
    triangles_only=False, uses_normals=False, closed_ring=False, takes_points=True,
    reference="Cazals & Pouget 2003, Estimating differential quantities using polynomial fitting of osculating jets",
    summary="least-squares bivariate polynomial (degree 2-4, with constant and linear terms) in a PCA frame",
    options={"degree": DEGREES, "weights": WEIGHTS, "width": WIDTHS},
    kernels=(_jet_kernel, _jet_levels_kernel), takes_levels=True,
    min_neighbours=lambda options: unknowns(options.get("degree", DEFAULT_DEGREE)) - 1,
))
