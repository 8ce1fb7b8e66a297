"""Modified Rusinkiewicz (paper §4.2): per-vertex least squares of normal differences.

For every neighbour q in range, the shape operator maps the tangent offset (u, v) of ``q - p`` to
the tangent part (a, b) of ``N_q - N_p`` (eq. 4.1/4.2, with our sign convention dN = W t): two
equations ``[u v 0] (e f g)^T = a`` and ``[0 u v] (e f g)^T = b`` per neighbour. N_p is orthogonal
to its own frame's U and V, so only N_q enters (a, b). No per-face step, so it works on any polygon
mesh. One kernel: the ball search and the normal equations run neighbour by neighbour.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit, jit_parallel, prange
from ..core.mesh import Mesh
from ..geometry.neighbourhood import ball_support, start_ball_support, widen_ball_support
from ._local_fit import (DEFAULT_NOISE_MODEL, MIN_PAIRS, MIN_TANGENT_LENGTH, NOISE_MODELS, SE_PARTS_BYTES, SLOT_BYTES,
                         add_ring_columns, centre_columns, deviator_gradients, finish_fit, fit_frame, list_room,
                         checked_noise_model, normal_in_frame, offset_in_frame, principal_gradients, run_fit, slice_bounds,
                         solve_sym3, start_levels, store_parts, store_se3, sym3_inverse)
from ._pooling import POOL_KERNEL
from .registry import EstimatorSpec, register


@jit
def _neighbour(p, q, x, y, z, nx, ny, nz, frame, n0, n1, n2, tiny2):
    """q's tangent offset (u, v) in p's frame and the tangent part (a, b) of its normal; ``ok`` when
    the offset carries a direction (:data:`~curv.estimators._local_fit.MIN_TANGENT_LENGTH`) and the
    normal is finite. Returns ``(u, v, a, b, ok)``."""
    u, v, _ = offset_in_frame(p, q, x, y, z, frame, n0, n1, n2)
    a, b, _ = normal_in_frame(q, nx, ny, nz, frame, n0, n1, n2)
    return u, v, a, b, u * u + v * v > tiny2 and math.isfinite(a) and math.isfinite(b)


@jit
def _noise_model(p, queue, count, tiny2, x, y, z, nx, ny, nz, frame, ring_ptr, ring, slots, touched, yv, jp,
                 su, sv, minv, grads, ru, rv):
    """The equations' errors as the neighbours' normals make them from noisy heights.

    A vertex normal made from its faces tilts, to first order, by the height gradient of its ring
    (for a regular ring the area- and Max-weighted normals are exactly the least-squares gradient,
    :func:`~curv.estimators._local_fit.ring_gradient`), so with independent height errors h
    (variance sigma_h²) the errors of the a (b) equations are ``-(J_q - J_p) h``, rows u (v): q's own
    normal and the tilt of p's, the frame. Neighbouring normals share vertices, so the equations' errors are correlated; the
    propagation follows them exactly: with ``y_j = Σ_eq A_eqᵀ J̃_eq,j`` the fit's error is
    ``M⁻¹ Σ_j y_j h_j``, so ``var(gᵀx) = sigma_h² Σ_j (gᵀM⁻¹y_j)²`` and
    ``E[RSS] = sigma_h² (‖J̃‖² - Σ_j y_jᵀM⁻¹y_j)``.

    Parameters
    ----------
    minv : (6,) float64
        M⁻¹'s entries (i00, i01, i02, i11, i12, i22).
    grads : (4, 3) float64
        The gradients of k1, k2 and of the deviator's two components over (e, f, g).
    ru, rv : (3,) float64
        Scratch.

    Returns
    -------
    var1, var2, var_dev, spare : float
        ``var / sigma_h²`` and ``E[RSS] / sigma_h²``.
    ok : bool
        False where a ring has no gradient (the caller keeps the independent model).
    touched, yv, jp :
        The short lists (grown, perhaps).
    """
    n0, n1, n2 = nx[p], ny[p], nz[p]
    touched, yv, jp = list_room(p, queue, count, ring_ptr, touched, yv, jp)
    var1 = var2 = vard = spare = 0.0
    # p's normal: the frame's tilt, shared by every equation
    used, ok, _, _, _, jpn = centre_columns(p, ring_ptr, ring, x, y, z, frame, slots, touched, yv, jp)
    if ok:
        for i in range(1, count):
            u, v, _, _, usable = _neighbour(p, queue[i], x, y, z, nx, ny, nz, frame, n0, n1, n2, tiny2)
            if not usable:
                continue
            # rows (u, v, 0) and (0, u, v) of the a and b equations
            ru[0], ru[1], ru[2] = u, v, 0.0
            rv[0], rv[1], rv[2] = 0.0, u, v
            used, ok, jqn, cross = add_ring_columns(queue[i], ring_ptr, ring, x, y, z, frame, slots, touched, yv, jp,
                                                    used, ru, rv)
            if not ok:
                break
            spare += jqn + jpn - 2.0 * cross
    i00, i01, i02, i11, i12, i22 = minv[0], minv[1], minv[2], minv[3], minv[4], minv[5]
    for s in range(used):
        if ok:
            # the frame's share: minus p's gradient in every a (b) equation
            c0, c1 = jp[s, 0], jp[s, 1]
            y0 = yv[s, 0] - su * c0
            y1 = yv[s, 1] - (sv * c0 + su * c1)
            y2 = yv[s, 2] - sv * c1
            t0 = i00 * y0 + i01 * y1 + i02 * y2
            t1 = i01 * y0 + i11 * y1 + i12 * y2
            t2 = i02 * y0 + i12 * y1 + i22 * y2
            spare -= y0 * t0 + y1 * t1 + y2 * t2
            d1 = grads[0, 0] * t0 + grads[0, 1] * t1 + grads[0, 2] * t2
            d2 = grads[1, 0] * t0 + grads[1, 1] * t1 + grads[1, 2] * t2
            da = grads[2, 0] * t0 + grads[2, 1] * t1 + grads[2, 2] * t2
            dh = grads[3, 0] * t0 + grads[3, 1] * t1 + grads[3, 2] * t2
            var1 += d1 * d1
            var2 += d2 * d2
            vard += da * da + dh * dh
        slots[touched[s]] = 0
    return var1, var2, vard, spare, ok, touched, yv, jp


@jit
def _mru_solve(suu, suv, svv, sau, sav, sbu, sbv):
    """The fit's (e, f, g) from the sums of its equations' rows (u, v, 0) and (0, u, v):
    ``AᵀA = [[uu, uv, 0], [uv, uu + vv, uv], [0, uv, vv]]``, ``Aᵀb = (au, av + bu, bv)``
    (:func:`~curv.estimators._local_fit.solve_sym3`). Returns ``(e, f, g, singular)``."""
    return solve_sym3(suu, suv, 0.0, suu + svv, suv, svv, sau, sav + sbu, sbv)


@jit
def _mru_levels_at(p, radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamp, queue, waiting, waiting_d2, k1, k2, d1, d2,
                   reason):
    """mru at vertex p at every level of ``radii`` (levels, n), in one walk
    (:func:`~curv.estimators._local_fit.run_fit_levels`): the equations of each level's new
    vertices are added to the last level's sums (their rows do not depend on the radius). A row whose
    tangent length is so short that a wider level's bound would drop it makes the following levels
    add up their whole support again, each with its own bound."""
    n0, n1, n2, frame, band2, ok = start_levels(p, radii, nx, ny, nz, k1, k2, d1, d2, reason)
    if not ok:
        return
    levels = radii.shape[0]
    count = start_ball_support(p, stamp, queue)
    head = pending = used = 0
    done = 1
    banded = True  # clears the sums below
    suu = suv = svv = sau = sav = sbu = sbv = 0.0
    for level in range(levels):
        r = radii[level, p]
        count, head, pending = widen_ball_support(p, r ** 2, level + 1 < levels, adj_ptr, adj, x, y, z, stamp, queue,
                                                  count, head, waiting, waiting_d2, pending)
        if banded:
            suu = suv = svv = sau = sav = sbu = sbv = 0.0
            used = 0
            done = 1
            banded = False
        tiny2 = (MIN_TANGENT_LENGTH * r) ** 2
        for i in range(done, count):
            u, v, a, b, usable = _neighbour(p, queue[i], x, y, z, nx, ny, nz, frame, n0, n1, n2, tiny2)
            if not usable:
                continue
            banded = banded or not (u * u + v * v > band2)
            used += 1
            suu += u * u
            suv += u * v
            svv += v * v
            sau += a * u
            sav += a * v
            sbu += b * u
            sbv += b * v
        done = count
        e, f, g, singular = _mru_solve(suu, suv, svv, sau, sav, sbu, sbv)
        finish_fit(p, e, f, g, singular, used, frame, k1[level], k2[level], d1[level], d2[level], reason[level])


@jit_parallel
def _mru_levels_kernel(centres, lo, hi, radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, outside, outside_d2,
                       k1, k2, d1, d2, reason):
    """The kernel of :func:`~curv.estimators._local_fit.run_fit_levels` for mru."""
    parts = stamps.shape[0]
    for t in prange(parts):
        queue, stamp, waiting, waiting_d2 = queues[t], stamps[t], outside[t], outside_d2[t]
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            _mru_levels_at(centres[i], radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamp, queue, waiting, waiting_d2,
                           k1, k2, d1, d2, reason)


@jit
def _mru_at(p, queue, count, r, x, y, z, nx, ny, nz, k1, k2, d1, d2, reason, k1_se, k2_se, se_parts, tilt,
            ring_ptr, ring, slots, touched, yv, jp, minv, grads, ru, rv):
    """Normal-difference least squares at vertex p over its support ``queue[1:count]``.

    Scratch: ``tilt`` (13,) for the frame-tilt columns of the independent model (:func:`store_se3`);
    ``slots`` (n,) int64 zeros, ``touched``, ``yv``, ``jp``, ``minv``, ``grads``, ``ru``, ``rv`` (3,) for
    :func:`_noise_model`. Returns the short lists (grown, perhaps).
    """
    n0, n1, n2, frame, ok = fit_frame(p, nx, ny, nz, k1, k2, d1, d2, reason, se_parts)
    if not ok:
        return touched, yv, jp
    tiny2 = (MIN_TANGENT_LENGTH * r) ** 2
    # normal equations of the two equation kinds: rows (u, v, 0) and (0, u, v)
    suu = suv = svv = sau = sav = sbu = sbv = saa_bb = su = sv = sa = sb = 0.0
    used = 0
    for i in range(1, count):
        u, v, a, b, usable = _neighbour(p, queue[i], x, y, z, nx, ny, nz, frame, n0, n1, n2, tiny2)
        if not usable:
            continue
        used += 1
        suu += u * u
        suv += u * v
        svv += v * v
        sau += a * u
        sav += a * v
        sbu += b * u
        sbv += b * v
        saa_bb += a * a + b * b
        su += u
        sv += v
        sa += a
        sb += b
    e, f, g, singular = _mru_solve(suu, suv, svv, sau, sav, sbu, sbv)
    finish_fit(p, e, f, g, singular, used, frame, k1, k2, d1, d2, reason)
    xatb = e * sau + f * (sav + sbu) + g * sbv
    if slots.size > 0 and ring.size > 0 and used > 3 and not singular:  # slots given: noise_model="normals"
        minv[0], minv[1], minv[2], minv[3], minv[4], minv[5] = sym3_inverse(suu, suv, 0.0, suu + svv, suv, svv)
        grads[0, 0], grads[0, 1], grads[0, 2], grads[1, 0], grads[1, 1], grads[1, 2] = principal_gradients(e, f, g)
        grads[2, 0], grads[2, 1], grads[2, 2], grads[3, 0], grads[3, 1], grads[3, 2] = deviator_gradients(e, f, g)
        var1, var2, vard, spare, ok, touched, yv, jp = _noise_model(
            p, queue, count, tiny2, x, y, z, nx, ny, nz, frame, ring_ptr, ring, slots, touched, yv, jp,
            su, sv, minv, grads, ru, rv)
        if ok and spare > 0.0:
            store_parts(p, k1_se, k2_se, se_parts, var1, var2, saa_bb - xatb, spare, vard, math.hypot(0.5 * (e - g), f))
            return touched, yv, jp
    # noise_model="independent" (and the first pass of "sampled"), a point cloud, or a ring without a gradient:
    # the equations' errors taken as independent
    if ring.size > 0:
        # a mesh: the noise level from the plain residuals. A term for the tilt of p's own normal
        # read it smaller still (neighbouring normals share faces, so their errors move together):
        # mru R2 put 70 % of noisy meshes' vertices within 2 se with it, 85 % without
        store_se3(p, suu, suv, 0.0, suu + svv, suv, svv, saa_bb, xatb, 2 * used, 0,
                  0.0, 0.0, 0.0, e, f, g, k1_se, k2_se, se_parts, e, f, g)
    else:
        # a point cloud (normals fitted, not shared faces): a tilt t of p's own normal (the frame)
        # adds -t to every a (and b) equation, so the noise level is read from the residuals of the
        # fit with those two constants as unknowns
        tilt[0], tilt[1], tilt[2] = used, 0.0, used
        tilt[3], tilt[4], tilt[5], tilt[6], tilt[7], tilt[8] = su, sv, 0.0, 0.0, su, sv
        tilt[9], tilt[10], tilt[11], tilt[12] = sa, sb, used, used
        store_se3(p, suu, suv, 0.0, suu + svv, suv, svv, saa_bb, xatb, 2 * used, 0,
                  0.0, 0.0, 0.0, e, f, g, k1_se, k2_se, se_parts, e, f, g, tilt)
    # its noise level is of the normals, not of the heights: pooled with no other vertex's
    if se_parts.shape[0] > 0:
        se_parts[p, 1] = -se_parts[p, 1]
    return touched, yv, jp


@jit_parallel
def _mru_kernel(centres, lo, hi, radius, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, k1, k2, d1, d2, reason,
                k1_se, k2_se, se_parts, ring_ptr, ring, slots):
    parts = stamps.shape[0]
    for t in prange(parts):
        queue = queues[t]
        stamp = stamps[t]
        slot = slots[t]
        tilt = np.empty(13)
        touched, yv, jp = np.empty(64, np.int64), np.empty((64, 3)), np.empty((64, 2))
        minv, grads, ru, rv = np.empty(6), np.empty((4, 3)), np.empty(3), np.empty(3)
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            count, queue = ball_support(p, radius[p] ** 2, adj_ptr, adj, x, y, z, stamp, queue)
            touched, yv, jp = _mru_at(p, queue, count, radius[p], x, y, z, nx, ny, nz, k1, k2, d1, d2, reason,
                                      k1_se, k2_se, se_parts, tilt, ring_ptr, ring, slot, touched, yv, jp, minv,
                                      grads, ru, rv)


def iter_mru(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, noise_model: str = DEFAULT_NOISE_MODEL,
            standard_errors: bool = True):
    """Normal-difference least squares over each vertex's support (within (k-1) longest 1-ring edges at Rk).

    ``noise_model`` (:data:`~curv.estimators._local_fit.NOISE_MODELS`) says how the standard errors
    take the errors of the neighbours' normals; the curvatures do not depend on it.
    ``standard_errors=False``: none (:func:`~curv.estimators._local_fit.run_fit`)."""
    return (yield from run_fit(mesh, normals, radii, _mru_kernel, chunk=chunk, centres=centres,
                                 features=features, noise_model=checked_noise_model(noise_model),
                                 standard_errors=standard_errors, levels_kernel=_mru_levels_kernel))


register(EstimatorSpec(
    name="mru", title="Modified Rusinkiewicz", ranges=(2, 3, 4), function=iter_mru,
    triangles_only=False, uses_normals=True, closed_ring=False, takes_points=True, min_neighbours=MIN_PAIRS,
    reference="Multivariate analysis of curvature estimators, §4.2 (after Rusinkiewicz 2004)",
    summary="per-vertex least squares of neighbour normal differences (eq. 4.1/4.2)", kernels=(_mru_kernel, _mru_levels_kernel, POOL_KERNEL),
    options={"noise_model": NOISE_MODELS},
    extra_bytes_per_unit=SE_PARTS_BYTES + SLOT_BYTES, skips_errors=True, takes_levels=True,
))
