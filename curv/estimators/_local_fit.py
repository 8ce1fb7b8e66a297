"""What the per-vertex least-squares estimators (nc, qs, an, mru) share: numba helpers and the driver.

Each of them writes, for every neighbour q in the support of vertex p, a few linear equations in
the unknowns of a local fit, expressed in p's tangent frame (U, V, N). The kernels accumulate the
normal equations ``AᵀA x = Aᵀb`` neighbour by neighbour while the ball search runs, so nothing per
pair is ever stored; the helpers below solve them and turn the fitted shape operator
``W = [[e, f], [f, g]]`` into principal curvatures and directions.

Every fit kernel has the same arguments (see :func:`run_fit`) and writes its vertices' rows of
``k1, k2, d1, d2, reason`` and of the standard errors ``k1_se, k2_se``.

Standard errors (docs/UNCERTAINTY.md): with m equations, p unknowns and the residual sum of
squares ``RSS = bᵀb - xᵀAᵀb``, the noise variance is ``sigma² = RSS / (m - p)`` and the fitted
coefficients have covariance ``sigma² (AᵀA)⁻¹`` when the equations' errors are independent. In
nc, qs and an they are not: every height is measured from the centre's own noisy position
(:func:`store_se3` models that shared part). A principal curvature is ``k_i = d_iᵀ W d_i``
with d_i = (c, s) its unit direction in (U, V); to first order ``dk_i = d_iᵀ dW d_i``, so its
gradient over (e, f, g) is ``(c², 2cs, s²)`` for k1 and ``(s², -2cs, c²)`` for k2, and
``se(k_i)² = sigma² gᵀ (AᵀA)⁻¹ g``. nc and qs read sigma² from the residuals of the fit with the
frame's tilt as two more unknowns (:func:`tilt_residual`), and the 3-unknown fits add the eigen
step's bias (:func:`eigen_bias`) in quadrature. mru and an, whose equations use the neighbours'
normals, model their errors as those normals get them from noisy heights (neighbouring normals
share vertices: :func:`ring_gradient`, the kernels' ``_noise_model``), on a mesh.

The kernels write each vertex's parts (:func:`store_parts`: the propagation per unit noise
variance, the residual sum of squares and its spare equations); :func:`run_fit` then pools the
noise level over each vertex and its edge neighbours (:mod:`curv.estimators._pooling`).
"""

from __future__ import annotations

import math
from typing import Generator

import numpy as np

from ..core.errors import EstimatorError
from ..core.filled import filled
from ..core.jit import iter_chunks, jit, jit_inlined, launch, rescaled, threads
from ..core.mesh import Mesh
from ..geometry.neighbourhood import all_centres, blocked_vertices, coordinate_columns, expansion_adjacency, new_queues, new_scratch
from ..core.result import Principal
from ..core.validity import DEGENERATE, OK, SINGULAR, TOO_FEW
from ._pooling import pool_members, pool_rings, pool_standard_errors, rad_bias

__all__ = ["run_fit", "run_fit_levels", "start_levels", "tangent_frame", "offset_in_frame", "solve_sym3", "solve_scaled", "store_principal", "finish_fit",
           "mark_degenerate", "slice_bounds", "principal_gradients", "noise_variance", "sym3_inverse", "sym3_bilinear",
           "cholesky_scaled", "factor_whiten", "row_dot", "store_se3", "tilt_residual", "deviator_gradients", "eigen_bias",
           "clear_parts", "store_parts", "store_se3_weighted", "sym3_sandwich", "ring_gradient", "gradient_column", "list_room", "list_slot", "centre_columns",
           "add_ring_columns", "fit_frame", "normal_in_frame", "checked_noise_model", "sampled_scales",
           "MIN_TANGENT_LENGTH", "MIN_PAIRS", "SE_PARTS_BYTES", "SLOT_BYTES", "RCOND"]


MIN_TANGENT_LENGTH = 1e-9
"""Neighbours whose tangent-plane offset is below this fraction of the ball radius carry no direction."""

MIN_PAIRS = 3
"""Fewer usable neighbours than this make the vertex ``TOO_FEW_NEIGHBOURS`` (the fits have 3
curvature unknowns)."""

RCOND = 1e-10
"""A system is singular when its determinant is below this (scaled) bound."""

SE_PARTS_BYTES = 16.0
"""The standard errors' parts (4 float64 per vertex, :func:`store_parts`)
per size unit (vertices + faces / 2, about 2 vertices on a triangle mesh)."""
SLOT_BYTES = 16.0
"""The noise model's vertex slots (an int64 per vertex and kernel thread, 4 threads) per size unit."""

@jit
def tangent_frame(nx, ny, nz):
    """Orthonormal tangent basis (U, V) with U x V = N, crossing N with its least-aligned axis.

    Returns
    -------
    ux, uy, uz, vx, vy, vz : float
        NaN where N is not finite.
    """
    ax, ay, az = abs(nx), abs(ny), abs(nz)
    # the coordinate axis least aligned with N (first on ties); N x axis is never near zero
    if ax <= ay and ax <= az:
        ux, uy, uz = 0.0, nz, -ny
    elif ay <= az:
        ux, uy, uz = -nz, 0.0, nx
    else:
        ux, uy, uz = ny, -nx, 0.0
    norm = math.sqrt(ux * ux + uy * uy + uz * uz)
    ux /= norm
    uy /= norm
    uz /= norm
    vx = ny * uz - nz * uy
    vy = nz * ux - nx * uz
    vz = nx * uy - ny * ux
    return ux, uy, uz, vx, vy, vz


@jit
def offset_in_frame(p, q, x, y, z, frame, n0, n1, n2):
    """The offset ``q - p`` in p's frame: ``(u, v, w)`` along U, V and the normal N = (n0, n1, n2)."""
    ux, uy, uz, vx, vy, vz = frame
    dx, dy, dz = x[q] - x[p], y[q] - y[p], z[q] - z[p]
    return (dx * ux + dy * uy + dz * uz, dx * vx + dy * vy + dz * vz, dx * n0 + dy * n1 + dz * n2)


@jit
def sym3_cofactors(a00, a01, a02, a11, a12, a22):
    """The cofactors of a symmetric 3x3 A (the upper triangle of ``det(A) A⁻¹``) and det(A).

    Returns
    -------
    c00, c01, c02, c11, c12, c22, det : float
    """
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    return c00, c01, c02, c11, c12, c22, a00 * c00 + a01 * c01 + a02 * c02


@jit
def solve_sym3(a00, a01, a02, a11, a12, a22, b0, b1, b2):
    """Solve a symmetric 3x3 system by Cramer's rule.

    Returns
    -------
    x0, x1, x2 : float
    singular : bool
        ``|det A| <= RCOND * max|a_ij|^3`` (the x are then NaN).
    """
    c00, c01, c02, c11, c12, c22, det = sym3_cofactors(a00, a01, a02, a11, a12, a22)
    scale = max(abs(a00), abs(a01), abs(a02), abs(a11), abs(a12), abs(a22))
    if not abs(det) > RCOND * scale * scale * scale:
        return math.nan, math.nan, math.nan, True
    inv = 1.0 / det
    return ((c00 * b0 + c01 * b1 + c02 * b2) * inv,
            (c01 * b0 + c11 * b1 + c12 * b2) * inv,
            (c02 * b0 + c12 * b1 + c22 * b2) * inv,
            False)


@jit
def solve_scaled(ata, size, factor, atb, x):
    """Solve a small symmetric positive definite system ``A x = atb`` after Jacobi scaling.

    The scaled matrix ``D A D`` (``D = diag(A)^(-1/2)``) has a unit diagonal; it is factored by
    Cholesky (:func:`cholesky_scaled`), and the system is called singular when the factorisation
    breaks down (or a diagonal entry is not finite) or the scaled matrix's determinant is at most
    ``RCOND**2``.

    Parameters
    ----------
    ata : (K, K) float64
        A in the lower triangle of its leading ``size`` block.
    size : int
    factor : (K + 1, K) float64
        Receives L and D (:func:`cholesky_scaled` with ``srow = size``); may be ``ata`` itself.
    atb : (K,) float64
        Kept.
    x : (K,) float64
        Receives the solution ``D L⁻ᵀ L⁻¹ D atb`` (NaN if singular).

    Returns
    -------
    singular : bool
    factored : bool
        Whether the factorisation held (``factor`` then serves :func:`factor_whiten`).
    """
    for i in range(size):
        if not math.isfinite(ata[i, i]):
            x[:size] = math.nan
            return True, False
    if not cholesky_scaled(ata, size, factor, size):
        x[:size] = math.nan
        return True, False
    det = 1.0
    for i in range(size):
        t = atb[i] * factor[size, i]
        for k in range(i):
            t -= factor[i, k] * x[k]
        x[i] = t / factor[i, i]
        det *= factor[i, i] * factor[i, i]
    if not det > RCOND * RCOND:
        x[:size] = math.nan
        return True, True
    for i in range(size - 1, -1, -1):
        t = x[i]
        for k in range(i + 1, size):
            t -= factor[k, i] * x[k]
        x[i] = t / factor[i, i]
    for i in range(size):
        x[i] *= factor[size, i]
    return False, True


@jit
def store_principal(p, e, f, g, ux, uy, uz, vx, vy, vz, k1, k2, d1, d2):
    """Eigen-decompose W = [[e, f], [f, g]] in the frame (U, V) and write row p of the outputs.

    k1 = H + sqrt(((e - g)/2)^2 + f^2) >= k2; d1 at angle theta = atan2(f, (e - g)/2) / 2 from U,
    d2 = N x d1.
    """
    half = 0.5 * (e - g)
    mean = 0.5 * (e + g)
    rad = math.hypot(half, f)
    theta = 0.5 * math.atan2(f, half)
    c = math.cos(theta)
    s = math.sin(theta)
    k1[p] = mean + rad
    k2[p] = mean - rad
    d1[p, 0] = c * ux + s * vx
    d1[p, 1] = c * uy + s * vy
    d1[p, 2] = c * uz + s * vz
    d2[p, 0] = -s * ux + c * vx
    d2[p, 1] = -s * uy + c * vy
    d2[p, 2] = -s * uz + c * vz


@jit
def principal_gradients(e, f, g):
    """First-order gradients of k1 and k2 of W = [[e, f], [f, g]] over (e, f, g).

    ``dk_i = d_iᵀ dW d_i`` with d1 = (c, s), d2 = (-s, c) the eigenvectors (:func:`store_principal`:
    angle theta with ``cos 2theta = (e - g) / 2 / rad``, ``sin 2theta = f / rad``), written without
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
    else:  # an umbilic: atan2(0, 0) = 0, as in store_principal
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
def clear_parts(p, parts):
    """Row p of ``parts`` before a fit: no residual to pool (:func:`store_parts`). Nothing with
    ``parts`` of no rows (a fit without standard errors, :func:`run_fit`)."""
    if parts.shape[0] == 0:
        return
    parts[p, 0] = math.nan
    parts[p, 1] = 0.0
    parts[p, 2] = 0.0
    parts[p, 3] = 0.0


@jit
def store_parts(p, k1_se, k2_se, parts, var1, var2, rss, dof, var_deviator, rad):
    """Write what vertex p's standard errors need besides the noise level, which is pooled afterwards
    over p and its neighbours (:func:`curv.estimators._pooling.pool_standard_errors`).

    Parameters
    ----------
    p : int
    k1_se, k2_se : (n,) float64
        Row p gets ``var(k_i) / sigma²`` (the propagation through the fit and the eigen step);
        the pooling replaces it by the standard error.
    parts : (n, 4) float64
        Row p gets ``(RSS, spare equations, var_deviator / sigma², rad)``: the residual sum of
        squares and the (effective) number of spare equations it is spread over (0 when there is
        none), and what :func:`rad_bias` needs. No rows: the fit computes no standard errors
        (:func:`run_fit`), nothing is written.
    """
    if parts.shape[0] == 0:
        return
    k1_se[p] = var1
    k2_se[p] = var2
    parts[p, 0] = rss
    parts[p, 1] = dof if dof > 0.0 else 0.0
    parts[p, 2] = var_deviator
    parts[p, 3] = rad


@jit
def ring_gradient(v, ring_ptr, ring, x, y, z, ux, uy, uz, vx, vy, vz):
    """The least-squares height gradient at vertex v from its edge neighbours, in the frame (U, V):
    ``grad = G⁻¹ Σ_j d_j (h_j - h_v)`` with d_j the tangent offsets and ``G = Σ d_j d_jᵀ``.

    Returns
    -------
    i00, i01, i11, sdu, sdv : float
        G⁻¹ and ``Σ d_j`` (the column of h_v is ``-G⁻¹ Σ d_j``).
    ok : bool
        False when G is singular (fewer than two independent directions).
    """
    g00 = g01 = g11 = sdu = sdv = 0.0
    for k in range(ring_ptr[v], ring_ptr[v + 1]):
        w = ring[k]
        dx, dy, dz = x[w] - x[v], y[w] - y[v], z[w] - z[v]
        du = dx * ux + dy * uy + dz * uz
        dv = dx * vx + dy * vy + dz * vz
        g00 += du * du
        g01 += du * dv
        g11 += dv * dv
        sdu += du
        sdv += dv
    det = g00 * g11 - g01 * g01
    if not det > 1e-12 * g00 * g11:
        return 0.0, 0.0, 0.0, 0.0, 0.0, False
    return g11 / det, -g01 / det, g00 / det, sdu, sdv, True


@jit
def gradient_column(w, v, i00, i01, i11, sdu, sdv, x, y, z, ux, uy, uz, vx, vy, vz):
    """The column of vertex w (v itself or one of its edge neighbours) in :func:`ring_gradient`'s
    gradient at v: ``G⁻¹ d_w``, or ``-G⁻¹ Σ d_j`` for v. Returns its two components."""
    if w == v:
        return -(i00 * sdu + i01 * sdv), -(i01 * sdu + i11 * sdv)
    dx, dy, dz = x[w] - x[v], y[w] - y[v], z[w] - z[v]
    du = dx * ux + dy * uy + dz * uz
    dv = dx * vx + dy * vy + dz * vz
    return i00 * du + i01 * dv, i01 * du + i11 * dv


@jit
def centre_columns(p, ring_ptr, ring, x, y, z, frame, slots, touched, yv, jp):
    """The columns of p's own ring gradient (:func:`gradient_column`), J_p: the tilt of p's normal,
    the frame every equation of its fit shares; written to ``jp`` at each vertex's place in the
    short lists (:func:`list_slot`, starting empty).

    Returns
    -------
    used : int
        Entries of the short lists in use (0 when not ok).
    ok : bool
        False when p's ring has no gradient.
    p00, p01, p11 : float
        ``J_p`` 's row products ``Σ c0²``, ``Σ c0 c1``, ``Σ c1²``.
    jpn : float
        ``‖J_p‖² = Σ (c0² + c1²)``.
    """
    ux, uy, uz, vx, vy, vz = frame
    pi00, pi01, pi11, psu, psv, ok = ring_gradient(p, ring_ptr, ring, x, y, z, ux, uy, uz, vx, vy, vz)
    used = 0
    p00 = p01 = p11 = jpn = 0.0
    if not ok:
        return used, ok, p00, p01, p11, jpn
    for k in range(ring_ptr[p], ring_ptr[p + 1] + 1):
        w = p if k == ring_ptr[p + 1] else ring[k]
        c0, c1 = gradient_column(w, p, pi00, pi01, pi11, psu, psv, x, y, z, ux, uy, uz, vx, vy, vz)
        s, used = list_slot(w, slots, touched, yv, jp, used)
        jp[s, 0] = c0
        jp[s, 1] = c1
        p00 += c0 * c0
        p01 += c0 * c1
        p11 += c1 * c1
        jpn += c0 * c0 + c1 * c1
    return used, ok, p00, p01, p11, jpn


@jit
def add_ring_columns(q, ring_ptr, ring, x, y, z, frame, slots, touched, yv, jp, used, ru, rv):
    """Add a neighbour q's two slope equations to the noise model's sums: their rows ``ru``, ``rv``
    (K,) times the columns (c0, c1) of q's ring gradient (:func:`gradient_column`), to ``yv`` at
    each ring vertex's place (:func:`list_slot`).

    Returns
    -------
    used : int
        Entries of the short lists in use.
    ok : bool
        False when q's ring has no gradient (nothing added).
    jqn, cross : float
        ``‖J_q‖²`` and ``J_q · J_p`` (``jp``, :func:`centre_columns`).
    """
    ux, uy, uz, vx, vy, vz = frame
    qi00, qi01, qi11, qsu, qsv, ok = ring_gradient(q, ring_ptr, ring, x, y, z, ux, uy, uz, vx, vy, vz)
    jqn = cross = 0.0
    if not ok:
        return used, ok, jqn, cross
    for k in range(ring_ptr[q], ring_ptr[q + 1] + 1):
        w = q if k == ring_ptr[q + 1] else ring[k]
        c0, c1 = gradient_column(w, q, qi00, qi01, qi11, qsu, qsv, x, y, z, ux, uy, uz, vx, vy, vz)
        s, used = list_slot(w, slots, touched, yv, jp, used)
        for j in range(ru.size):
            yv[s, j] += ru[j] * c0 + rv[j] * c1
        jqn += c0 * c0 + c1 * c1
        cross += c0 * jp[s, 0] + c1 * jp[s, 1]
    return used, ok, jqn, cross


@jit
def list_room(v, queue, count, ring_ptr, touched, yv, jp):
    """The short lists of vertex v's noise model (:func:`list_slot`), grown to hold every vertex its
    support ``queue[:count]`` and their edge neighbours can bring. Returns ``(touched, yv, jp)``."""
    need = 0
    for i in range(count):
        q = queue[i]
        need += ring_ptr[q + 1] - ring_ptr[q] + 1
    if need <= touched.size:
        return touched, yv, jp
    return np.empty(need, np.int64), np.empty((need, yv.shape[1])), np.empty((need, 2))


@jit
def list_slot(w, slots, touched, yv, jp, used):
    """The place of vertex w in the short lists of a vertex's noise model (added, with zero sums, when
    new; :func:`list_room` makes the room first).

    Parameters
    ----------
    w : int
    slots : (n,) int64
        ``slots[w]`` is 1 + w's place, 0 when absent (reset to 0 by the caller after each vertex).
    touched : (cap,) int64
        The vertices listed.
    yv : (cap, K) float64
    jp : (cap, 2) float64
    used : int
        Entries in use.

    Returns
    -------
    place, used : int
    """
    s = slots[w]
    if s > 0:
        return s - 1, used
    touched[used] = w
    yv[used, :] = 0.0
    jp[used, 0] = jp[used, 1] = 0.0
    slots[w] = used + 1
    return used, used + 1


@jit
def noise_variance(bb, xatb, dof):
    """``sigma² = RSS / dof`` with ``RSS = bᵀb - xᵀAᵀb`` (clipped at 0 against rounding); NaN if dof <= 0."""
    if not dof > 0.0:
        return math.nan
    return max(bb - xatb, 0.0) / dof


@jit
def sym3_inverse(a00, a01, a02, a11, a12, a22):
    """The six entries of A⁻¹ for a symmetric 3x3 A, by its cofactors (inf/NaN when A is singular)."""
    c00, c01, c02, c11, c12, c22, det = sym3_cofactors(a00, a01, a02, a11, a12, a22)
    inv = 1.0 / det
    return c00 * inv, c01 * inv, c02 * inv, c11 * inv, c12 * inv, c22 * inv


@jit
def sym3_bilinear(i00, i01, i02, i11, i12, i22, g0, g1, g2, h0, h1, h2):
    """``gᵀ S h`` for the symmetric 3x3 S = [[i00, i01, i02], [., i11, i12], [., ., i22]]."""
    return (g0 * (i00 * h0 + i01 * h1 + i02 * h2) + g1 * (i01 * h0 + i11 * h1 + i12 * h2)
            + g2 * (i02 * h0 + i12 * h1 + i22 * h2))


@jit
def tilt_schur(i00, i01, i02, i11, i12, i22, tilt):
    """The frame tilt's two columns L against a 3-unknown fit (M⁻¹ given by its upper triangle):
    ``T = LᵀQ M⁻¹`` (2 x 3) and the Schur complement ``S = LᵀL - T QᵀL`` (2 x 2, symmetric).

    Parameters
    ----------
    i00 .. i22 : float
        M⁻¹.
    tilt : (13,) float64
        The tilt columns' sums (:func:`tilt_residual`).

    Returns
    -------
    tu0, tu1, tu2, tv0, tv1, tv2, s_uu, s_uv, s_vv : float
        T's rows u and v, and S.
    """
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
def tilt_residual(i00, i01, i02, i11, i12, i22, x0, x1, x2, s0, s1, s2, tilt):
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
    i00 .. i22 : float
        M⁻¹.
    x0, x1, x2 : float
        The 3-unknown solution.
    s0, s1, s2 : float
        Row sum of Q (the shared centre error's column; zeros without one).
    tilt : (13,) float64
        ``LᵀL`` (l00, l01, l11), ``LᵀQ`` (row u: 3, row v: 3), ``Lᵀb`` (2), ``Σ L rows`` (2).

    Returns
    -------
    drop : float
        ``r_Lᵀ S⁻¹ r_L`` (NaN when S is singular).
    shared_extra : float
        ``d_Lᵀ S⁻¹ d_L`` with ``d_L = Σ L rows - LᵀQ M⁻¹ s``: the linear terms' share of the centre's
        common error (add it to ``sᵀM⁻¹s``).
    """
    tu0, tu1, tu2, tv0, tv1, tv2, s_uu, s_uv, s_vv = tilt_schur(i00, i01, i02, i11, i12, i22, tilt)
    qu0, qu1, qu2, qv0, qv1, qv2 = tilt[3], tilt[4], tilt[5], tilt[6], tilt[7], tilt[8]
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
def store_se3(p, a00, a01, a02, a11, a12, a22, bb, xatb, m, shared, s0, s1, s2, e, f, g, k1_se, k2_se, parts,
              x0=0.0, x1=0.0, x2=0.0, tilt=None):
    """Row p of the standard errors' parts of a 3-unknown fit of W = [[e, f], [f, g]]
    (:func:`store_parts`; :func:`curv.estimators._pooling.pool_standard_errors` finishes them).

    With ``shared`` > 0, the centre's own height error enters every equation alike: the errors
    are modelled as ``eps_q + delta`` (independent, all of variance sigma²) and s = Σ rows. Then

    - ``E[RSS] = sigma² (m - 3 + shared - sᵀM⁻¹s)`` gives sigma², and
    - ``var(k) = sigma² (gᵀM⁻¹g + (gᵀM⁻¹s)²)`` with M = AᵀA and g the gradient of
      :func:`principal_gradients` (the unknowns are (e, f, g) or their negatives: a gradient's
      sign does not change a variance).

    With ``shared`` = 0 the errors are independent: ``sigma² = RSS / (m - 3)``, ``var(k) = sigma² gᵀM⁻¹g``.

    With ``tilt`` (the linear columns' sums, :func:`tilt_residual`), sigma² is read from the
    residuals of the fit with the frame's tilt as two more unknowns: ``RSS₅ / (m - 5 + shared -
    s₅ᵀM₅⁻¹s₅)``. Both add the eigen step's bias (:func:`eigen_bias`) to the variance.

    Parameters
    ----------
    a00 .. a22 : float
        M = AᵀA.
    bb, xatb : float
        bᵀb and xᵀAᵀb.
    m : int
        Equations.
    shared : int
        Equations sharing the centre's error (m or 0).
    s0, s1, s2 : float
        Their row sum (ignored when ``shared`` is 0).
    x0, x1, x2 : float
        The solution (with ``tilt`` only).
    tilt : (13,) float64, optional
        ``LᵀL`` (3), ``LᵀQ`` (6), ``Lᵀb`` (2), ``Σ L rows`` (2) of the two linear columns.
    k1_se, k2_se, parts :
        As in :func:`store_parts`.
    """
    if parts.shape[0] == 0:
        return  # no standard errors asked (:func:`run_fit`)
    i00, i01, i02, i11, i12, i22 = sym3_inverse(a00, a01, a02, a11, a12, a22)
    g10, g11, g12, g20, g21, g22 = principal_gradients(e, f, g)
    a0, a1, a2, h0, h1, h2 = deviator_gradients(e, f, g)
    var1 = sym3_bilinear(i00, i01, i02, i11, i12, i22, g10, g11, g12, g10, g11, g12)
    var2 = sym3_bilinear(i00, i01, i02, i11, i12, i22, g20, g21, g22, g20, g21, g22)
    vard = (sym3_bilinear(i00, i01, i02, i11, i12, i22, a0, a1, a2, a0, a1, a2)
            + sym3_bilinear(i00, i01, i02, i11, i12, i22, h0, h1, h2, h0, h1, h2))
    dof = m - 3.0
    if shared > 0:
        dof += shared - sym3_bilinear(i00, i01, i02, i11, i12, i22, s0, s1, s2, s0, s1, s2)
        gs1 = sym3_bilinear(i00, i01, i02, i11, i12, i22, g10, g11, g12, s0, s1, s2)
        gs2 = sym3_bilinear(i00, i01, i02, i11, i12, i22, g20, g21, g22, s0, s1, s2)
        as_ = sym3_bilinear(i00, i01, i02, i11, i12, i22, a0, a1, a2, s0, s1, s2)
        hs = sym3_bilinear(i00, i01, i02, i11, i12, i22, h0, h1, h2, s0, s1, s2)
        var1 += gs1 * gs1
        var2 += gs2 * gs2
        vard += as_ * as_ + hs * hs
    rss = bb - xatb
    if tilt is not None:
        drop, extra = tilt_residual(i00, i01, i02, i11, i12, i22, x0, x1, x2, s0, s1, s2, tilt)
        rss -= drop
        dof -= 2.0 + (extra if shared > 0 else 0.0)
        m -= 2
    store_parts(p, k1_se, k2_se, parts, var1, var2, rss, dof if m > 3 else 0.0, vard, math.hypot(0.5 * (e - g), f))


@jit
def sym3_sandwich(i00, i01, i02, i11, i12, i22, meat, g0, g1, g2):
    """``tᵀ B t + (tᵀ s)²`` with ``t = M⁻¹ g`` (M⁻¹'s entries i00 .. i22; B, s the weighted sums in
    ``meat``, :func:`store_se3_weighted`): the variance of ``gᵀx`` per unit height variance."""
    t0 = i00 * g0 + i01 * g1 + i02 * g2
    t1 = i01 * g0 + i11 * g1 + i12 * g2
    t2 = i02 * g0 + i12 * g1 + i22 * g2
    shared = t0 * meat[1] + t1 * meat[2] + t2 * meat[3]
    return (t0 * (meat[6] * t0 + meat[7] * t1 + meat[8] * t2) + t1 * (meat[7] * t0 + meat[9] * t1 + meat[10] * t2)
            + t2 * (meat[8] * t0 + meat[10] * t1 + meat[11] * t2) + shared * shared)


@jit
def store_se3_weighted(p, a00, a01, a02, a11, a12, a22, bb, xatb, m, e, f, g, x0, x1, x2, tilt, meat, k1_se, k2_se,
                       parts):
    """Row p of the standard errors' parts of a 3-unknown fit whose equations' errors are known
    multiples of height errors: equation j's error is ``c_j (h_q - h_p)``, with h the heights' errors
    (independent, one variance sigma_h²) and q its neighbour (nc: a normal curvature ``2 w / l²``
    moves by ``c_j = 2 / l²`` per unit height, so its noise grows toward the near neighbours).

    The errors' covariance is ``sigma_h² (C² + c cᵀ)`` (C = diag(c), the centre's height shared by
    all), so with the sandwich ``B = Σ c_j² a_j a_jᵀ`` and ``s = Σ c_j a_j``:

    - ``var(gᵀx) = sigma_h² (gᵀM⁻¹BM⁻¹g + (gᵀM⁻¹s)²)``;
    - ``E[RSS] = sigma_h² tr((I - H)(C² + c cᵀ)) = sigma_h² (2 Σ c² - tr(M⁻¹B) - sᵀM⁻¹s)``.

    The noise level is read, as in :func:`store_se3`, from the residuals of the fit with the frame's
    tilt as two more unknowns (L their columns; whatever the tilt, it leaves no trace in them):
    ``RSS₅ = RSS₃ - r_Lᵀ S⁻¹ r_L``, and the hat matrix grows by ``Kᵀ S⁻¹ K`` with ``K = [-T, I]``,
    ``T = LᵀQ M⁻¹``, which takes ``tr(S⁻¹ K B₅ Kᵀ) + d_Lᵀ S⁻¹ d_L`` (``d_L = s_L - T s``) more from
    ``E[RSS] / sigma_h²``. ``sigma_h²`` is a height variance, so it pools across vertices in one unit.

    Parameters
    ----------
    a00 .. a22 : float
        M = AᵀA (unweighted: the fit's own normal equations).
    bb, xatb : float
        bᵀb and xᵀAᵀb.
    m : int
        Equations.
    e, f, g : float
        The fitted W; ``x0, x1, x2`` the solution.
    tilt : (13,) float64
        The tilt columns' sums (:func:`tilt_residual`).
    meat : (21,) float64
        ``Σ c²``, ``s = Σ c a`` (3), ``s_L = Σ c L`` (2), ``B_QQ = Σ c² a aᵀ`` (upper triangle, 6),
        ``B_LQ = Σ c² L aᵀ`` (row u: 3, row v: 3), ``B_LL = Σ c² L Lᵀ`` (3).
    k1_se, k2_se, parts :
        As in :func:`store_parts`.
    """
    if parts.shape[0] == 0:
        return  # no standard errors asked (:func:`run_fit`)
    i00, i01, i02, i11, i12, i22 = sym3_inverse(a00, a01, a02, a11, a12, a22)
    g10, g11, g12, g20, g21, g22 = principal_gradients(e, f, g)
    a0, a1, a2, h0, h1, h2 = deviator_gradients(e, f, g)
    var1 = sym3_sandwich(i00, i01, i02, i11, i12, i22, meat, g10, g11, g12)
    var2 = sym3_sandwich(i00, i01, i02, i11, i12, i22, meat, g20, g21, g22)
    vard = (sym3_sandwich(i00, i01, i02, i11, i12, i22, meat, a0, a1, a2)
            + sym3_sandwich(i00, i01, i02, i11, i12, i22, meat, h0, h1, h2))
    sc0, sc1, sc2 = meat[1], meat[2], meat[3]
    b0, b1, b2, b3, b4, b5 = meat[6], meat[7], meat[8], meat[9], meat[10], meat[11]
    # tr(M⁻¹ B) and sᵀM⁻¹s
    trace = i00 * b0 + i11 * b3 + i22 * b5 + 2.0 * (i01 * b1 + i02 * b2 + i12 * b4)
    spare = 2.0 * meat[0] - trace - sym3_bilinear(i00, i01, i02, i11, i12, i22, sc0, sc1, sc2, sc0, sc1, sc2)
    drop, _ = tilt_residual(i00, i01, i02, i11, i12, i22, x0, x1, x2, 0.0, 0.0, 0.0, tilt)
    rss = bb - xatb - drop
    # the tilt's share of the hat matrix
    tu0, tu1, tu2, tv0, tv1, tv2, s_uu, s_uv, s_vv = tilt_schur(i00, i01, i02, i11, i12, i22, tilt)
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
    store_parts(p, k1_se, k2_se, parts, var1, var2, rss, spare if m > 5 else 0.0, vard, math.hypot(0.5 * (e - g), f))


@jit
def cholesky_scaled(ata, size, work, srow):
    """Jacobi-scaled Cholesky ``D A D = L Lᵀ`` of a symmetric A (the lower triangle of its leading ``size`` block).

    Writes L to the lower triangle and diagonal of ``work`` and D = diag(A)^(-1/2) to ``work[srow]``;
    ``work`` may be ``ata`` itself (each entry of A is read before its place is written).

    Returns
    -------
    bool
        False when A is not positive definite.
    """
    for i in range(size):
        d = ata[i, i]
        if not d > 0.0:
            return False
        work[srow, i] = 1.0 / math.sqrt(d)
    for j in range(size):
        acc = 1.0
        for k in range(j):
            acc -= work[j, k] * work[j, k]
        if not acc > 1e-300:
            return False
        ljj = math.sqrt(acc)
        work[j, j] = ljj
        for i in range(j + 1, size):
            t = ata[i, j] * work[srow, i] * work[srow, j]
            for k in range(j):
                t -= work[i, k] * work[j, k]
            work[i, j] = t / ljj
    return True


@jit
def factor_whiten(factor, scales, srow, size, rows):
    """Replace each row v of ``rows`` by ``L⁻¹ D v``, from ``D A D = L Lᵀ``, so that ``gᵀA⁻¹h`` is the
    dot product of the whitened g and h.

    Parameters
    ----------
    factor : (K, K) float64
        L in its lower triangle and diagonal (:func:`cholesky_scaled`, or the jet's
        ``solve_spd_scaled``).
    scales : (R, K) float64
        ``scales[srow, :size]`` is the diagonal of D.
    srow, size : int
    rows : (r, K) float64
        Overwritten in their first ``size`` columns.
    """
    for r in range(rows.shape[0]):
        for i in range(size):
            # forward substitution in place: rows[r, :i] already hold (L⁻¹ D v)[:i]
            t = rows[r, i] * scales[srow, i]
            for k in range(i):
                t -= factor[i, k] * rows[r, k]
            rows[r, i] = t / factor[i, i]


@jit
def row_dot(rows, i, j, size):
    """``rows[i, :size] . rows[j, :size]``."""
    acc = 0.0
    for k in range(size):
        acc += rows[i, k] * rows[j, k]
    return acc


@jit
def slice_bounds(lo, hi, t, parts):
    """Vertices ``start .. stop-1`` of slice t of ``parts`` equal slices of ``lo .. hi-1``."""
    return lo + (hi - lo) * t // parts, lo + (hi - lo) * (t + 1) // parts


@jit
def finish_fit(p, e, f, g, singular, used, frame, k1, k2, d1, d2, reason):
    """Write vertex p's principal curvatures, directions and reason from its fitted (e, f, g).

    ``frame`` is (ux, uy, uz, vx, vy, vz) from :func:`tangent_frame`; ``used`` the number of
    usable neighbours. The fit's own codes: TOO_FEW_NEIGHBOURS before SINGULAR (too few rows
    decide no system), else OK. They stand where :func:`curv.core.validity.precedence` puts
    SINGULAR: the input's flags (non-manifold, degenerate, border) then mark only the rows left OK
    (:func:`curv.estimate_finish.finish`).
    """
    ux, uy, uz, vx, vy, vz = frame
    store_principal(p, e, f, g, ux, uy, uz, vx, vy, vz, k1, k2, d1, d2)
    if used < MIN_PAIRS:
        reason[p] = TOO_FEW
    elif singular or not math.isfinite(k1[p]):
        reason[p] = SINGULAR
    else:
        reason[p] = OK


@jit
def fit_frame(p, nx, ny, nz, k1, k2, d1, d2, reason, parts):
    """Start vertex p's fit: clear its row of the standard errors' ``parts`` (:func:`clear_parts`)
    and read its normal and tangent frame (:func:`tangent_frame`).

    Returns
    -------
    n0, n1, n2 : float
        The normal.
    frame : tuple of 6 float
    ok : bool
        False without a finite normal: the vertex is then marked (:func:`mark_degenerate`) and
        ``frame`` is NaN.
    """
    clear_parts(p, parts)
    n0, n1, n2 = nx[p], ny[p], nz[p]
    if not (math.isfinite(n0) and math.isfinite(n1) and math.isfinite(n2)):
        mark_degenerate(p, k1, k2, d1, d2, reason)
        return n0, n1, n2, (math.nan, math.nan, math.nan, math.nan, math.nan, math.nan), False
    return n0, n1, n2, tangent_frame(n0, n1, n2), True


@jit
def normal_in_frame(q, nx, ny, nz, frame, n0, n1, n2):
    """Vertex q's normal in p's frame (U, V, N = (n0, n1, n2)): ``(a, b, c)``."""
    ux, uy, uz, vx, vy, vz = frame
    return (nx[q] * ux + ny[q] * uy + nz[q] * uz, nx[q] * vx + ny[q] * vy + nz[q] * vz,
            nx[q] * n0 + ny[q] * n1 + nz[q] * n2)


@jit
def mark_degenerate(p, k1, k2, d1, d2, reason):
    """Vertex p has no usable normal, so no frame to fit in."""
    k1[p] = math.nan
    k2[p] = math.nan
    d1[p, :] = math.nan
    d2[p, :] = math.nan
    reason[p] = DEGENERATE


NOISE_MODELS = ("sampled", "independent", "normals")
"""How the standard errors of ``an`` and ``mru`` (the fits that read the neighbours' normals) take
the errors of those normals (the curvatures do not depend on it):

- ``"sampled"`` (the default): the ``"normals"`` model's effect measured at a sample of the mesh's
  vertices (:data:`SAMPLE_SIZE`, evenly spaced) and applied to every vertex: each vertex's
  independent-equation propagation is scaled by the median, over the sample, of the ratio of the
  two models' ``var(k_i) / E[RSS]`` (:func:`sampled_scales`), and the noise level is pooled over the
  vertex and its edge neighbours. Within a few percent of ``"normals"`` on the noisy study meshes
  (regular and irregular) at about the independent model's cost. One factor for the whole mesh (or
  region): where the mesh's regularity changes from place to place, the vertices unlike the sample's
  majority get the majority's factor. A point cloud keeps the independent model.
- ``"independent"``: every equation's error independent, the noise level read from the vertex's own
  residuals (with the tilt of its own normal as two more unknowns). Where the normals are made from
  noisy vertex positions, as a mesh's are, neighbouring normals share faces and their errors are
  correlated, so ``± 2 se`` holds less than the nominal 95 % (docs/UNCERTAINTY.md gives the figures).
- ``"normals"``: the errors as the normals take them from independent height noise (each vertex
  normal tilts by the least-squares height gradient of its ring), followed exactly through the fit
  and pooled over the vertex's edge neighbours, at every vertex; calibrated on noisy meshes with
  their default normals, and 3-5 times the whole call's time (it visits every neighbour's ring:
  docs/UNCERTAINTY.md, Cost, says where the time goes). A point cloud, or a ring without a
  gradient, keeps the independent model."""

DEFAULT_NOISE_MODEL = NOISE_MODELS[0]


def checked_noise_model(noise_model: str) -> str:
    """``noise_model`` if it is one of :data:`NOISE_MODELS`; else an
    :class:`~curv.core.errors.EstimatorError` naming the choices."""
    if noise_model not in NOISE_MODELS:
        raise EstimatorError(f"noise_model must be one of {', '.join(NOISE_MODELS)}; got {noise_model!r}")
    return noise_model


SAMPLE_SIZE = 2000
"""Vertices at which ``noise_model="sampled"`` runs the normals' model (:func:`sampled_scales`)."""
SAMPLE_RUN = 125
"""... in runs of this many consecutive vertices (16 runs)."""


def sampled_scales(kernel, fitted, radius, adj_ptr, adj, x, y, z, nx, ny, nz, queues, k1, k2, d1, d2, reason,
                   k1_se, k2_se, parts, ring_ptr, ring) -> np.ndarray | None:
    """The factors by which the normals' model scales the independent model's standard errors,
    measured at a sample of the fitted vertices (``noise_model="sampled"``).

    Both models read the noise level from the same residuals, so at a vertex the ratio of their
    ``var(k_i) / E[RSS]`` (propagation per unit noise variance over the spare equations it expects)
    is the factor between their squared standard errors, free of the noise's units. The kernel runs
    again with its slot maps at up to :data:`SAMPLE_SIZE` vertices (all of ``fitted`` or runs of
    :data:`SAMPLE_RUN` consecutive ones, evenly spaced); the factors are the medians over the sample
    where both models hold.

    Parameters
    ----------
    kernel, fitted, radius, ..., ring :
        As in :func:`run_fit`, after the independent model's run: ``k1_se``, ``k2_se`` hold
        ``var(k_i) / sigma²`` and ``parts`` the parts of :func:`store_parts` (spare equations
        negative: the independent model's noise level, in units of the normals).

    Returns
    -------
    (3,) float64 or None
        The factors of ``var(k1)``, ``var(k2)`` and the deviator's variance; None when no sampled
        vertex holds both models. The rows of the sample are left as the independent run wrote them.
    """
    if fitted.size <= SAMPLE_SIZE:
        sample = fitted
    else:
        # runs of consecutive vertices, evenly spaced: a run's supports share the pages of the
        # fresh scratch below (single vertices spread over the mesh cost a page fault each)
        starts = np.linspace(0, fitted.size - SAMPLE_RUN, SAMPLE_SIZE // SAMPLE_RUN).astype(np.int64)
        sample = fitted[(starts[:, None] + np.arange(SAMPLE_RUN)).ravel()]
    sample = sample[(reason[sample] == OK) & (parts[sample, 1] < 0.0)]
    if sample.size == 0:
        return None
    kept = k1_se[sample], k2_se[sample], parts[sample]
    stamps = new_scratch(x.size, max(1, min(threads(), sample.size // SAMPLE_RUN)))  # fresh marks
    slots = new_scratch(x.size, stamps.shape[0])
    launch(kernel, sample, 0, sample.size, radius, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues,
           k1, k2, d1, d2, reason, k1_se, k2_se, parts, ring_ptr, ring, slots)
    exact = parts[sample, 1] > 0.0  # the normals' model held (else the kernel fell back)
    per_spare_exact = np.stack([k1_se[sample], k2_se[sample], parts[sample, 2]]) / parts[sample, 1]
    per_spare_indep = np.stack([kept[0], kept[1], kept[2][:, 2]]) / -kept[2][:, 1]
    k1_se[sample], k2_se[sample], parts[sample] = kept
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = per_spare_exact[:, exact] / per_spare_indep[:, exact]
    ratio = ratio[:, np.all(np.isfinite(ratio) & (ratio > 0.0), axis=0)]
    if ratio.shape[1] == 0:
        return None
    return np.median(ratio, axis=1)


def run_fit(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, kernel, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, noise_model: str | None = None,
            standard_errors: bool = True, levels_kernel=None) -> Generator[float, None, Principal | list]:
    """Run a fit kernel over all (or some) vertices, a chunk of them per call, and assemble the result.

    ``radii`` of shape ``(levels, n)`` (several ranges, ascending per vertex) gives one result per
    level (:func:`run_fit_levels`).

    Parameters
    ----------
    mesh : Mesh
    normals : (n, 3) float64
        Unit vertex normals (NaN rows: no frame, the vertex is ``DEGENERATE``).
    radii : (n,) float64
        Ball radius of every vertex (:func:`curv.core.ranges.ball_radii`).
    kernel : callable
        A numba kernel (or a :func:`functools.partial` of one, binding its leading arguments):
        ``kernel(centres, lo, hi, radius, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, k1, k2,
        d1, d2, reason, k1_se, k2_se, parts, ring_ptr, ring, slots)`` estimates the vertices
        ``centres[lo:hi]``, splitting them into ``stamps.shape[0]`` slices, each with its own row of the
        stamps, queues and slots, and writes the parts of their standard errors (:func:`store_parts`);
        ``ring_ptr, ring`` are the mesh's edge neighbours (none on a point cloud,
        :func:`curv.estimators._pooling.pool_rings`).
    chunk : int, optional
        Vertices per call (default adaptive).
    centres : (c,) int64, optional
        The vertices to estimate (default all); the other rows of the outputs are left unset. On a
        mesh the fits also run at their neighbours (:func:`curv.estimators._pooling.pool_members`;
        ``radii`` must cover them), whose residuals the standard errors pool.
    features : curv.core.features.FeatureSet, optional
        The search does not expand through feature vertices.
    noise_model : str, optional
        For the fits with a model of their normals' errors (an, mru; :data:`NOISE_MODELS`):
        ``"normals"`` gives the kernel a zeroed (slices, n) int64 ``slots`` (vertex -> 1 + its place in
        a short list, reset after each vertex) instead of an empty one; ``"sampled"`` runs the kernel
        without and scales the standard errors by :func:`sampled_scales` on a mesh.
    standard_errors : bool
        False: the caller reads no standard errors, so the fits run at ``centres`` only (not at a
        region's pooling neighbours), there is no pooling pass and no sample of ``noise_model``,
        and the result's ``k1_se``, ``k2_se`` are None. The curvatures, directions and reasons are
        the same either way (each vertex's fit reads only its own support).

    levels_kernel : callable, optional
        The kernel of :func:`run_fit_levels` for ``(levels, n)`` radii.

    It yields the fraction of vertices done and returns the :class:`~curv.core.result.Principal`,
    as the estimators' functions do (:data:`~curv.estimators.registry.EstimatorFunction`).
    """
    if np.ndim(radii) == 2:
        return (yield from run_fit_levels(mesh, normals, radii, kernel, levels_kernel, chunk=chunk, centres=centres,
                                          features=features, noise_model=noise_model,
                                          standard_errors=standard_errors))
    n = mesh.n_vertices
    given = centres is not None
    centres = all_centres(n, centres)
    if standard_errors:
        # each vertex once (the pooling pass updates its rows in place)
        pooled = np.unique(centres) if given else centres
        whole = pooled.size == n
        # a region's standard errors pool its neighbours' residuals too: fit them as well
        fitted = centres if whole else pool_members(mesh, pooled)
    else:
        # no pooling: a vertex listed twice is fitted twice, to the same values
        fitted = centres
        whole = not given
    ring_ptr, ring = pool_rings(mesh)
    adj_ptr, adj = expansion_adjacency(mesh, blocked_vertices(features), radii)
    x, y, z = coordinate_columns(mesh)
    nx, ny, nz = (np.ascontiguousarray(normals[:, c]) for c in range(3))
    radius = np.ascontiguousarray(radii, dtype=np.float64)
    stamps = new_scratch(n, max(1, min(threads(), fitted.size)))
    queues = new_queues(n, stamps.shape[0])
    k1, k2 = np.empty(n), np.empty(n)
    d1, d2 = np.empty((n, 3)), np.empty((n, 3))
    reason = np.empty(n, np.uint8)
    if standard_errors:
        k1_se, k2_se = filled(n, np.nan, most_written=whole), filled(n, np.nan, most_written=whole)
        parts = filled((n, 4), np.nan, most_written=whole)
    else:
        # no rows: the kernels skip the standard errors' sums and write none (clear_parts, store_parts)
        k1_se, k2_se, parts = np.empty(0), np.empty(0), np.empty((0, 4))
    slots = new_scratch(n if noise_model == "normals" and standard_errors else 0, stamps.shape[0])

    def run(lo: int, hi: int) -> None:
        launch(kernel, fitted, lo, hi, radius, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues,
               k1, k2, d1, d2, reason, k1_se, k2_se, parts, ring_ptr, ring, slots)

    yield from iter_chunks(fitted.size, run, chunk=chunk)
    if not standard_errors:
        return Principal(k1=k1, k2=k2, d1=d1, d2=d2, reason=reason)
    if noise_model == "sampled" and ring.size > 0:
        scales = sampled_scales(kernel, fitted, radius, adj_ptr, adj, x, y, z, nx, ny, nz, queues, k1, k2, d1, d2,
                                reason, k1_se, k2_se, parts, ring_ptr, ring)
        if scales is not None:
            # the independent model's noise levels, now all of the same units: pooled
            at = slice(None) if whole else fitted
            k1_se[at] *= scales[0]
            k2_se[at] *= scales[1]
            parts[at, 2] *= scales[2]
            np.abs(parts[:, 1], out=parts[:, 1])
    pool_standard_errors(pooled, ring_ptr, ring, reason, parts, k1_se, k2_se)
    if not whole:
        extra = np.setdiff1d(fitted, pooled, assume_unique=True)
        k1_se[extra] = np.nan
        k2_se[extra] = np.nan
    return Principal(k1=k1, k2=k2, d1=d1, d2=d2, reason=reason, k1_se=k1_se, k2_se=k2_se)


def run_fit_levels(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, kernel, levels_kernel, *,
                   chunk: int | None = None, centres: np.ndarray | None = None, features=None,
                   noise_model: str | None = None, standard_errors: bool = True) -> Generator[float, None, list]:
    """A fit at several ranges: one :class:`~curv.core.result.Principal` per row of ``radii``.

    Without standard errors, on a mesh, the ranges share one walk per vertex and its sums:
    ``levels_kernel`` widens the support level by level
    (:func:`~curv.geometry.neighbourhood.widen_ball_support`: each level's support is exactly the
    single search's at its radius), adds the rows of the vertices each level brings to the normal
    equations of the last and solves them at every level. The sums are added in the walk's order,
    not the single search's, so the values agree with one call per range to rounding (the first
    level's order is the single search's: its values are bit for bit those of its own call where
    the rows do not depend on the radius, nc, qs and mru; an's are summed in the widest level's
    coordinates). Otherwise (standard errors, whose sums do not share, or a
    point cloud) each level runs :func:`run_fit` on its own.

    Parameters
    ----------
    mesh, normals, kernel, chunk, centres, features, noise_model, standard_errors :
        As in :func:`run_fit`.
    radii : (levels, n) float64
        The radii of every vertex at each level, ascending per vertex.
    levels_kernel : callable
        ``levels_kernel(centres, lo, hi, radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues,
        outside, outside_d2, k1, k2, d1, d2, reason)``: the vertices ``centres[lo:hi]`` in
        ``stamps.shape[0]`` slices, each with its row of the stamps, queues and the walk's waiting
        vertices (``outside`` int64, ``outside_d2`` float64); writes column p of the ``(levels, n)``
        ``k1, k2, reason`` and ``(levels, n, 3)`` ``d1, d2``.
    """
    radii = np.ascontiguousarray(radii, dtype=np.float64)
    count = radii.shape[0]
    if standard_errors or levels_kernel is None or not isinstance(mesh, Mesh):
        out = []
        for level in range(count):
            gen = run_fit(mesh, normals, radii[level], kernel, chunk=chunk, centres=centres, features=features,
                          noise_model=noise_model, standard_errors=standard_errors)
            out.append((yield from rescaled(gen, level / count, (level + 1) / count)))
        return out
    n = mesh.n_vertices
    centres = all_centres(n, centres)
    adj_ptr, adj = expansion_adjacency(mesh, blocked_vertices(features))
    x, y, z = coordinate_columns(mesh)
    nx, ny, nz = (np.ascontiguousarray(normals[:, c]) for c in range(3))
    stamps = new_scratch(n, max(1, min(threads(), centres.size)))
    queues = new_queues(n, stamps.shape[0])
    outside, outside_d2 = new_queues(n, stamps.shape[0]), np.empty((stamps.shape[0], n))
    k1, k2 = np.empty((count, n)), np.empty((count, n))
    d1, d2 = np.empty((count, n, 3)), np.empty((count, n, 3))
    reason = np.empty((count, n), np.uint8)

    def run(lo: int, hi: int) -> None:
        launch(levels_kernel, centres, lo, hi, radii, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, outside,
               outside_d2, k1, k2, d1, d2, reason)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return [Principal(k1=k1[i], k2=k2[i], d1=d1[i], d2=d2[i], reason=reason[i]) for i in range(count)]


@jit
def start_levels(p, radii, nx, ny, nz, k1, k2, d1, d2, reason):
    """Start vertex p's fit at every level (:func:`run_fit_levels`): its normal and tangent frame
    (:func:`tangent_frame`) and ``(MIN_TANGENT_LENGTH * r)²`` at the widest level, the bound below
    which a row's tangent length may count at one level and not at a wider one.

    Returns
    -------
    n0, n1, n2 : float
    frame : tuple of 6 float
    band2 : float
    ok : bool
        False without a finite normal: every level's row p is marked (:func:`mark_degenerate`).
    """
    n0, n1, n2 = nx[p], ny[p], nz[p]
    if not (math.isfinite(n0) and math.isfinite(n1) and math.isfinite(n2)):
        for level in range(radii.shape[0]):
            mark_degenerate(p, k1[level], k2[level], d1[level], d2[level], reason[level])
        return n0, n1, n2, (math.nan, math.nan, math.nan, math.nan, math.nan, math.nan), 0.0, False
    band2 = (MIN_TANGENT_LENGTH * radii[radii.shape[0] - 1, p]) ** 2
    return n0, n1, n2, tangent_frame(n0, n1, n2), band2, True
