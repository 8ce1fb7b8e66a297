"""The jet's fit at one vertex (:mod:`curv.estimators.jet`, steps 1-4 of its notes): the PCA frame
of the support, the least-squares height polynomial in it, the differential quantities of the graph
at the origin, and their standard errors.

Serial ``@jit`` helpers over per-thread scratch (:func:`jet_scratch`): the jet's kernels, the
fitted normals of a mesh (:func:`curv.estimators.jet.jet_normals`) and of a point cloud
(:mod:`curv.point_normals`) call them once per vertex.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..core.jit import jit, jit_inlined
from ..core.small_linalg import (cholesky_scaled, cholesky_solve_scaled, reciprocal_condition, scaled_determinant,
                                 scaled_norm_bound, sym2_eigen, sym3_eigen_closed)
from ..core.validity import DEGENERATE, OK, SINGULAR, TOO_FEW
from ..uncertainty.factored import whitened_errors
from ..uncertainty.propagation import noise_variance, principal_gradients

__all__ = ["Points", "MAX_UNKNOWNS", "RCOND", "MIN_NORMAL_COSINE", "smooth_weight", "jet_scratch", "fit_jet",
           "jet_normal", "jet_principal", "jet_errors"]

MAX_UNKNOWNS = 15
"""Unknowns of a degree-4 jet."""

Points = namedtuple("Points", ["x", "y", "z", "normals"])
"""What a jet fit reads: the (n,) coordinate columns and the (n, 3) normals (any layout) that orient
each fit (a plain tuple of the four works too)."""

RCOND = 1e-12
"""A fit whose scaled normal matrix has an estimated reciprocal condition number below this (a
least-squares matrix condition above 1e6) is ``SINGULAR``."""

MIN_NORMAL_COSINE = 0.2
"""The PCA normal and the jet's normal must be within about 78 degrees of the vertex normal, or the fit
does not describe the surface at the vertex (``DEGENERATE``)."""

V_SIGNS = np.array([(-1.0) ** j for t in range(5) for j in range(t + 1)])
"""(:data:`MAX_UNKNOWNS`,) the sign each unknown takes when the frame's ``e2`` turns over (``v`` to
``-v``, the monomial ``u^(t-j) v^j`` by ``(-1)^j``): a frame turned towards the other side of the
reference normal (``e3``, and with it ``e2 = e3 x e1``) gives the same fit with these signs and the
heights' (:func:`_solve`'s condition estimate is the same for both)."""



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


@jit
def jet_scratch():
    """Per-thread scratch of :func:`fit_jet`: ``(m, vec, cov, frame, evec)``: the normal matrix (its
    Cholesky factor below the diagonal, its scales in row :data:`MAX_UNKNOWNS`), vectors (right-hand
    side, coefficients, work), the 3x3 covariance, the frame, its eigenvectors."""
    m = np.empty((MAX_UNKNOWNS + 1, MAX_UNKNOWNS))
    vec = np.empty((3, MAX_UNKNOWNS))
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
def fit_jet(p, count, queue, points, degree, scratch, r2=0.0):
    """Fit the degree-``degree`` jet of the support of ``p`` (steps 1 and 2 of the module notes).

    Parameters
    ----------
    p : int
        Centre vertex; ``queue[:count]`` is its support with ``queue[0] == p``.
    points : Points or (x, y, z, normals)
        The (n,) coordinate columns; ``normals[p]`` orients the fit (the vertex normal); NaN gives
        ``DEGENERATE``.
    degree : int
    scratch : tuple
        Per-thread scratch from :func:`jet_scratch`, ``(m, vec, cov, frame, evec)``. On success
        ``frame`` rows are ``e1, e2, e3`` (world coordinates), ``vec[1, :N_d]`` holds the
        coefficients ``J`` in the order of :func:`_monomials`, for coordinates divided by the returned
        ``h``, and ``m`` the factor of the scaled normal matrix (:func:`jet_errors` reads it).
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
    m, vec, _, frame, _ = scratch
    nd = (degree + 1) * (degree + 2) // 2  # unknowns(degree); the registry's min_neighbours is nd - 1
    if count < nd:
        return TOO_FEW, 0.0, 0.0
    code, h2 = _pca_frame((p, count, queue), points, r2, scratch)
    if code != OK:
        return code, 0.0, 0.0
    # normal equations of the height fit in coordinates divided by h
    ww = _normal_equations((p, count, queue), points, frame, (r2, 1.0 / math.sqrt(h2)), degree, (m, vec))
    if not _solve(m, vec, nd):
        return SINGULAR, 0.0, 0.0
    for a in range(nd):
        if not math.isfinite(vec[1, a]):
            return SINGULAR, 0.0, 0.0
    return OK, math.sqrt(h2), ww


@jit
def _pca_frame(support, points, r2, scratch):
    """The fit's frame over ``support = (p, count, queue)`` (step 1 of the module notes): the rows
    ``e1, e2, e3`` of ``scratch``'s ``frame`` from the (weighted) PCA of the support, ``e3`` turned
    towards ``normals[p]``; the eigenpairs in ``evec`` (left unset when it stops before them).

    Returns
    -------
    reason : int
        ``OK``, or ``DEGENERATE``: no reference normal, a support of one place, or a PCA normal
        too far from the reference (:data:`MIN_NORMAL_COSINE`).
    h2 : float
        The squared largest distance from p to a support point.
    """
    p, count, queue = support
    x, y, z, normals = points
    _, _, cov, frame, evec = scratch
    rx, ry, rz = normals[p, 0], normals[p, 1], normals[p, 2]
    if not (math.isfinite(rx) and math.isfinite(ry) and math.isfinite(rz)):
        return DEGENERATE, 0.0
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
        return DEGENERATE, 0.0
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
    sym3_eigen_closed(cov, evec)  # reads the upper triangle
    # The support must be a height field over its PCA plane: a plane far from the vertex normal
    # (a support wrapping round a thin rim) gives an arbitrary fit whose sign flips with rounding.
    along = evec[0, 0] * rx + evec[1, 0] * ry + evec[2, 0] * rz
    if not abs(along) >= MIN_NORMAL_COSINE * math.sqrt(rx * rx + ry * ry + rz * rz):
        return DEGENERATE, 0.0
    # e3: least variance (the height axis), turned towards the reference normal; e1: most variance
    sign = 1.0 if along >= 0.0 else -1.0
    for a in range(3):
        frame[2, a] = sign * evec[a, 0]
        frame[0, a] = evec[a, 2]
    frame[1, 0] = frame[2, 1] * frame[0, 2] - frame[2, 2] * frame[0, 1]
    frame[1, 1] = frame[2, 2] * frame[0, 0] - frame[2, 0] * frame[0, 2]
    frame[1, 2] = frame[2, 0] * frame[0, 1] - frame[2, 1] * frame[0, 0]
    return OK, h2


@jit_inlined
def _heights(q, origin, points, frame, scale):
    """Support point q in the fit's frame: its weight and ``(u, v, w)``, the offsets from
    ``origin = (px, py, pz)`` divided by h (``scale = (r2, 1 / h)``) along ``e1, e2, e3``."""
    x, y, z = points[0], points[1], points[2]
    r2, inv_h = scale
    dx, dy, dz = x[q] - origin[0], y[q] - origin[1], z[q] - origin[2]
    wt = smooth_weight(dx * dx + dy * dy + dz * dz, r2)
    dx, dy, dz = dx * inv_h, dy * inv_h, dz * inv_h
    u = dx * frame[0, 0] + dy * frame[0, 1] + dz * frame[0, 2]
    v = dx * frame[1, 0] + dy * frame[1, 1] + dz * frame[1, 2]
    w = dx * frame[2, 0] + dy * frame[2, 1] + dz * frame[2, 2]
    return wt, u, v, w


@jit
def _normal_equations(support, points, frame, scale, degree, out):
    """The normal equations of the height fit of degree ``degree`` over ``support = (p, count,
    queue)``: the upper triangle of ``Σ wt μ μᵀ`` into ``m`` and ``Σ wt w μ`` into ``vec[0]``
    (``out = (m, vec)``; ``μ`` the monomials of :func:`_monomials` at :func:`_heights`'s ``(u,
    v)``, ``vec[1]`` overwritten). Returns ``ww = Σ wt w²``.

    Degree 2 (the default, and the point normals' fit) adds in scalars (:func:`_normal_equations_2`);
    the same products in the same order, so the sums are the same to the bit."""
    if degree == 2:
        return _normal_equations_2(support, points, frame, scale, out)
    p, count, queue = support
    m, vec = out
    nd = (degree + 1) * (degree + 2) // 2
    origin = (points[0][p], points[1][p], points[2][p])
    ww = 0.0
    for a in range(nd):
        vec[0, a] = 0.0
        for b in range(a, nd):
            m[a, b] = 0.0
    for i in range(count):
        wt, u, v, w = _heights(queue[i], origin, points, frame, scale)
        _monomials(u, v, degree, vec)
        ww += wt * w * w
        for a in range(nd):
            ma = wt * vec[1, a]
            vec[0, a] += ma * w
            for b in range(a, nd):
                m[a, b] += ma * vec[1, b]
    return ww


@jit
def _normal_equations_2(support, points, frame, scale, out):
    """:func:`_normal_equations` of degree 2 (monomials ``1, u, v, u², vu, v²``): each sum in a
    scalar, as the general loop adds it (``(wt mono_a) mono_b``), so that no sum goes through memory."""
    p, count, queue = support
    m, vec = out
    origin = (points[0][p], points[1][p], points[2][p])
    ww = b0 = b1 = b2 = b3 = b4 = b5 = 0.0
    m00 = m01 = m02 = m03 = m04 = m05 = m11 = m12 = m13 = m14 = m15 = 0.0
    m22 = m23 = m24 = m25 = m33 = m34 = m35 = m44 = m45 = m55 = 0.0
    for i in range(count):
        wt, u, v, w = _heights(queue[i], origin, points, frame, scale)
        uu, vu, vv = u * u, v * u, v * v
        ww += wt * w * w
        a0, a1, a2, a3, a4, a5 = wt * 1.0, wt * u, wt * v, wt * uu, wt * vu, wt * vv
        b0 += a0 * w
        b1 += a1 * w
        b2 += a2 * w
        b3 += a3 * w
        b4 += a4 * w
        b5 += a5 * w
        m00 += a0 * 1.0
        m01 += a0 * u
        m02 += a0 * v
        m03 += a0 * uu
        m04 += a0 * vu
        m05 += a0 * vv
        m11 += a1 * u
        m12 += a1 * v
        m13 += a1 * uu
        m14 += a1 * vu
        m15 += a1 * vv
        m22 += a2 * v
        m23 += a2 * uu
        m24 += a2 * vu
        m25 += a2 * vv
        m33 += a3 * uu
        m34 += a3 * vu
        m35 += a3 * vv
        m44 += a4 * vu
        m45 += a4 * vv
        m55 += a5 * vv
    vec[0, 0], vec[0, 1], vec[0, 2], vec[0, 3], vec[0, 4], vec[0, 5] = b0, b1, b2, b3, b4, b5
    m[0, 0], m[0, 1], m[0, 2], m[0, 3], m[0, 4], m[0, 5] = m00, m01, m02, m03, m04, m05
    m[1, 1], m[1, 2], m[1, 3], m[1, 4], m[1, 5] = m11, m12, m13, m14, m15
    m[2, 2], m[2, 3], m[2, 4], m[2, 5] = m22, m23, m24, m25
    m[3, 3], m[3, 4], m[3, 5] = m33, m34, m35
    m[4, 4], m[4, 5] = m44, m45
    m[5, 5] = m55
    return ww


CLEAR = 1e3 * RCOND
"""A fit whose scaled normal matrix has a smallest eigenvalue provably at least this times its
norm bound is not ``SINGULAR`` without the estimate (:func:`_solve`): a thousand times
:data:`RCOND`, far beyond the rounding of the factor and the estimate's solves."""


@jit
def _solve(m, vec, nd):
    """Solve the normal equations (``m``'s upper triangle, right-hand side ``vec[0]``) into
    ``vec[1]`` by the Jacobi-scaled Cholesky factor (:func:`~curv.core.small_linalg.cholesky_scaled`,
    left in ``m``); returns whether the scaled matrix is conditioned: its estimated reciprocal
    condition number (:func:`~curv.core.small_linalg.reciprocal_condition`) at least :data:`RCOND`
    (False when the factorisation broke down), the same for either side of the frame
    (:data:`V_SIGNS`), so that ``SINGULAR`` does not follow the reference normal's free sign.

    The estimate (six solves) is asked only where a free bound leaves the verdict open: the scaled
    matrix's eigenvalues are at most ``lam_max`` (:func:`~curv.core.small_linalg.scaled_norm_bound`),
    so its smallest is at least ``det / lam_max^(nd - 1)``, the determinant being the factor's
    diagonal squared. The estimate is itself at least the smallest eigenvalue (inverse iteration),
    so where the bound is at least :data:`CLEAR` times ``lam_max`` the estimate is above
    :data:`RCOND` and the verdict is its own (the bound is as sign-symmetric as the estimate)."""
    lam_max = scaled_norm_bound(m, nd, MAX_UNKNOWNS)
    if not cholesky_scaled(m, nd, MAX_UNKNOWNS):
        return False
    cholesky_solve_scaled(m, MAX_UNKNOWNS, nd, vec)
    if scaled_determinant(m, nd) >= CLEAR * lam_max ** nd:
        return True
    return reciprocal_condition(m, nd, lam_max, vec, 2, V_SIGNS) >= RCOND


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
def jet_principal(scratch, h, normals, out, row):
    """Principal curvatures and directions of the jet at the origin (step 3 of the module notes).

    The jet's coefficients are ``vec[1]`` of ``scratch`` (:func:`fit_jet`). Writes row ``row`` of
    ``out`` (:class:`~curv.estimators._principal.Rows`): k1 >= k2 in mesh units and unit directions,
    rotated into the tangent plane of ``normals[row]``.

    Returns
    -------
    int
        ``Reason.OK``, or ``DEGENERATE`` when the jet normal is about 78 degrees or more from ``normals[row]``.
    """
    _, vec, _, frame, _ = scratch
    ju, jv = vec[1, 1], vec[1, 2]
    e, f, g = _jet_shape_operator(ju, jv, 2.0 * vec[1, 3], vec[1, 4], 2.0 * vec[1, 5])
    n0, n1, n2, t10, t11, t12, t20, t21, t22, _, _, _ = _jet_frame(ju, jv)
    k1, k2, c, sn = sym2_eigen(e, f, g)
    out.k1[row] = k1 / h
    out.k2[row] = k2 / h
    # d1 = c T1 + s T2, d2 = n x d1 = -s T1 + c T2, then to world coordinates
    _to_world(frame, c * t10 + sn * t20, c * t11 + sn * t21, c * t12 + sn * t22, out.d1, row)
    _to_world(frame, -sn * t10 + c * t20, -sn * t11 + c * t21, -sn * t12 + c * t22, out.d2, row)
    # carry the directions to the tangent plane of the reference normal r: smallest rotation taking n to r
    nw0 = n0 * frame[0, 0] + n1 * frame[1, 0] + n2 * frame[2, 0]
    nw1 = n0 * frame[0, 1] + n1 * frame[1, 1] + n2 * frame[2, 1]
    nw2 = n0 * frame[0, 2] + n1 * frame[1, 2] + n2 * frame[2, 2]
    rx, ry, rz = normals[row, 0], normals[row, 1], normals[row, 2]
    cosine = nw0 * rx + nw1 * ry + nw2 * rz
    if not cosine >= MIN_NORMAL_COSINE:
        return DEGENERATE
    ax0, ax1, ax2 = nw1 * rz - nw2 * ry, nw2 * rx - nw0 * rz, nw0 * ry - nw1 * rx
    _rotate(out.d1, row, ax0, ax1, ax2, cosine)
    _rotate(out.d2, row, ax0, ax1, ax2, cosine)
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
def jet_errors(p, level, errors, scratch, fit, grads):
    """Standard errors of the jet's k1, k2 at the origin (first order), after :func:`fit_jet`:
    column p of row ``level`` of ``errors`` (``(k1_se, k2_se)``, (levels, n) each; nothing when None).

    ``sigma² = RSS / (count - N_d)`` with ``RSS = ww - Jᵀ(Aᵀb)``; the jet has its own constant and
    linear terms, so the centre's noise is one more independent equation. The covariance of the
    coefficients J is ``sigma² (AᵀA)⁻¹``, read from the Cholesky factor the fit left in ``m``
    (:func:`~curv.uncertainty.factored.whitened_errors`). Through the fundamental-forms step,
    ``dk_i = d_iᵀ dW d_i`` with ``dW`` the derivative of :func:`_jet_shape_operator` along each
    coefficient: exact for the second derivatives (W is linear in them), central differences for
    the slopes. ``fit = (h, count, degree, ww)`` (:func:`fit_jet`); ``grads`` (2, K) is scratch.
    """
    if errors is None:
        return
    m, vec, _, _, _ = scratch
    h, count, degree, ww = fit
    nd = (degree + 1) * (degree + 2) // 2
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
    se1, se2 = whitened_errors(m, MAX_UNKNOWNS, nd, grads, sigma2)
    errors[0][level, p] = se1 / h
    errors[1][level, p] = se2 / h


