"""Goldfeather & Interrante (2004) fits, extended to any range (paper §4.1).

For every neighbour q of vertex p in range, with ``(u, v, w)`` the offset ``q - p`` in p's frame
(U, V, N) and W = [[e, f], [f, g]] the shape operator in (U, V):

- ``nc``: normal curvature approximation, one equation per neighbour:
  ``t^T W t = kn`` with t = (u, v)/|(u, v)| and ``kn = 2 (p - q).N / |p - q|^2``.
- ``qs``: quadratic height fit ``w = A/2 u^2 + B u v + C/2 v^2``, W = -[[A, B], [B, C]].
- ``an``: adjacent-normal cubic fit: the quadratic plus four cubic terms
  ``D u^3 + E u^2 v + F u v^2 + G v^3``; the neighbour's normal N_q = (a, b, c) in p's frame gives
  the slopes ``w_u = -a/c`` and ``w_v = -b/c`` (7 unknowns, 3 equations per neighbour).

All three work on any polygon mesh and on borders (the fit is one-sided there; the API marks the
border vertices themselves). Each is one kernel: the ball search and the normal equations run
neighbour by neighbour (:mod:`curv.estimators._local_fit`).
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np

from ..core.jit import jit, jit_inlined, jit_parallel, prange
from ..core.mesh import Mesh
from ..geometry.neighbourhood import ball_support, start_ball_support, widen_ball_support
from ._local_fit import (DEFAULT_NOISE_MODEL, MIN_PAIRS, MIN_TANGENT_LENGTH, NOISE_MODELS, SE_PARTS_BYTES, SLOT_BYTES,
                         add_ring_columns, centre_columns, deviator_gradients, factor_whiten, finish_fit,
                         fit_frame, list_room, list_slot, checked_noise_model, normal_in_frame, offset_in_frame,
                         principal_gradients, row_dot, run_fit, slice_bounds, solve_scaled, solve_sym3, start_levels, store_parts,
                         store_se3, store_se3_weighted)
from ._pooling import POOL_KERNEL
from .registry import EstimatorSpec, register

MIN_NORMAL_Z = 0.1
"""A neighbour normal tilted more than ~84 degrees from the centre normal gives no slope equation."""


@jit
def _nc_qs_row(u, v, w, l2, nc):
    """The equation of a neighbour at offset ``(u, v, w)`` (``l2 = u² + v²``) in p's frame: nc's
    (``nc`` True) or qs's row, right-hand side, and the columns of the frame's tilt (the standard
    error's). Returns ``(c0, c1, c2, rhs, lu, lv)``."""
    if nc:
        rhs = -2.0 * w / (l2 + w * w)  # kn
        # row (tu^2, 2 tu tv, tv^2) of the unit tangent t = (u, v)/|(u, v)|
        # a tilt of the frame adds (u, v) / l² times its slopes to kn (the standard error's columns)
        return u * u / l2, 2.0 * u * v / l2, v * v / l2, rhs, u / l2, v / l2
    # w = A/2 u^2 + B uv + C/2 v^2; a tilt of the frame adds a linear term to w
    return 0.5 * u * u, u * v, 0.5 * v * v, w, u, v


@jit_inlined
def _nc_qs_at(p, queue, count, r, x, y, z, nx, ny, nz, k1, k2, d1, d2, reason, k1_se, k2_se, se_parts, tilt, meat,
              offs, nc):
    """The 3-unknown fit at vertex p over its support ``queue[1:count]``: normal-curvature least
    squares (``nc`` True) or the quadratic height fit; ``tilt`` (13,) and ``meat`` (21,) are scratch
    for the frame-tilt columns of the standard error (:func:`store_se3`) and nc's weighted sums
    (:func:`store_se3_weighted`), written once after the loop; ``offs`` (rows, 2) keeps nc's tangent
    offsets for its second pass (grown, perhaps, and returned)."""
    n0, n1, n2, frame, ok = fit_frame(p, nx, ny, nz, k1, k2, d1, d2, reason, se_parts)
    if not ok:
        return offs
    errors = se_parts.shape[0] > 0  # no rows: no standard errors asked, their sums are skipped
    if nc and errors and offs.shape[0] < count:
        offs = np.empty((count, 2))
    tiny2 = (MIN_TANGENT_LENGTH * r) ** 2
    a00 = a01 = a02 = a11 = a12 = a22 = b0 = b1 = b2 = bb = s0 = s1 = s2 = 0.0
    # the standard error's sums in local scalars (array entries cost a load and a store per neighbour):
    # the tilt columns' ``LᵀL``, ``LᵀQ``, ``Lᵀb`` and row sums (t0-t12,
    # :func:`~curv.estimators._local_fit.tilt_residual`)
    t0 = t1 = t2 = t3 = t4 = t5 = t6 = t7 = t8 = t9 = t10 = t11 = t12 = 0.0
    used = 0
    for i in range(1, count):
        q = queue[i]
        u, v, w = offset_in_frame(p, q, x, y, z, frame, n0, n1, n2)
        l2 = u * u + v * v
        if not (l2 > tiny2):
            continue
        if nc and errors:
            offs[used, 0] = u
            offs[used, 1] = v
        used += 1
        c0, c1, c2, rhs, lu, lv = _nc_qs_row(u, v, w, l2, nc)
        if errors:
            t0 += lu * lu
            t1 += lu * lv
            t2 += lv * lv
            t3 += lu * c0
            t4 += lu * c1
            t5 += lu * c2
            t6 += lv * c0
            t7 += lv * c1
            t8 += lv * c2
            t9 += lu * rhs
            t10 += lv * rhs
            t11 += lu
            t12 += lv
        a00 += c0 * c0
        a01 += c0 * c1
        a02 += c0 * c2
        a11 += c1 * c1
        a12 += c1 * c2
        a22 += c2 * c2
        b0 += c0 * rhs
        b1 += c1 * rhs
        b2 += c2 * rhs
        bb += rhs * rhs
        s0 += c0
        s1 += c1
        s2 += c2
    tilt[0], tilt[1], tilt[2], tilt[3], tilt[4], tilt[5], tilt[6] = t0, t1, t2, t3, t4, t5, t6
    tilt[7], tilt[8], tilt[9], tilt[10], tilt[11], tilt[12] = t7, t8, t9, t10, t11, t12
    if nc and errors:
        # nc's weighted sums (:func:`~curv.estimators._local_fit.store_se3_weighted`) in a second pass
        # over the support's offsets (kept in the first): kn = 2 h / l² moves by c = 2 / l² per unit
        # height of q (or of p, the other way), and with ρ = 1 / l² the rows are a = ρ (u², 2uv, v²)
        # and L = ρ (u, v), so the sums are 18 moments of u and v weighted by ρ² and ρ⁴
        m0 = p20 = p11 = p02 = p10 = p01 = 0.0
        q40 = q31 = q22 = q13 = q04 = k30 = k21 = k12 = k03 = l20 = l11 = l02 = 0.0
        for j in range(used):
            u, v = offs[j, 0], offs[j, 1]
            rho = 1.0 / (u * u + v * v)
            r2 = rho * rho
            r4 = r2 * r2
            uu, uv, vv = u * u, u * v, v * v
            m0 += r2
            p20 += r2 * uu
            p11 += r2 * uv
            p02 += r2 * vv
            p10 += r2 * u
            p01 += r2 * v
            fu, fv, fuu, fuv, fvv = r4 * u, r4 * v, r4 * uu, r4 * uv, r4 * vv
            q40 += fuu * uu
            q31 += fuu * uv
            q22 += fuu * vv
            q13 += fuv * vv
            q04 += fvv * vv
            k30 += fuu * u
            k21 += fuu * v
            k12 += fu * vv
            k03 += fvv * v
            l20 += fuu
            l11 += fuv
            l02 += fvv
        # Σ c², s = Σ c a, s_L = Σ c L, B_QQ = Σ c² a aᵀ, B_LQ = Σ c² L aᵀ, B_LL = Σ c² L Lᵀ
        meat[0], meat[1], meat[2], meat[3], meat[4], meat[5] = 4.0 * m0, 2.0 * p20, 4.0 * p11, 2.0 * p02, 2.0 * p10, 2.0 * p01
        meat[6], meat[7], meat[8], meat[9], meat[10], meat[11] = 4.0 * q40, 8.0 * q31, 4.0 * q22, 16.0 * q22, 8.0 * q13, 4.0 * q04
        meat[12], meat[13], meat[14], meat[15], meat[16], meat[17] = 4.0 * k30, 8.0 * k21, 4.0 * k12, 4.0 * k21, 8.0 * k12, 4.0 * k03
        meat[18], meat[19], meat[20] = 4.0 * l20, 4.0 * l11, 4.0 * l02
    x0, x1, x2, singular = solve_sym3(a00, a01, a02, a11, a12, a22, b0, b1, b2)
    # nc solves for W = (e, f, g); qs for the Hessian of the height along N, W = -(A, B, C)
    sign = 1.0 if nc else -1.0
    e, f, g = sign * x0, sign * x1, sign * x2
    finish_fit(p, e, f, g, singular, used, frame, k1, k2, d1, d2, reason)
    if nc:
        # each equation's error is its heights' difference times 2 / l² (docs/UNCERTAINTY.md)
        store_se3_weighted(p, a00, a01, a02, a11, a12, a22, bb, x0 * b0 + x1 * b1 + x2 * b2, used, e, f, g, x0, x1,
                           x2, tilt, meat, k1_se, k2_se, se_parts)
        return offs
    # p's own height error enters every equation alike (docs/UNCERTAINTY.md)
    store_se3(p, a00, a01, a02, a11, a12, a22, bb, x0 * b0 + x1 * b1 + x2 * b2, used, used, s0, s1, s2,
              e, f, g, k1_se, k2_se, se_parts, x0, x1, x2, tilt)
    return offs


@jit
def _scaled_offset(p, q, x, y, z, inv_r, frame, n0, n1, n2):
    """The offset ``(q - p) / r`` in p's frame (U, V, N = (n0, n1, n2)): ``(u, v, w)``."""
    ux, uy, uz, vx, vy, vz = frame
    dx, dy, dz = (x[q] - x[p]) * inv_r, (y[q] - y[p]) * inv_r, (z[q] - z[p]) * inv_r
    return dx * ux + dy * uy + dz * uz, dx * vx + dy * vy + dz * vz, dx * n0 + dy * n1 + dz * n2


@jit
def _height_row(u, v, row):
    """``row`` (7,): the height equation's ``(u²/2, uv, v²/2, u³, u²v, uv², v³)``."""
    uu, uv, vv = u * u, u * v, v * v
    row[0], row[1], row[2] = 0.5 * uu, uv, 0.5 * vv
    row[3], row[4], row[5], row[6] = uu * u, uu * v, u * vv, vv * v


@jit
def _slope_rows(u, v, ru, rv):
    """``ru``, ``rv`` (7,): the slope equations' rows, ``w_u``: (u, v, 0, 3u², 2uv, v², 0) and
    ``w_v``: (0, u, v, 0, u², 2uv, 3v²)."""
    uu, uv, vv = u * u, u * v, v * v
    ru[0], ru[1], ru[2], ru[3], ru[4], ru[5], ru[6] = u, v, 0.0, 3.0 * uu, 2.0 * uv, vv, 0.0
    rv[0], rv[1], rv[2], rv[3], rv[4], rv[5], rv[6] = 0.0, u, v, 0.0, uu, 2.0 * uv, 3.0 * vv


AN_SUMS = 35
"""The normal equations of an's 7 unknowns as one tuple of scalars: the upper triangle of ``AᵀA``
row by row (28 entries), then ``Aᵀb`` (7): :func:`_add_height`, :func:`_add_slopes`."""
NO_SUMS = (0.0,) * AN_SUMS
"""The sums before any equation."""


@jit_inlined
def _add_height(s, u, v, w):
    """The sums ``s`` (:data:`AN_SUMS` float tuple) with the height equation
    ``(u²/2, uv, v²/2, u³, u²v, uv², v³) · x = w`` (:func:`_height_row`) added.

    Scalars, not arrays: each product lands in a register, where a row array and a loop over it
    cost a load and a store per entry."""
    uu, uv, vv = u * u, u * v, v * v
    h0, h1, h2, h3, h4, h5, h6 = 0.5 * uu, uv, 0.5 * vv, uu * u, uu * v, u * vv, vv * v
    return (
            s[0] + h0 * h0, s[1] + h0 * h1, s[2] + h0 * h2, s[3] + h0 * h3, s[4] + h0 * h4, s[5] + h0 * h5,
            s[6] + h0 * h6, s[7] + h1 * h1, s[8] + h1 * h2, s[9] + h1 * h3, s[10] + h1 * h4, s[11] + h1 * h5,
            s[12] + h1 * h6, s[13] + h2 * h2, s[14] + h2 * h3, s[15] + h2 * h4, s[16] + h2 * h5, s[17] + h2 * h6,
            s[18] + h3 * h3, s[19] + h3 * h4, s[20] + h3 * h5, s[21] + h3 * h6, s[22] + h4 * h4, s[23] + h4 * h5,
            s[24] + h4 * h6, s[25] + h5 * h5, s[26] + h5 * h6, s[27] + h6 * h6, s[28] + h0 * w, s[29] + h1 * w,
            s[30] + h2 * w, s[31] + h3 * w, s[32] + h4 * w, s[33] + h5 * w, s[34] + h6 * w,
    )


@jit_inlined
def _add_slopes(s, u, v, a, b):
    """The sums ``s`` (:data:`AN_SUMS` float tuple) with the slope equations ``w_u = a`` and
    ``w_v = b`` (:func:`_slope_rows`) added, the u-slope's products before the v-slope's; their
    rows' zeros are left out."""
    uu, uv2, vv = u * u, 2.0 * (u * v), v * v
    su3, sv3 = 3.0 * uu, 3.0 * vv
    return (
            s[0] + u * u, s[1] + u * v, s[2], s[3] + u * su3, s[4] + u * uv2, s[5] + u * vv, s[6],
            s[7] + v * v + u * u, s[8] + u * v, s[9] + v * su3, s[10] + v * uv2 + u * uu, s[11] + v * vv + u * uv2,
            s[12] + u * sv3, s[13] + v * v, s[14], s[15] + v * uu, s[16] + v * uv2, s[17] + v * sv3, s[18] + su3 * su3,
            s[19] + su3 * uv2, s[20] + su3 * vv, s[21], s[22] + uv2 * uv2 + uu * uu, s[23] + uv2 * vv + uu * uv2,
            s[24] + uu * sv3, s[25] + vv * vv + uv2 * uv2, s[26] + uv2 * sv3, s[27] + sv3 * sv3, s[28] + u * a,
            s[29] + v * a + u * b, s[30] + v * b, s[31] + su3 * a, s[32] + uv2 * a + uu * b, s[33] + vv * a + uv2 * b,
            s[34] + sv3 * b,
    )


@jit
def _normal_equations(t2, h, s, ata, atb):
    """``ata`` (7, 7) and ``atb`` (7,) from the sums ``h`` times ``t2`` plus ``s`` (both
    :data:`AN_SUMS` tuples; ``t2 = 0``: ``s`` alone, as it is)."""
    k = 0
    for i in range(7):
        for j in range(i, 7):
            ata[i, j] = ata[j, i] = t2 * h[k] + s[k]
            k += 1
        atb[i] = t2 * h[28 + i] + s[28 + i]


@jit
def _an_noise_model(p, queue, count, inv_r, x, y, z, nx, ny, nz, frame, ring_ptr, ring, slots, touched, yv, jp,
                    factor, grads, row, ru, rv, agg, wrow):
    """an's equations' errors as noisy heights make them (the model of mru's ``_noise_model``).

    With independent height errors h (variance sigma_h²), vertex normals tilted by their ring's height
    gradient (:func:`~curv.estimators._local_fit.ring_gradient`: ``J_v h``) and p's normal (the frame)
    tilted by ``J_p h``, in the radius-scaled coordinates (U, V) = (u, v) / r:

    - a height equation's error is ``(h_q - h_p) / r - (U, V) · J_p h`` (the frame's tilt moves every
      height by its slope times the offset);
    - a slope equation's is ``(J_q - J_p) h``, row u or v.

    Neighbouring normals share vertices, and every equation shares p's height and normal, so the
    errors are correlated; the propagation follows them: with ``y_j = Σ_eq A_eqᵀ J̃_eq,j`` the fit's
    error is ``M⁻¹ Σ_j y_j h_j``, ``var(gᵀx) = sigma_h² Σ_j (gᵀM⁻¹y_j)²`` and ``E[RSS] = sigma_h²
    (‖J̃‖² - Σ_j y_jᵀM⁻¹y_j)``.

    Parameters
    ----------
    factor : (8, 7) float64
        M's scaled Cholesky factor (:func:`~curv.estimators._local_fit.cholesky_scaled`, scales in row 7).
    grads : (7, 7) float64
        Rows 0, 1, 5, 6 whitened (:func:`~curv.estimators._local_fit.factor_whiten`): the gradients of
        k1, k2 and the deviator's components over the 7 unknowns.
    row, ru, rv : (7,), agg : (5, 7), wrow : (1, 7) float64
        Scratch.

    Returns
    -------
    var1, var2, var_dev, spare : float
        ``var / sigma_h²`` (of the scaled unknowns) and ``E[RSS] / sigma_h²``.
    ok : bool
        False where a ring has no gradient.
    touched, yv, jp :
        The short lists (grown, perhaps).
    """
    n0, n1, n2 = nx[p], ny[p], nz[p]
    tiny2 = MIN_TANGENT_LENGTH ** 2
    touched, yv, jp = list_room(p, queue, count, ring_ptr, touched, yv, jp)
    var1 = var2 = vard = spare = 0.0
    agg[:, :] = 0.0  # Σ height rows, Σ height rows · U, · V, Σ u-slope rows, Σ v-slope rows
    used, ok, p00, p01, p11, _ = centre_columns(p, ring_ptr, ring, x, y, z, frame, slots, touched, yv, jp)
    sp = slots[p] - 1 if ok else 0
    if ok:
        for i in range(1, count):
            q = queue[i]
            u, v, _ = _scaled_offset(p, q, x, y, z, inv_r, frame, n0, n1, n2)
            if not (u * u + v * v > tiny2):
                continue
            uu, uv, vv = u * u, u * v, v * v
            _height_row(u, v, row)
            s, used = list_slot(q, slots, touched, yv, jp, used)
            for j in range(7):
                yv[s, j] += row[j] * inv_r
                agg[0, j] += row[j]
                agg[1, j] += row[j] * u
                agg[2, j] += row[j] * v
            # ‖(e_q - e_p) / r - U J_p0 - V J_p1‖²
            tq = u * jp[s, 0] + v * jp[s, 1]
            tp = u * jp[sp, 0] + v * jp[sp, 1]
            spare += (2.0 * inv_r * inv_r + uu * p00 + 2.0 * uv * p01 + vv * p11 - 2.0 * inv_r * (tq - tp))
            a, b, c = normal_in_frame(q, nx, ny, nz, frame, n0, n1, n2)
            if not (c > MIN_NORMAL_Z) or not (math.isfinite(a) and math.isfinite(b)):
                continue
            _slope_rows(u, v, ru, rv)
            for j in range(7):
                agg[3, j] += ru[j]
                agg[4, j] += rv[j]
            used, ok, jqn, cross = add_ring_columns(q, ring_ptr, ring, x, y, z, frame, slots, touched, yv, jp, used,
                                                    ru, rv)
            if not ok:
                break
            spare += jqn + p00 + p11 - 2.0 * cross
    for s in range(used):
        if ok:
            # the shared parts: p's height (-Σ height rows / r) and p's normal, the frame's tilt
            c0, c1 = jp[s, 0], jp[s, 1]
            for j in range(7):
                wrow[0, j] = yv[s, j] - (agg[1, j] + agg[3, j]) * c0 - (agg[2, j] + agg[4, j]) * c1
                if s == sp:
                    wrow[0, j] -= agg[0, j] * inv_r
            factor_whiten(factor, factor, 7, 7, wrow)
            spare -= row_dot(wrow, 0, 0, 7)
            d1 = d2 = da = dh = 0.0
            for j in range(7):
                d1 += grads[0, j] * wrow[0, j]
                d2 += grads[1, j] * wrow[0, j]
                da += grads[5, j] * wrow[0, j]
                dh += grads[6, j] * wrow[0, j]
            var1 += d1 * d1
            var2 += d2 * d2
            vard += da * da + dh * dh
        slots[touched[s]] = 0
    return var1, var2, vard, spare, ok, touched, yv, jp


@jit
def _an_at(p, queue, count, r, x, y, z, nx, ny, nz, k1, k2, d1, d2, reason, k1_se, k2_se, se_parts, ata, atb, row, ru,
           rv, sol, grads, ring_ptr, ring, slots, touched, yv, jp, agg, wrow):
    """Adjacent-normal cubic fit at vertex p.

    Scratch: ``ata`` (8, 7): the normal equations, then their scaled Cholesky factor (the solve's,
    :func:`~curv.estimators._local_fit.solve_scaled`, and the standard error's); ``atb``, ``row``, ``ru``,
    ``rv``, ``sol`` (7,); ``grads`` (7, 7): the k1, k2 gradients, the three shared columns, the
    deviator's two components (the eigen step's bias, as in ``store_se3``).

    Heights and slopes enter the fit with equal weight in the radius-scaled coordinates. On a mesh
    the standard error models the equations' errors from the heights' (:func:`_an_noise_model`;
    more scratch: ``slots``, ``touched``, ``yv``, ``jp``, ``agg``, ``wrow``, and returns the short
    lists). Elsewhere (a point cloud, or a ring without a gradient) ``sigma²`` pools the two kinds of
    residual; p's own height error is shared by the height equations and the tilt of its normal by
    each kind of slope equation, modelled as in :func:`~curv.estimators._local_fit.store_se3`.
    """
    n0, n1, n2, frame, ok = fit_frame(p, nx, ny, nz, k1, k2, d1, d2, reason, se_parts)
    if not ok:
        return touched, yv, jp
    errors = se_parts.shape[0] > 0  # no rows: no standard errors asked, their sums are skipped
    # Heights are lengths, slopes are not: fit in coordinates divided by the ball radius so the
    # balance of the two kinds of equation (and so the result) does not depend on the mesh's scale.
    inv_r = 1.0 / r
    tiny2 = MIN_TANGENT_LENGTH ** 2
    sums = NO_SUMS
    bb = 0.0
    equations = 0
    sloped = 0
    # the sums of the height, u-slope and v-slope rows (rows 2-4 of grads below): of u², uv, v², u³, u²v,
    # uv², v³ over every neighbour, of u, v, 3u², u², 2uv, v², 3v² over the sloped ones
    h0 = h1 = h2 = h3 = h4 = h5 = h6 = r0 = r1 = r2 = r3 = r4 = r5 = r6 = 0.0
    used = 0
    for i in range(1, count):
        q = queue[i]
        u, v, w = _scaled_offset(p, q, x, y, z, inv_r, frame, n0, n1, n2)
        if not (u * u + v * v > tiny2):
            continue
        used += 1
        # height: w = A/2 u^2 + B uv + C/2 v^2 + D u^3 + E u^2 v + F u v^2 + G v^3
        sums = _add_height(sums, u, v, w)
        bb += w * w
        equations += 1
        if errors:
            uu, vv = u * u, v * v
            h0 += 0.5 * uu
            h1 += u * v
            h2 += 0.5 * vv
            h3 += uu * u
            h4 += uu * v
            h5 += u * vv
            h6 += vv * v
        a, b, c = normal_in_frame(q, nx, ny, nz, frame, n0, n1, n2)
        if not (c > MIN_NORMAL_Z) or not (math.isfinite(a) and math.isfinite(b)):
            continue
        # slopes of the neighbour's normal: w_u = -a/c, w_v = -b/c
        sums = _add_slopes(sums, u, v, -a / c, -b / c)
        if errors:
            uu, vv = u * u, v * v
            r0 += u
            r1 += v
            r2 += 3.0 * uu
            r3 += uu
            r4 += 2.0 * (u * v)
            r5 += vv
            r6 += 3.0 * vv
        bb += (a * a + b * b) / (c * c)
        equations += 2
        sloped += 1
    _normal_equations(0.0, sums, sums, ata, atb)
    singular, factored = solve_scaled(ata, 7, ata, atb, sol)
    # second derivatives back in unscaled coordinates
    e, f, g = -sol[0] * inv_r, -sol[1] * inv_r, -sol[2] * inv_r
    finish_fit(p, e, f, g, singular, used, frame, k1, k2, d1, d2, reason)
    if not errors:
        return touched, yv, jp
    xatb = 0.0
    for j in range(7):
        xatb += sol[j] * atb[j]
    height_sums = (h0, h1, h2, h3, h4, h5, h6)
    u_sums, v_sums = (r0, r1, 0.0, r2, r4, r5, 0.0), (0.0, r0, r1, 0.0, r3, r4, r6)
    for j in range(7):
        grads[2, j], grads[3, j], grads[4, j] = height_sums[j], u_sums[j], v_sums[j]
    # k_i's gradient over the 7 unknowns: (c², 2cs, s²) on the quadratic terms, 0 on the cubic ones
    for j in range(7):
        grads[0, j] = 0.0
        grads[1, j] = 0.0
    grads[0, 0], grads[0, 1], grads[0, 2], grads[1, 0], grads[1, 1], grads[1, 2] = principal_gradients(e, f, g)
    # the deviator's two components (the eigen step's bias, store_se3), on the quadratic terms too
    for j in range(7):
        grads[5, j] = 0.0
        grads[6, j] = 0.0
    grads[5, 0], grads[5, 1], grads[5, 2], grads[6, 0], grads[6, 1], grads[6, 2] = deviator_gradients(e, f, g)
    if equations > 7 and factored:
        factor_whiten(ata, ata, 7, 7, grads)
        scale = inv_r * inv_r  # the variances in unscaled coordinates
        if slots.size > 0 and ring.size > 0 and not singular:  # slots given: noise_model="normals"
            var1, var2, var_dev, spare, ok, touched, yv, jp = _an_noise_model(
                p, queue, count, inv_r, x, y, z, nx, ny, nz, frame, ring_ptr, ring, slots, touched, yv, jp,
                ata, grads, row, ru, rv, agg, wrow)
            if ok and spare > 0.0:
                store_parts(p, k1_se, k2_se, se_parts, var1 * scale, var2 * scale, bb - xatb, spare,
                            var_dev * scale, math.hypot(0.5 * (e - g), f))
                return touched, yv, jp
        # no mesh rings (a point cloud) or a ring without a gradient: the equations' errors taken
        # as independent but for p's shared height and normal; its noise level (of heights and
        # slopes alike) is pooled with no other vertex's
        dof = (equations - 7 + used - row_dot(grads, 2, 2, 7)
               + sloped - row_dot(grads, 3, 3, 7) + sloped - row_dot(grads, 4, 4, 7))
        var_dev = 0.0
        for i in range(5, 7):
            var_dev += row_dot(grads, i, i, 7)
            for shared in range(2, 5):
                var_dev += row_dot(grads, i, shared, 7) ** 2
        var1 = row_dot(grads, 0, 0, 7)
        var2 = row_dot(grads, 1, 1, 7)
        for shared in range(2, 5):
            var1 += row_dot(grads, 0, shared, 7) ** 2
            var2 += row_dot(grads, 1, shared, 7) ** 2
        store_parts(p, k1_se, k2_se, se_parts, var1 * scale, var2 * scale, bb - xatb, dof, var_dev * scale,
                    math.hypot(0.5 * (e - g), f))
        if se_parts.shape[0] > 0:
            se_parts[p, 1] = -se_parts[p, 1]
    return touched, yv, jp


@jit
def _nc_qs_add(p, queue, lo, hi, tiny2, band2, x, y, z, frame, n0, n1, n2, nc, acc):
    """Add the equations of the neighbours ``queue[lo:hi]`` whose tangent length squared exceeds
    ``tiny2`` to the 3-unknown fit's normal equations ``acc`` (9,): ``(a00, a01, a02, a11, a12,
    a22, b0, b1, b2)`` (:func:`_nc_qs_row`).

    Returns
    -------
    used : int
        The equations added.
    banded : bool
        Whether one of them has a tangent length squared of at most ``band2``.
    """
    a00, a01, a02, a11, a12, a22 = acc[0], acc[1], acc[2], acc[3], acc[4], acc[5]
    b0, b1, b2 = acc[6], acc[7], acc[8]
    used = 0
    banded = False
    for i in range(lo, hi):
        u, v, w = offset_in_frame(p, queue[i], x, y, z, frame, n0, n1, n2)
        l2 = u * u + v * v
        if not (l2 > tiny2):
            continue
        banded = banded or not (l2 > band2)
        used += 1
        c0, c1, c2, rhs, _, _ = _nc_qs_row(u, v, w, l2, nc)
        a00 += c0 * c0
        a01 += c0 * c1
        a02 += c0 * c2
        a11 += c1 * c1
        a12 += c1 * c2
        a22 += c2 * c2
        b0 += c0 * rhs
        b1 += c1 * rhs
        b2 += c2 * rhs
    acc[0], acc[1], acc[2], acc[3], acc[4], acc[5] = a00, a01, a02, a11, a12, a22
    acc[6], acc[7], acc[8] = b0, b1, b2
    return used, banded


@jit
def _nc_qs_levels_at(p, radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamp, queue, waiting, waiting_d2, k1, k2, d1, d2,
                     reason, acc, nc):
    """nc (``nc`` True) or qs at vertex p at every level of ``radii`` (levels, n), in one walk
    (:func:`~curv.estimators._local_fit.run_fit_levels`): the equations of each level's new
    vertices are added to the last level's sums (their rows do not depend on the radius). A row whose
    tangent length is so short that a wider level's bound would drop it (``banded``) makes the
    following levels add up their whole support again, each with its own bound."""
    n0, n1, n2, frame, band2, ok = start_levels(p, radii, nx, ny, nz, k1, k2, d1, d2, reason)
    if not ok:
        return
    levels = radii.shape[0]
    count = start_ball_support(p, stamp, queue)
    head = pending = used = 0
    done = 1
    banded = False
    acc[:] = 0.0
    for level in range(levels):
        r = radii[level, p]
        count, head, pending = widen_ball_support(p, r ** 2, level + 1 < levels, adj_ptr, adj, x, y, z, stamp, queue,
                                                  count, head, waiting, waiting_d2, pending)
        if banded:
            acc[:] = 0.0
            used = 0
            done = 1
            banded = False
        added, new_band = _nc_qs_add(p, queue, done, count, (MIN_TANGENT_LENGTH * r) ** 2, band2, x, y, z, frame,
                                     n0, n1, n2, nc, acc)
        used += added
        banded = banded or new_band
        done = count
        x0, x1, x2, singular = solve_sym3(acc[0], acc[1], acc[2], acc[3], acc[4], acc[5], acc[6], acc[7], acc[8])
        # nc solves for W = (e, f, g); qs for the Hessian of the height along N, W = -(A, B, C)
        sign = 1.0 if nc else -1.0
        finish_fit(p, sign * x0, sign * x1, sign * x2, singular, used, frame, k1[level], k2[level], d1[level],
                   d2[level], reason[level])


@jit
def _an_levels_at(p, radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamp, queue, waiting, waiting_d2, k1, k2, d1, d2,
                  reason, ata, atb, sol):
    """an at vertex p at every level of ``radii`` (levels, n), in one walk
    (:func:`~curv.estimators._local_fit.run_fit_levels`).

    A level of radius r fits in coordinates divided by r (:func:`_an_at`); written in coordinates
    divided by the widest radius R instead, its height equations are the same ones multiplied by
    ``t = R / r`` and its slope equations the same, with the unknowns rescaled by a diagonal
    (``t`` on the quadratic terms, ``t²`` on the cubic ones). So the height and slope equations are
    summed apart in R's coordinates (two :data:`AN_SUMS` tuples), level by level, and each level
    solves ``(t² H + S) y = t² h + s``: the Jacobi-scaled solve
    (:func:`~curv.estimators._local_fit.solve_scaled`) does not depend on the diagonal, and the
    second derivatives come back as ``-y / R``. Rows short enough for a wider level to drop: as in
    :func:`_nc_qs_levels_at`. Scratch: ``ata`` (8, 7), ``atb``, ``sol`` (7,)."""
    n0, n1, n2, frame, _, ok = start_levels(p, radii, nx, ny, nz, k1, k2, d1, d2, reason)
    if not ok:
        return
    levels = radii.shape[0]
    widest = radii[levels - 1, p]
    inv_w = 1.0 / widest
    band2 = MIN_TANGENT_LENGTH ** 2
    count = start_ball_support(p, stamp, queue)
    head = pending = used = 0
    done = 1
    banded = True  # clears the sums below
    heights = slopes = NO_SUMS
    for level in range(levels):
        r = radii[level, p]
        count, head, pending = widen_ball_support(p, r ** 2, level + 1 < levels, adj_ptr, adj, x, y, z, stamp, queue,
                                                  count, head, waiting, waiting_d2, pending)
        if banded:
            heights = slopes = NO_SUMS
            used = 0
            done = 1
            banded = False
        tiny2 = (MIN_TANGENT_LENGTH * r * inv_w) ** 2
        for i in range(done, count):
            q = queue[i]
            u, v, w = _scaled_offset(p, q, x, y, z, inv_w, frame, n0, n1, n2)
            l2 = u * u + v * v
            if not (l2 > tiny2):
                continue
            banded = banded or not (l2 > band2)
            used += 1
            heights = _add_height(heights, u, v, w)
            a, b, c = normal_in_frame(q, nx, ny, nz, frame, n0, n1, n2)
            if not (c > MIN_NORMAL_Z) or not (math.isfinite(a) and math.isfinite(b)):
                continue
            slopes = _add_slopes(slopes, u, v, -a / c, -b / c)
        done = count
        t = widest / r
        _normal_equations(t * t, heights, slopes, ata, atb)
        singular, _ = solve_scaled(ata, 7, ata, atb, sol)
        finish_fit(p, -sol[0] * inv_w, -sol[1] * inv_w, -sol[2] * inv_w, singular, used, frame, k1[level], k2[level],
                   d1[level], d2[level], reason[level])


NC, QS, AN = 0, 1, 2
"""The ``method`` of :func:`_fit_kernel`."""


@jit_parallel
def _levels_kernel(method, centres, lo, hi, radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, outside,
                   outside_d2, k1, k2, d1, d2, reason):
    """The kernel of :func:`~curv.estimators._local_fit.run_fit_levels` for the three fits
    (``method``: :data:`NC`, :data:`QS` or :data:`AN`); each slice of vertices has its own scratch."""
    parts = stamps.shape[0]
    for t in prange(parts):
        queue, stamp, waiting, waiting_d2 = queues[t], stamps[t], outside[t], outside_d2[t]
        acc = np.empty(9)
        ata, atb, sol = np.empty((8, 7)), np.empty(7), np.empty(7)
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            if method == AN:
                _an_levels_at(p, radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamp, queue, waiting, waiting_d2, k1, k2,
                              d1, d2, reason, ata, atb, sol)
            else:
                _nc_qs_levels_at(p, radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamp, queue, waiting, waiting_d2, k1,
                                 k2, d1, d2, reason, acc, method == NC)


@jit_parallel
def _fit_kernel(method, centres, lo, hi, radius, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, k1, k2, d1, d2,
                reason, k1_se, k2_se, se_parts, ring_ptr, ring, slots):
    """The kernel of :func:`~curv.estimators._local_fit.run_fit` for the three fits (``method``:
    :data:`NC`, :data:`QS` or :data:`AN`); each slice of vertices has its own scratch."""
    parts = stamps.shape[0]
    for t in prange(parts):
        queue = queues[t]
        stamp = stamps[t]
        slot = slots[t]
        tilt, meat, offs = np.empty(13), np.empty(21), np.empty((64, 2))
        ata, atb, grads = np.empty((8, 7)), np.empty(7), np.empty((7, 7))
        row, ru, rv, sol = np.empty(7), np.empty(7), np.empty(7), np.empty(7)
        touched, yv, jp = np.empty(64, np.int64), np.empty((64, 7)), np.empty((64, 2))
        agg, wrow = np.empty((5, 7)), np.empty((1, 7))
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            count, queue = ball_support(p, radius[p] ** 2, adj_ptr, adj, x, y, z, stamp, queue)
            if method == AN:
                touched, yv, jp = _an_at(p, queue, count, radius[p], x, y, z, nx, ny, nz, k1, k2, d1, d2, reason,
                                         k1_se, k2_se, se_parts, ata, atb, row, ru, rv, sol, grads,
                                         ring_ptr, ring, slot, touched, yv, jp, agg, wrow)
            else:
                offs = _nc_qs_at(p, queue, count, radius[p], x, y, z, nx, ny, nz, k1, k2, d1, d2, reason, k1_se,
                                 k2_se, se_parts, tilt, meat, offs, method == NC)


def iter_nc(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, standard_errors: bool = True):
    """Normal-curvature least squares over each vertex's support (3 unknowns, 1 equation per neighbour).

    ``standard_errors=False``: none (:func:`~curv.estimators._local_fit.run_fit`)."""
    return (yield from run_fit(mesh, normals, radii, partial(_fit_kernel, NC), chunk=chunk, centres=centres,
                               features=features, standard_errors=standard_errors,
                               levels_kernel=partial(_levels_kernel, NC)))


def iter_qs(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, standard_errors: bool = True):
    """Quadratic height fit over each vertex's support (3 unknowns, 1 equation per neighbour).

    ``standard_errors=False``: none (:func:`~curv.estimators._local_fit.run_fit`)."""
    return (yield from run_fit(mesh, normals, radii, partial(_fit_kernel, QS), chunk=chunk, centres=centres,
                               features=features, standard_errors=standard_errors,
                               levels_kernel=partial(_levels_kernel, QS)))


def iter_an(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, noise_model: str = DEFAULT_NOISE_MODEL,
            standard_errors: bool = True):
    """Adjacent-normal cubic fit over each vertex's support (7 unknowns, 3 equations per neighbour).

    ``noise_model`` (:data:`~curv.estimators._local_fit.NOISE_MODELS`) says how the standard errors
    take the errors of the neighbours' normals; the curvatures do not depend on it.
    ``standard_errors=False``: none (:func:`~curv.estimators._local_fit.run_fit`)."""
    return (yield from run_fit(mesh, normals, radii, partial(_fit_kernel, AN), chunk=chunk, centres=centres,
                               features=features, noise_model=checked_noise_model(noise_model),
                               standard_errors=standard_errors, levels_kernel=partial(_levels_kernel, AN)))


_GI = "Goldfeather & Interrante 2004, A novel cubic-order algorithm for approximating principal direction vectors"

register(EstimatorSpec(
    name="nc", title="Normal curvature approximation", ranges=(1, 2, 3, 4), function=iter_nc,
    triangles_only=False, uses_normals=False, closed_ring=False, takes_points=True, reference=_GI, min_neighbours=MIN_PAIRS,
    summary="least squares of edge normal curvatures 2 (p-q).N/|p-q|^2", kernels=(_fit_kernel, _levels_kernel, POOL_KERNEL),
    extra_bytes_per_unit=SE_PARTS_BYTES, skips_errors=True, takes_levels=True,
))
register(EstimatorSpec(
    name="qs", title="Quadratic surface approximation", ranges=(1, 2, 3, 4), function=iter_qs,
    triangles_only=False, uses_normals=False, closed_ring=False, takes_points=True, reference=_GI, min_neighbours=MIN_PAIRS,
    summary="least-squares height fit A/2 u^2 + B uv + C/2 v^2 in the tangent frame", kernels=(_fit_kernel, _levels_kernel, POOL_KERNEL),
    extra_bytes_per_unit=SE_PARTS_BYTES, skips_errors=True, takes_levels=True,
))
register(EstimatorSpec(
    name="an", title="Adjacent-normal cubic approximation", ranges=(2, 3, 4), function=iter_an,
    triangles_only=False, uses_normals=True, closed_ring=False, takes_points=True, reference=_GI, min_neighbours=MIN_PAIRS,
    summary="cubic height fit using positions and the neighbours' normals (7 unknowns)", kernels=(_fit_kernel, _levels_kernel, POOL_KERNEL),
    options={"noise_model": NOISE_MODELS},
    extra_bytes_per_unit=SE_PARTS_BYTES + SLOT_BYTES, skips_errors=True, takes_levels=True,
))
