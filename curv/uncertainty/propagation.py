"""From a 3-unknown fit to its standard errors' parts: the propagation through the eigen step and
the noise level read from the residuals (docs/UNCERTAINTY.md).

With m equations in the unknowns x of W = [[e, f], [f, g]] (or their negatives), M = AᵀA, the
residual sum of squares ``RSS = bᵀb - xᵀAᵀb`` and independent errors of one variance, the noise
variance is ``sigma² = RSS / (m - 3)`` and x has covariance ``sigma² M⁻¹``. A principal curvature is
``k_i = d_iᵀ W d_i`` with d_i = (c, s) its unit direction, so to first order ``dk_i = d_iᵀ dW d_i``:
its gradient over (e, f, g) is ``(c², 2cs, s²)`` for k1 and ``(s², -2cs, c²)`` for k2
(:func:`principal_gradients`) and ``se(k_i)² = sigma² gᵀM⁻¹g``. The eigen step also biases k1 up
and k2 down where the noise in W is as large as k1 - k2 (:func:`eigen_bias`), added in quadrature.

A fit hands over what it produced: M (the upper triangle), ``(bᵀb, xᵀAᵀb, m)``, the solution and W,
and the sums of the columns its errors share (:func:`three_unknown_parts`: the centre's own height
in every equation; the frame's tilt, :func:`add_tilt`) or the weights of its equations' errors
(:func:`weighted_parts`: nc's normal curvatures, :func:`normal_curvature_meat`).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit, jit_inlined
from ..core.small_linalg import RCOND, sym3_bilinear, sym3_inverse
from .parts import store_parts

__all__ = ["principal_gradients", "deviator_gradients", "rad_bias", "eigen_bias", "noise_variance", "NO_TILT",
           "add_tilt", "tilt_schur", "tilt_residual", "three_unknown_parts", "sym3_sandwich", "weighted_parts",
           "offsets_room", "keep_offset", "normal_curvature_meat", "normal_curvature_parts"]


@jit
def principal_gradients(e, f, g):
    """First-order gradients of k1 and k2 of W = [[e, f], [f, g]] over (e, f, g).

    ``dk_i = d_iᵀ dW d_i`` with d1 = (c, s), d2 = (-s, c) the eigenvectors (the eigen step's angle
    theta with ``cos 2theta = (e - g) / 2 / rad``, ``sin 2theta = f / rad``), written without
    trigonometry: ``c² = (1 + cos 2theta) / 2``, ``2cs = sin 2theta``.

    Returns
    -------
    g10, g11, g12, g20, g21, g22 : float
        ``(c², 2cs, s²)`` for k1 and ``(s², -2cs, c²)`` for k2.
    """
    half = 0.5 * (e - g)
    rad = math.hypot(half, f)
    if rad > 0.0:
        cos2, sin2 = half / rad, f / rad
    else:  # an umbilic: atan2(0, 0) = 0, as in the eigen step
        cos2, sin2 = 1.0, 0.0
    cc, ss = 0.5 * (1.0 + cos2), 0.5 * (1.0 - cos2)
    return cc, sin2, ss, ss, -sin2, cc


@jit
def deviator_gradients(e, f, g):
    """Gradients over (e, f, g) of the two components of W's deviator ``((e - g) / 2, f)``: along
    its estimate (``rad``'s first-order gradient, ``(cos 2theta / 2, sin 2theta, -cos 2theta / 2)``)
    and perpendicular to it (``(-sin 2theta / 2, cos 2theta, sin 2theta / 2)``): see
    :func:`eigen_bias`.

    Returns
    -------
    a0, a1, a2, h0, h1, h2 : float
    """
    half = 0.5 * (e - g)
    rad = math.hypot(half, f)
    if rad > 0.0:
        cos2, sin2 = half / rad, f / rad
    else:
        cos2, sin2 = 1.0, 0.0
    return 0.5 * cos2, sin2, -0.5 * cos2, -0.5 * sin2, cos2, 0.5 * sin2


@jit
def rad_bias(rad, var_deviator):
    """The eigen step's bias of k1 (+) and k2 (-) from the length ``rad`` of W's deviator and the
    deviator's noise variance: ``rad - sqrt(max(rad² - var_deviator, 0))`` (:func:`eigen_bias`)."""
    return rad - math.sqrt(max(rad * rad - var_deviator, 0.0))


@jit
def eigen_bias(e, f, g, var_deviator):
    """The bias of k1 (+) and k2 (-) that the eigen step adds to a noisy W, estimated from W itself.

    ``k1, k2 = (e + g) / 2 ± rad`` with ``rad = |((e - g) / 2, f)|``, the length of W's deviator.
    Noise in the deviator (total variance ``var_deviator`` of its two components,
    :func:`deviator_gradients`) lengthens it on average: ``E[rad²] = rad_true² + var_deviator``, so
    the larger of two noisy eigenvalues is biased up and the smaller down, by about
    ``var_deviator / (2 rad)`` for a well-separated pair and by about the noise's standard deviation
    where the true principal curvatures are (nearly) equal. The first-order propagation has no term
    for it; where the noise in W is as large as k1 - k2 (a small support on a noisy mesh) it is as
    large as the standard error itself. Estimated as ``rad - sqrt(max(rad² - var_deviator, 0))``
    (the debiased length of a noisy vector).
    """
    return rad_bias(math.hypot(0.5 * (e - g), f), var_deviator)


@jit
def noise_variance(bb, xatb, dof):
    """``sigma² = RSS / dof`` with ``RSS = bᵀb - xᵀAᵀb`` (clipped at 0 against rounding); NaN if dof <= 0."""
    if not dof > 0.0:
        return math.nan
    return max(bb - xatb, 0.0) / dof


NO_TILT = (0.0,) * 13
"""The frame tilt's sums before any equation (:func:`add_tilt`)."""


@jit
def add_tilt(errors, tilt, row, rhs, lu, lv):
    """The sums of the frame tilt's two columns ``L = (lu, lv)`` with one more equation (``row`` =
    its 3 coefficients, ``rhs`` its right-hand side) added: ``LᵀL`` (3), ``LᵀQ`` (row u: 3, row v:
    3), ``Lᵀb`` (2), ``Σ L rows`` (2) as a 13-tuple (:func:`tilt_residual`). ``tilt`` as it is
    without ``errors`` (None: no standard errors)."""
    if errors is None:
        return tilt
    c0, c1, c2 = row
    return (tilt[0] + lu * lu, tilt[1] + lu * lv, tilt[2] + lv * lv, tilt[3] + lu * c0, tilt[4] + lu * c1,
            tilt[5] + lu * c2, tilt[6] + lv * c0, tilt[7] + lv * c1, tilt[8] + lv * c2, tilt[9] + lu * rhs,
            tilt[10] + lv * rhs, tilt[11] + lu, tilt[12] + lv)


@jit
def tilt_schur(minv, tilt):
    """The frame tilt's two columns L against a 3-unknown fit (M⁻¹ given by its upper triangle):
    ``T = LᵀQ M⁻¹`` (2 x 3) and the Schur complement ``S = LᵀL - T QᵀL`` (2 x 2, symmetric).

    Returns
    -------
    tu0, tu1, tu2, tv0, tv1, tv2, s_uu, s_uv, s_vv : float
        T's rows u and v, and S.
    """
    i00, i01, i02, i11, i12, i22 = minv
    qu0, qu1, qu2, qv0, qv1, qv2 = tilt[3], tilt[4], tilt[5], tilt[6], tilt[7], tilt[8]
    tu0 = qu0 * i00 + qu1 * i01 + qu2 * i02
    tu1 = qu0 * i01 + qu1 * i11 + qu2 * i12
    tu2 = qu0 * i02 + qu1 * i12 + qu2 * i22
    tv0 = qv0 * i00 + qv1 * i01 + qv2 * i02
    tv1 = qv0 * i01 + qv1 * i11 + qv2 * i12
    tv2 = qv0 * i02 + qv1 * i12 + qv2 * i22
    s_uu = tilt[0] - (tu0 * qu0 + tu1 * qu1 + tu2 * qu2)
    s_uv = tilt[1] - (tu0 * qv0 + tu1 * qv1 + tu2 * qv2)
    s_vv = tilt[2] - (tv0 * qv0 + tv1 * qv1 + tv2 * qv2)
    return tu0, tu1, tu2, tv0, tv1, tv2, s_uu, s_uv, s_vv


@jit
def tilt_residual(minv, x, s, tilt):
    """What fitting the frame's tilt as well takes from the residual sum of squares and the spare
    equations, by the Schur complement of the 3-unknown fit.

    The frame's normal is itself an estimate: a tilt t adds ``t · (column u, column v)`` to every
    equation (``u`` and ``v`` for a height, ``u / l²`` and ``v / l²`` for a normal curvature), which
    a model without linear terms leaves in the residuals. A normal made from the same 1-ring (the
    default) has already taken the linear part of the ring's noise out of them (2 of the 3 spare
    equations of a 6-neighbour ring); a normal from elsewhere leaves its tilt in them, which inflates
    them. Both are right when the noise variance is read from the residuals of the fit *with* the
    two linear terms: ``RSS₅ = RSS₃ - r_Lᵀ S⁻¹ r_L`` over ``m - 5`` spare equations, with L the two
    linear columns, ``r_L = Lᵀb - LᵀQ x``, ``S = LᵀL - LᵀQ M⁻¹ QᵀL`` (M = QᵀQ, x the 3-unknown
    solution). The curvatures stay those of the 3-unknown fit.

    Parameters
    ----------
    minv : 6-tuple of float
        M⁻¹.
    x : 3-tuple of float
        The 3-unknown solution.
    s : 3-tuple of float
        Row sum of Q (the shared centre error's column; zeros without one).
    tilt : 13-tuple of float
        :func:`add_tilt`'s sums.

    Returns
    -------
    drop : float
        ``r_Lᵀ S⁻¹ r_L`` (NaN when S is singular).
    shared_extra : float
        ``d_Lᵀ S⁻¹ d_L`` with ``d_L = Σ L rows - LᵀQ M⁻¹ s``: the linear terms' share of the centre's
        common error (add it to ``sᵀM⁻¹s``).
    """
    tu0, tu1, tu2, tv0, tv1, tv2, s_uu, s_uv, s_vv = tilt_schur(minv, tilt)
    qu0, qu1, qu2, qv0, qv1, qv2 = tilt[3], tilt[4], tilt[5], tilt[6], tilt[7], tilt[8]
    x0, x1, x2 = x
    s0, s1, s2 = s
    det = s_uu * s_vv - s_uv * s_uv
    if not det > RCOND * max(s_uu * s_vv, 1e-300):
        return math.nan, math.nan
    ru = tilt[9] - (qu0 * x0 + qu1 * x1 + qu2 * x2)
    rv = tilt[10] - (qv0 * x0 + qv1 * x1 + qv2 * x2)
    drop = (s_vv * ru * ru - 2.0 * s_uv * ru * rv + s_uu * rv * rv) / det
    du = tilt[11] - (tu0 * s0 + tu1 * s1 + tu2 * s2)
    dv = tilt[12] - (tv0 * s0 + tv1 * s1 + tv2 * s2)
    extra = (s_vv * du * du - 2.0 * s_uv * du * dv + s_uu * dv * dv) / det
    return drop, extra


@jit
def three_unknown_parts(p, errors, normal, residual, shared, w, x, tilt):
    """Row p of the standard errors' parts of a 3-unknown fit of ``w = (e, f, g)``
    (:func:`curv.uncertainty.parts.store_parts`; :mod:`curv.uncertainty.pooling` finishes them).

    With a shared count > 0, the centre's own height error enters every equation alike: the errors
    are modelled as ``eps_q + delta`` (independent, all of variance sigma²) and s = Σ rows. Then

    - ``E[RSS] = sigma² (m - 3 + shared - sᵀM⁻¹s)`` gives sigma², and
    - ``var(k) = sigma² (gᵀM⁻¹g + (gᵀM⁻¹s)²)`` with g the gradient of :func:`principal_gradients`
      (the unknowns are (e, f, g) or their negatives: a gradient's sign does not change a variance).

    With no shared count the errors are independent: ``sigma² = RSS / (m - 3)``, ``var(k) = sigma² gᵀM⁻¹g``.

    With ``tilt`` (:func:`add_tilt`), sigma² is read from the residuals of the fit with the frame's
    tilt as two more unknowns: ``RSS₅ / (m - 5 + shared - s₅ᵀM₅⁻¹s₅)``. Both add the eigen step's
    bias (:func:`eigen_bias`) to the variance.

    Parameters
    ----------
    p : int
    errors : Errors or None
        Nothing is written without (no standard errors asked).
    normal : 6-tuple of float
        M = AᵀA (upper triangle).
    residual : (float, float, int)
        ``(bᵀb, xᵀAᵀb, m)``: m equations.
    shared : (int, float, float, float)
        The equations sharing the centre's error (m or 0) and their row sum s.
    w, x : 3-tuples of float
        W and the solution.
    tilt : 13-tuple of float or None
        The frame tilt's sums; None: the noise level from the plain residuals.
    """
    if errors is None:
        return
    a00, a01, a02, a11, a12, a22 = normal
    bb, xatb, m = residual
    count, s0, s1, s2 = shared
    e, f, g = w
    minv = sym3_inverse(a00, a01, a02, a11, a12, a22)
    g10, g11, g12, g20, g21, g22 = principal_gradients(e, f, g)
    a0, a1, a2, h0, h1, h2 = deviator_gradients(e, f, g)
    k1_grad, k2_grad = (g10, g11, g12), (g20, g21, g22)
    along, across, s = (a0, a1, a2), (h0, h1, h2), (s0, s1, s2)
    var1 = sym3_bilinear(minv, k1_grad, k1_grad)
    var2 = sym3_bilinear(minv, k2_grad, k2_grad)
    vard = sym3_bilinear(minv, along, along) + sym3_bilinear(minv, across, across)
    dof = m - 3.0
    if count > 0:
        dof += count - sym3_bilinear(minv, s, s)
        gs1 = sym3_bilinear(minv, k1_grad, s)
        gs2 = sym3_bilinear(minv, k2_grad, s)
        as_ = sym3_bilinear(minv, along, s)
        hs = sym3_bilinear(minv, across, s)
        var1 += gs1 * gs1
        var2 += gs2 * gs2
        vard += as_ * as_ + hs * hs
    rss = bb - xatb
    rss, dof, m = _without_tilt(minv, x, s, tilt, rss, dof, m, count)
    store_parts(p, errors, var1, var2, rss, dof if m > 3 else 0.0, vard, math.hypot(0.5 * (e - g), f))


@jit
def _without_tilt(minv, x, s, tilt, rss, dof, m, count):
    """``(rss, dof, m)`` of the fit with the frame's tilt as two more unknowns (:func:`tilt_residual`);
    as they are without ``tilt`` (None)."""
    if tilt is None:
        return rss, dof, m
    drop, extra = tilt_residual(minv, x, s, tilt)
    return rss - drop, dof - (2.0 + (extra if count > 0 else 0.0)), m - 2


@jit
def sym3_sandwich(minv, meat, g):
    """``tᵀ B t + (tᵀ s)²`` with ``t = M⁻¹ g`` (M⁻¹ the 6-tuple ``minv``; B, s the weighted sums in
    ``meat``, :func:`weighted_parts`): the variance of ``gᵀx`` per unit height variance."""
    i00, i01, i02, i11, i12, i22 = minv
    g0, g1, g2 = g
    t0 = i00 * g0 + i01 * g1 + i02 * g2
    t1 = i01 * g0 + i11 * g1 + i12 * g2
    t2 = i02 * g0 + i12 * g1 + i22 * g2
    shared = t0 * meat[1] + t1 * meat[2] + t2 * meat[3]
    return (t0 * (meat[6] * t0 + meat[7] * t1 + meat[8] * t2) + t1 * (meat[7] * t0 + meat[9] * t1 + meat[10] * t2)
            + t2 * (meat[8] * t0 + meat[10] * t1 + meat[11] * t2) + shared * shared)


@jit
def weighted_parts(p, errors, normal, residual, w, x, tilt, meat):
    """Row p of the standard errors' parts of a 3-unknown fit whose equations' errors are known
    multiples of height errors: equation j's error is ``c_j (h_q - h_p)``, with h the heights' errors
    (independent, one variance sigma_h²) and q its neighbour (nc: a normal curvature ``2 w / l²``
    moves by ``c_j = 2 / l²`` per unit height, so its noise grows toward the near neighbours).

    The errors' covariance is ``sigma_h² (C² + c cᵀ)`` (C = diag(c), the centre's height shared by
    all), so with the sandwich ``B = Σ c_j² a_j a_jᵀ`` and ``s = Σ c_j a_j``:

    - ``var(gᵀx) = sigma_h² (gᵀM⁻¹BM⁻¹g + (gᵀM⁻¹s)²)``;
    - ``E[RSS] = sigma_h² tr((I - H)(C² + c cᵀ)) = sigma_h² (2 Σ c² - tr(M⁻¹B) - sᵀM⁻¹s)``.

    The noise level is read, as in :func:`three_unknown_parts`, from the residuals of the fit with
    the frame's tilt as two more unknowns (L their columns; whatever the tilt, it leaves no trace in
    them): ``RSS₅ = RSS₃ - r_Lᵀ S⁻¹ r_L``, and the hat matrix grows by ``Kᵀ S⁻¹ K`` with ``K = [-T, I]``,
    ``T = LᵀQ M⁻¹``, which takes ``tr(S⁻¹ K B₅ Kᵀ) + d_Lᵀ S⁻¹ d_L`` (``d_L = s_L - T s``) more from
    ``E[RSS] / sigma_h²``. ``sigma_h²`` is a height variance, so it pools across vertices in one unit.

    Parameters
    ----------
    p, errors, normal, residual, w, x :
        As in :func:`three_unknown_parts` (M unweighted: the fit's own normal equations).
    tilt : 13-tuple of float
        The tilt columns' sums (:func:`add_tilt`).
    meat : 21-tuple of float
        ``Σ c²``, ``s = Σ c a`` (3), ``s_L = Σ c L`` (2), ``B_QQ = Σ c² a aᵀ`` (upper triangle, 6),
        ``B_LQ = Σ c² L aᵀ`` (row u: 3, row v: 3), ``B_LL = Σ c² L Lᵀ`` (3)
        (:func:`normal_curvature_meat`).
    """
    if errors is None:
        return
    a00, a01, a02, a11, a12, a22 = normal
    bb, xatb, m = residual
    e, f, g = w
    minv = sym3_inverse(a00, a01, a02, a11, a12, a22)
    i00, i01, i02, i11, i12, i22 = minv
    g10, g11, g12, g20, g21, g22 = principal_gradients(e, f, g)
    a0, a1, a2, h0, h1, h2 = deviator_gradients(e, f, g)
    var1 = sym3_sandwich(minv, meat, (g10, g11, g12))
    var2 = sym3_sandwich(minv, meat, (g20, g21, g22))
    vard = sym3_sandwich(minv, meat, (a0, a1, a2)) + sym3_sandwich(minv, meat, (h0, h1, h2))
    sc0, sc1, sc2 = meat[1], meat[2], meat[3]
    b0, b1, b2, b3, b4, b5 = meat[6], meat[7], meat[8], meat[9], meat[10], meat[11]
    # tr(M⁻¹ B) and sᵀM⁻¹s
    trace = i00 * b0 + i11 * b3 + i22 * b5 + 2.0 * (i01 * b1 + i02 * b2 + i12 * b4)
    spare = 2.0 * meat[0] - trace - sym3_bilinear(minv, (sc0, sc1, sc2), (sc0, sc1, sc2))
    drop, _ = tilt_residual(minv, x, (0.0, 0.0, 0.0), tilt)
    rss = bb - xatb - drop
    # the tilt's share of the hat matrix
    tu0, tu1, tu2, tv0, tv1, tv2, s_uu, s_uv, s_vv = tilt_schur(minv, tilt)
    det = s_uu * s_vv - s_uv * s_uv
    # K B₅ Kᵀ = B_LL - T B_QL - B_LQ Tᵀ + T B_QQ Tᵀ (2 x 2)
    bq_tu0 = b0 * tu0 + b1 * tu1 + b2 * tu2  # B_QQ Tᵀ, column u
    bq_tu1 = b1 * tu0 + b3 * tu1 + b4 * tu2
    bq_tu2 = b2 * tu0 + b4 * tu1 + b5 * tu2
    bq_tv0 = b0 * tv0 + b1 * tv1 + b2 * tv2
    bq_tv1 = b1 * tv0 + b3 * tv1 + b4 * tv2
    bq_tv2 = b2 * tv0 + b4 * tv1 + b5 * tv2
    lu0, lu1, lu2, lv0, lv1, lv2 = meat[12], meat[13], meat[14], meat[15], meat[16], meat[17]
    k_uu = (meat[18] - 2.0 * (tu0 * lu0 + tu1 * lu1 + tu2 * lu2)
            + tu0 * bq_tu0 + tu1 * bq_tu1 + tu2 * bq_tu2)
    k_uv = (meat[19] - (tu0 * lv0 + tu1 * lv1 + tu2 * lv2) - (tv0 * lu0 + tv1 * lu1 + tv2 * lu2)
            + tu0 * bq_tv0 + tu1 * bq_tv1 + tu2 * bq_tv2)
    k_vv = (meat[20] - 2.0 * (tv0 * lv0 + tv1 * lv1 + tv2 * lv2)
            + tv0 * bq_tv0 + tv1 * bq_tv1 + tv2 * bq_tv2)
    du = meat[4] - (tu0 * sc0 + tu1 * sc1 + tu2 * sc2)
    dv = meat[5] - (tv0 * sc0 + tv1 * sc1 + tv2 * sc2)
    if det > RCOND * max(s_uu * s_vv, 1e-300):
        # tr(S⁻¹ K B₅ Kᵀ) + d_Lᵀ S⁻¹ d_L
        spare -= (s_vv * k_uu - 2.0 * s_uv * k_uv + s_uu * k_vv + s_vv * du * du - 2.0 * s_uv * du * dv
                  + s_uu * dv * dv) / det
    else:
        rss = math.nan
    store_parts(p, errors, var1, var2, rss, spare if m > 5 else 0.0, vard, math.hypot(0.5 * (e - g), f))


@jit
def offsets_room(errors, offsets, count):
    """``offsets`` (rows, 2) grown to hold a support of ``count`` (:func:`keep_offset`); as it is
    without ``errors`` (None)."""
    if errors is None or offsets.shape[0] >= count:
        return offsets
    return np.empty((count, 2))


@jit
def keep_offset(errors, offsets, j, u, v):
    """Keep equation j's tangent offset (u, v) for :func:`normal_curvature_meat`; nothing without
    ``errors`` (None)."""
    if errors is None:
        return
    offsets[j, 0] = u
    offsets[j, 1] = v


NO_MOMENTS = (0.0,) * 18


@jit_inlined
def _add_moments(s, u, v):
    """The 18 moments of :func:`normal_curvature_meat` with the offset (u, v) added: ``ρ²`` times
    (1, u², uv, v², u, v) and ``ρ⁴`` times (u⁴, u³v, u²v², uv³, v⁴, u³, u²v, uv², v³, u², uv, v²),
    ``ρ = 1 / (u² + v²)``."""
    rho = 1.0 / (u * u + v * v)
    r2 = rho * rho
    r4 = r2 * r2
    uu, uv, vv = u * u, u * v, v * v
    fu, fv, fuu, fuv, fvv = r4 * u, r4 * v, r4 * uu, r4 * uv, r4 * vv
    return (s[0] + r2, s[1] + r2 * uu, s[2] + r2 * uv, s[3] + r2 * vv, s[4] + r2 * u, s[5] + r2 * v,
            s[6] + fuu * uu, s[7] + fuu * uv, s[8] + fuu * vv, s[9] + fuv * vv, s[10] + fvv * vv,
            s[11] + fuu * u, s[12] + fuu * v, s[13] + fu * vv, s[14] + fvv * v, s[15] + fuu, s[16] + fuv,
            s[17] + fvv)


@jit
def normal_curvature_meat(offsets, used):
    """:func:`weighted_parts`' sums for normal-curvature equations from their tangent offsets
    ``offsets[:used]``.

    ``kn = 2 h / l²`` moves by ``c = 2 / l²`` per unit height of q (or of p, the other way), and with
    ``ρ = 1 / l²`` the rows are ``a = ρ (u², 2uv, v²)`` and the tilt's ``L = ρ (u, v)``, so the sums
    are 18 moments of u and v weighted by ρ² and ρ⁴ (:func:`_add_moments`).

    Returns
    -------
    21-tuple of float
        ``Σ c²``, ``s = Σ c a``, ``s_L = Σ c L``, ``B_QQ = Σ c² a aᵀ``, ``B_LQ = Σ c² L aᵀ``,
        ``B_LL = Σ c² L Lᵀ``.
    """
    m = NO_MOMENTS
    for j in range(used):
        m = _add_moments(m, offsets[j, 0], offsets[j, 1])
    m0, p20, p11, p02, p10, p01, q40, q31, q22, q13, q04, k30, k21, k12, k03, l20, l11, l02 = m
    return (4.0 * m0, 2.0 * p20, 4.0 * p11, 2.0 * p02, 2.0 * p10, 2.0 * p01,
            4.0 * q40, 8.0 * q31, 4.0 * q22, 16.0 * q22, 8.0 * q13, 4.0 * q04,
            4.0 * k30, 8.0 * k21, 4.0 * k12, 4.0 * k21, 8.0 * k12, 4.0 * k03,
            4.0 * l20, 4.0 * l11, 4.0 * l02)


@jit
def normal_curvature_parts(p, errors, normal, residual, w, tilt, offsets):
    """Row p of the standard errors' parts of nc, whose unknowns are W's entries ``w`` and whose
    equations' errors are ``2 / l²`` times their heights' (:func:`weighted_parts`, with the sums of
    :func:`normal_curvature_meat` over the first ``m`` of ``offsets``). Nothing without ``errors``."""
    if errors is None:
        return
    weighted_parts(p, errors, normal, residual, w, w, tilt, normal_curvature_meat(offsets, residual[2]))
