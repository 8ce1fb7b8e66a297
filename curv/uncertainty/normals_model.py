"""The errors a fit's equations take from noisy heights through the normals (``noise_model="normals"``).

A vertex normal made from its faces tilts, to first order, by the height gradient of its ring (for
a regular ring the area- and Max-weighted normals are exactly the least-squares gradient,
:func:`ring_gradient`), so with independent height errors h (variance sigma_h²), in the fit's
frame (U, V) at p and in coordinates divided by the ball radius r where the fit uses them:

- a **height equation** of neighbour q (an) errs by ``(h_q - h_p) / r - (U, V) · J_p h``: its own
  and the centre's heights, and the frame's tilt moving every height by its slope times the offset;
- a **slope equation** of q (an's slopes, mru's normal differences) errs by ``(J_q - J_p) h``, row u
  or v: q's own normal and the tilt of p's, the frame.

Neighbouring normals share vertices and every equation shares p's height and normal, so the errors
are correlated; the propagation follows them exactly: with ``y_j = Σ_eq A_eqᵀ J̃_eq,j`` (J̃ the
equations' columns over the heights) the fit's error is ``M⁻¹ Σ_j y_j h_j``, so
``var(gᵀx) = sigma_h² Σ_j (gᵀM⁻¹y_j)²`` and ``E[RSS] = sigma_h² (‖J̃‖² - Σ_j y_jᵀM⁻¹y_j)``.

The fit feeds the model its equations as it makes them (:func:`model_height`,
:func:`model_slopes`, after :func:`model_start`) and finishes it with its factored normal matrix
(:func:`model_finish`). The ``y_j`` live in short per-vertex lists (:class:`Lists`), one entry per
vertex the equations reach; row t of ``slots`` (thread slice t's) maps a vertex to 1 + its entry
(0: absent) and is reset after each vertex. Without a :class:`NoiseModel` (None) numba compiles the
fit without any of this.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..core.jit import jit
from ..core.small_linalg import factor_whiten, row_dot

__all__ = ["NoiseModel", "Lists", "new_lists", "ring_gradient", "gradient_column", "model_start", "model_height",
           "model_slopes", "model_finish", "model_release", "SLOT_BYTES"]

NoiseModel = namedtuple("NoiseModel", ["ring_ptr", "ring", "slots"])
"""The model's inputs: a mesh's edge neighbours (CSR ``ring_ptr`` (n+1,), ``ring`` int64) and the
slot maps, (thread slices, n) int64 zeros."""

Lists = namedtuple("Lists", ["touched", "yv", "jp", "agg", "wrow"])
"""One vertex's short lists (:func:`list_slot`): ``touched`` (cap,) int64 the vertices listed,
``yv`` (cap, K) their ``y_j``, ``jp`` (cap, 2) the columns of p's own ring gradient; ``agg`` (5, K)
the sums of the height rows, of the height rows times U and V, of the u- and v-slope rows;
``wrow`` (1, K) scratch. K is the fit's number of unknowns."""

SLOT_BYTES = 16.0
"""The model's vertex slots (an int64 per vertex and kernel thread, 4 threads) per size unit."""


@jit
def new_lists(unknowns):
    """Empty :class:`Lists` for a fit of ``unknowns`` unknowns (grown by :func:`model_start`)."""
    return Lists(np.empty(64, np.int64), np.empty((64, unknowns)), np.empty((64, 2)), np.empty((5, unknowns)),
                 np.empty((1, unknowns)))


@jit
def ring_gradient(v, noise, geometry, frame):
    """The least-squares height gradient at vertex v from its edge neighbours, in the frame (U, V):
    ``grad = G⁻¹ Σ_j d_j (h_j - h_v)`` with d_j the tangent offsets and ``G = Σ d_j d_jᵀ``.

    Returns
    -------
    gradient : (i00, i01, i11, sdu, sdv)
        G⁻¹ and ``Σ d_j`` (the column of h_v is ``-G⁻¹ Σ d_j``).
    ok : bool
        False when G is singular (fewer than two independent directions).
    """
    ux, uy, uz, vx, vy, vz = frame[0], frame[1], frame[2], frame[3], frame[4], frame[5]
    x, y, z = geometry.x, geometry.y, geometry.z
    g00 = g01 = g11 = sdu = sdv = 0.0
    for k in range(noise.ring_ptr[v], noise.ring_ptr[v + 1]):
        w = noise.ring[k]
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
        return (0.0, 0.0, 0.0, 0.0, 0.0), False
    return (g11 / det, -g01 / det, g00 / det, sdu, sdv), True


@jit
def gradient_column(w, v, gradient, geometry, frame):
    """The column of vertex w (v itself or one of its edge neighbours) in :func:`ring_gradient`'s
    gradient at v: ``G⁻¹ d_w``, or ``-G⁻¹ Σ d_j`` for v. Returns its two components."""
    i00, i01, i11, sdu, sdv = gradient
    if w == v:
        return -(i00 * sdu + i01 * sdv), -(i01 * sdu + i11 * sdv)
    ux, uy, uz, vx, vy, vz = frame[0], frame[1], frame[2], frame[3], frame[4], frame[5]
    x, y, z = geometry.x, geometry.y, geometry.z
    dx, dy, dz = x[w] - x[v], y[w] - y[v], z[w] - z[v]
    du = dx * ux + dy * uy + dz * uz
    dv = dx * vx + dy * vy + dz * vz
    return i00 * du + i01 * dv, i01 * du + i11 * dv


@jit
def _list_room(queue, count, noise, lists):
    """``lists`` grown to hold every vertex the support ``queue[:count]`` and their edge neighbours
    can bring."""
    need = 0
    for i in range(count):
        q = queue[i]
        need += noise.ring_ptr[q + 1] - noise.ring_ptr[q] + 1
    if need <= lists.touched.size:
        return lists
    return Lists(np.empty(need, np.int64), np.empty((need, lists.yv.shape[1])), np.empty((need, 2)), lists.agg,
                 lists.wrow)


@jit
def _list_slot(w, slots, t, lists, used):
    """The place of vertex w in the short lists of thread slice t (added, with zero sums, when new).
    Returns ``(place, used)``: ``used`` entries are in use."""
    s = slots[t, w]
    if s > 0:
        return s - 1, used
    lists.touched[used] = w
    lists.yv[used, :] = 0.0
    lists.jp[used, 0] = lists.jp[used, 1] = 0.0
    slots[t, w] = used + 1
    return used, used + 1


@jit
def _centre_columns(p, t, noise, geometry, frame, lists):
    """The columns of p's own ring gradient, J_p: the tilt of p's normal, the frame every equation
    shares; written to ``lists.jp`` at each vertex's entry.

    Returns
    -------
    used : int
        Entries in use (0 when not ok).
    ok : bool
        False when p's ring has no gradient.
    p00, p01, p11 : float
        ``J_p`` 's row products ``Σ c0²``, ``Σ c0 c1``, ``Σ c1²``.
    """
    gradient, ok = ring_gradient(p, noise, geometry, frame)
    used = 0
    p00 = p01 = p11 = 0.0
    if not ok:
        return used, ok, p00, p01, p11
    for k in range(noise.ring_ptr[p], noise.ring_ptr[p + 1] + 1):
        w = p if k == noise.ring_ptr[p + 1] else noise.ring[k]
        c0, c1 = gradient_column(w, p, gradient, geometry, frame)
        s, used = _list_slot(w, noise.slots, t, lists, used)
        lists.jp[s, 0] = c0
        lists.jp[s, 1] = c1
        p00 += c0 * c0
        p01 += c0 * c1
        p11 += c1 * c1
    return used, ok, p00, p01, p11


@jit
def model_start(p, t, queue, count, noise, geometry, frame, lists):
    """Start vertex p's model (in thread slice t) over its support ``queue[:count]``: room in the
    lists, zero sums, the columns of p's own normal.

    Returns
    -------
    state : (used, ok, spare, p00, p01, p11, sp, t)
        Entries in use, whether every ring so far has a gradient, ``E[RSS] / sigma_h²`` so far, J_p's
        row products, p's own entry and the thread slice.
    lists : Lists
        Grown, perhaps.
    """
    if noise is None:
        return (0, False, 0.0, 0.0, 0.0, 0.0, 0, t), lists
    lists = _list_room(queue, count, noise, lists)
    lists.agg[:, :] = 0.0
    used, ok, p00, p01, p11 = _centre_columns(p, t, noise, geometry, frame, lists)
    sp = noise.slots[t, p] - 1 if ok else 0
    return (used, ok, 0.0, p00, p01, p11, sp, t), lists


@jit
def model_height(state, q, row, u, v, inv_r, noise, lists):
    """Add neighbour q's height equation (``row`` a K-tuple, at the scaled tangent offset (u, v)) to the
    model: its error ``(h_q - h_p) / r - (U, V) · J_p h`` (module notes)."""
    used, ok, spare, p00, p01, p11, sp, t = state
    if noise is None or not ok:
        return state
    s, used = _list_slot(q, noise.slots, t, lists, used)
    yv, jp, agg = lists.yv, lists.jp, lists.agg
    for j in range(len(row)):
        yv[s, j] += row[j] * inv_r
        agg[0, j] += row[j]
        agg[1, j] += row[j] * u
        agg[2, j] += row[j] * v
    # ‖(e_q - e_p) / r - U J_p0 - V J_p1‖²
    tq = u * jp[s, 0] + v * jp[s, 1]
    tp = u * jp[sp, 0] + v * jp[sp, 1]
    spare += (2.0 * inv_r * inv_r + u * u * p00 + 2.0 * (u * v) * p01 + v * v * p11 - 2.0 * inv_r * (tq - tp))
    return used, ok, spare, p00, p01, p11, sp, t


@jit
def model_slopes(state, q, ru, rv, noise, geometry, frame, lists):
    """Add neighbour q's two slope equations (rows ``ru``, ``rv``, K-tuples) to the model: their errors
    ``(J_q - J_p) h``, rows u and v (module notes). A ring without a gradient ends the model
    (``ok`` False: the caller keeps the independent equations)."""
    used, ok, spare, p00, p01, p11, sp, t = state
    if noise is None or not ok:
        return state
    agg = lists.agg
    for j in range(len(ru)):
        agg[3, j] += ru[j]
        agg[4, j] += rv[j]
    gradient, ok = ring_gradient(q, noise, geometry, frame)
    if not ok:
        return used, ok, spare, p00, p01, p11, sp, t
    jqn = cross = 0.0
    yv, jp = lists.yv, lists.jp
    for k in range(noise.ring_ptr[q], noise.ring_ptr[q + 1] + 1):
        w = q if k == noise.ring_ptr[q + 1] else noise.ring[k]
        c0, c1 = gradient_column(w, q, gradient, geometry, frame)
        s, used = _list_slot(w, noise.slots, t, lists, used)
        for j in range(len(ru)):
            yv[s, j] += ru[j] * c0 + rv[j] * c1
        jqn += c0 * c0 + c1 * c1
        cross += c0 * jp[s, 0] + c1 * jp[s, 1]
    spare += jqn + p00 + p11 - 2.0 * cross
    return used, ok, spare, p00, p01, p11, sp, t


@jit
def model_finish(state, factor, srow, grads, inv_r, noise, lists):
    """The model's variances from the fit's normal matrix, factored by
    :func:`~curv.core.small_linalg.cholesky_scaled` (``factor``, D in row ``srow``), and the
    gradients ``grads`` (7, K), whitened by it (:func:`~curv.core.small_linalg.factor_whiten`): rows
    0 and 1 those of k1 and k2, rows 5 and 6 those of the deviator's two components. Resets the slots.

    Returns
    -------
    var1, var2, var_dev, spare : float
        ``var / sigma_h²`` (in the fit's unknowns) and ``E[RSS] / sigma_h²``.
    ok : bool
        False where a ring had no gradient.
    """
    used, ok, spare, p00, p01, p11, sp, t = state
    var1 = var2 = vard = 0.0
    yv, jp, agg, wrow = lists.yv, lists.jp, lists.agg, lists.wrow
    size = yv.shape[1]
    for s in range(used):
        if ok:
            # the shared parts: p's height (-Σ height rows / r) and p's normal, the frame's tilt
            c0, c1 = jp[s, 0], jp[s, 1]
            for j in range(size):
                wrow[0, j] = yv[s, j] - (agg[1, j] + agg[3, j]) * c0 - (agg[2, j] + agg[4, j]) * c1
                if s == sp:
                    wrow[0, j] -= agg[0, j] * inv_r
            factor_whiten(factor, srow, size, wrow)
            spare -= row_dot(wrow, 0, 0, size)
            d1 = d2 = da = dh = 0.0
            for j in range(size):
                d1 += grads[0, j] * wrow[0, j]
                d2 += grads[1, j] * wrow[0, j]
                da += grads[5, j] * wrow[0, j]
                dh += grads[6, j] * wrow[0, j]
            var1 += d1 * d1
            var2 += d2 * d2
            vard += da * da + dh * dh
        noise.slots[t, lists.touched[s]] = 0
    return var1, var2, vard, spare, ok


@jit
def model_release(state, noise, lists):
    """Reset the slots of a model that is not finished (the fit has nothing to propagate)."""
    if noise is None:
        return
    for s in range(state[0]):
        noise.slots[state[7], lists.touched[s]] = 0
