"""The local frame of a point's support: second moments, PCA normal, widest angular gap, spread.

numba helpers that read one support (``queue[:count]``, indices into the coordinate columns) and
write into per-thread scratch; the passes that walk every point are :mod:`.one_pass`.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit
from ..core.small_linalg import sym3_eigen_closed

__all__ = ["offset_moments", "MIN_SPREAD", "GAP_BINS"]

MIN_SPREAD = 0.05
"""A support whose offsets' second principal spread (what a quadratic function of the first does
not explain, :func:`_spread`) is below this fraction of the first lies nearly along a line or a
plane curve (e.g. the six nearest points of a scan row over a curved surface): no fit of a surface
is determined by it, so the point is ``SINGULAR`` (:func:`support_spread`). On scan rows 4:1
apart, ``mru`` and ``an`` at R2 passed the fits' own singularity test there with median errors in
H of 1.0 and 320; with the plain ratio of eigenvalues (a row's sagitta read as width) and the
neighbours without a normal counted, mru's 99th percentile was still 12.6 (0.05 now)."""



@jit
def offset_moments(p, queue, count, x, y, z, centred, cov):
    """Second moments of the offsets ``q - p`` over the support ``queue[:count]`` (p included), into
    ``cov`` (3, 3): about their mean (the covariance) when ``centred``, else about p."""
    sx = sy = sz = sxx = sxy = sxz = syy = syz = szz = 0.0
    for j in range(count):
        q = queue[j]
        dx, dy, dz = x[q] - x[p], y[q] - y[p], z[q] - z[p]
        sx += dx
        sy += dy
        sz += dz
        sxx += dx * dx
        sxy += dx * dy
        sxz += dx * dz
        syy += dy * dy
        syz += dy * dz
        szz += dz * dz
    m = float(count)
    mx, my, mz = (sx / m, sy / m, sz / m) if centred else (0.0, 0.0, 0.0)
    cov[0, 0] = sxx / m - mx * mx
    cov[0, 1] = cov[1, 0] = sxy / m - mx * my
    cov[0, 2] = cov[2, 0] = sxz / m - mx * mz
    cov[1, 1] = syy / m - my * my
    cov[1, 2] = cov[2, 1] = syz / m - my * mz
    cov[2, 2] = szz / m - mz * mz


GAP_BINS = 64
"""Bins of the gap test (:func:`_widest_gap`): each keeps the least and greatest angle that falls
in it, so the widest gap is the largest step from one occupied bin's greatest angle to the next
one's least (no sort, and ``atan2`` only at the few candidate steps). Exact whenever the widest gap
is at least two bins' width (7.2 degrees), far below the tests' thresholds; a support crowding every
bin would report the largest step between bins instead."""


@jit
def _within(queue, dist2, count, radius2, out):
    """``out[:m]``: the centre ``queue[0]`` and the points of ``queue[1:count]`` within ``sqrt(radius2)``."""
    out[0] = queue[0]
    m = 1
    for j in range(1, count):
        if dist2[j] <= radius2:
            out[m] = queue[j]
            m += 1
    return m


@jit
def gap_scratch():
    """Per-thread scratch of :func:`_widest_gap`: ``(bins (6, GAP_BINS), occupied (GAP_BINS,) int64,
    edges (GAP_BINS + 1,))``, ``edges[b]`` the angle (radians, in [-pi, pi]) where bin b begins."""
    edges = np.empty(GAP_BINS + 1)
    for b in range(GAP_BINS + 1):
        # the inverse of _pseudo_angle: within a quadrant, key f gives the angle atan2(f, 1 - f)
        key = -2.0 + 4.0 * b / GAP_BINS
        whole = math.floor(abs(key))
        f = abs(key) - whole
        angle = whole * 0.5 * math.pi + math.atan2(f, 1.0 - f)
        edges[b] = angle if key >= 0.0 else -angle
    return np.empty((6, GAP_BINS)), np.empty(GAP_BINS, np.int64), edges


@jit
def _pseudo_angle(u, v):
    """A value that increases with ``atan2(v, u)`` over (-pi, pi] (signed zeros as atan2 reads them),
    in [-2, 2] (one unit a quadrant), without a trigonometric call: its rate is between 1/2 and 1
    of the angle's, so an angle step is between 1 and 2 times the value's step."""
    if v > 0.0 or (v == 0.0 and math.copysign(1.0, v) > 0.0):
        if u >= 0.0:
            return v / (u + v)
        return 1.0 - u / (v - u)
    if u >= 0.0:
        return v / (u - v)
    return -1.0 + u / (-u - v)


@jit
def _gap_bin(u, v):
    """The bin (0 .. GAP_BINS - 1) of the offset (u, v) and its pseudo-angle."""
    key = _pseudo_angle(u, v)
    return min(max(int((key + 2.0) * (GAP_BINS / 4.0)), 0), GAP_BINS - 1), key


GAP_MARGIN = 1e-9
"""Radians added to :func:`_gap_bound` for the rounding of a pseudo-angle at a bin's edge."""


@jit
def _binned_offsets(i, queue, count, x, y, z, vecs, bins):
    """The gap bins (:func:`_gap_bin`) the offsets ``q - i`` of ``queue[1:count]`` fall in, projected on
    the plane of ``vecs``'s last two eigenvectors: ``(mask, used)``, a bit per occupied bin and how
    many offsets have a tangent part. With ``bins`` (6, GAP_BINS) (not None) each occupied bin's
    rows also get its least key and that offset's u, v, then its greatest key and u, v (the bins
    the mask leaves out are not cleared)."""
    e1x, e1y, e1z = vecs[0, 2], vecs[1, 2], vecs[2, 2]
    e2x, e2y, e2z = vecs[0, 1], vecs[1, 1], vecs[2, 1]
    px, py, pz = x[i], y[i], z[i]
    mask = np.uint64(0)
    one = np.uint64(1)
    used = 0
    for j in range(1, count):
        q = queue[j]
        dx, dy, dz = x[q] - px, y[q] - py, z[q] - pz
        u = dx * e1x + dy * e1y + dz * e1z
        v = dx * e2x + dy * e2y + dz * e2z
        if u * u + v * v > 0.0:
            b, key = _gap_bin(u, v)
            bit = one << np.uint64(b)
            if bins is not None:
                if mask & bit:
                    if key < bins[0, b]:
                        bins[0, b], bins[1, b], bins[2, b] = key, u, v
                    if key > bins[3, b]:
                        bins[3, b], bins[4, b], bins[5, b] = key, u, v
                else:
                    bins[0, b], bins[1, b], bins[2, b] = key, u, v
                    bins[3, b], bins[4, b], bins[5, b] = key, u, v
            mask |= bit
            used += 1
    return mask, used


@jit
def _gap_bound(i, queue, count, x, y, z, vecs, edges):
    """An upper bound of :func:`_widest_gap` from the occupied bins alone (one bit each, nothing
    else kept): between consecutive occupied bins a and b the gap is at most the angle from a's
    start to b's end. Returns ``(bound, used)``, ``used`` the offsets with a tangent part."""
    mask, used = _binned_offsets(i, queue, count, x, y, z, vecs, None)
    one = np.uint64(1)
    if used < 2:
        return 2.0 * math.pi, used
    first = last = -1
    bound = 0.0
    for b in range(GAP_BINS):
        if (mask >> np.uint64(b)) & one:
            if last >= 0:
                bound = max(bound, edges[b + 1] - edges[last])
            else:
                first = b
            last = b
    bound = max(bound, edges[first + 1] + 2.0 * math.pi - edges[last])
    return bound + GAP_MARGIN, used


@jit
def _widest_gap(i, queue, count, x, y, z, vecs, scratch, screen):
    """Widest angle between consecutive offsets ``q - i`` projected on the plane of ``vecs``'s
    last two eigenvectors (2 pi with fewer than two); ``scratch``: :func:`gap_scratch`.

    Exact wherever it is at least ``screen`` (radians); below, an upper bound that is itself below
    ``screen`` (:func:`_gap_bound`, which costs a third of the exact measure): a test of the gap
    against a threshold of at least ``screen`` reads the same as with the exact gap everywhere.

    The exact measure: the offsets fall in :data:`GAP_BINS` bins of their pseudo-angle
    (:func:`_pseudo_angle`); each bin keeps its least and greatest (a bit mask says which bins hold
    any: no bin is cleared before). Between consecutive occupied bins the step of the pseudo-angle
    bounds the angle within a factor 2, so only the steps within a factor 2 of the largest are
    measured with ``atan2`` (as the difference of the two ends' angles).
    """
    bins, occupied, edges = scratch
    if screen > 0.0:
        bound, used = _gap_bound(i, queue, count, x, y, z, vecs, edges)
        if used < 2 or bound < screen:
            return bound
    mask, used = _binned_offsets(i, queue, count, x, y, z, vecs, bins)
    one = np.uint64(1)
    if used < 2:
        return 2.0 * math.pi
    # the occupied bins in order, without a branch per bin
    m = 0
    for b in range(GAP_BINS):
        occupied[m] = b
        m += int((mask >> np.uint64(b)) & one)
    # the largest step of the key between consecutive occupied bins (the last to the first round the circle)
    first, last = occupied[0], occupied[m - 1]
    largest = bins[0, first] + 4.0 - bins[3, last]
    for k in range(1, m):
        largest = max(largest, bins[0, occupied[k]] - bins[3, occupied[k - 1]])
    # every step whose angle may beat the largest step's angle (at least its key step)
    bound = 0.5 * largest * (1.0 - 1e-9)
    widest = 0.0
    for k in range(1, m):
        a, b = occupied[k - 1], occupied[k]
        if bins[0, b] - bins[3, a] >= bound:
            step = math.atan2(bins[2, b], bins[1, b]) - math.atan2(bins[5, a], bins[4, a])
            widest = max(widest, step)
    if bins[0, first] + 4.0 - bins[3, last] >= bound:
        step = math.atan2(bins[2, first], bins[1, first]) + 2.0 * math.pi - math.atan2(bins[5, last], bins[4, last])
        widest = max(widest, step)
    return widest


@jit
def _frame(i, sub, count, x, y, z, cov, vecs, scratch, screen):
    """PCA normal (``vecs[:3, 0]``) and widest gap of the support ``sub[:count]`` (exact from
    ``screen`` on, :func:`_widest_gap`); the gap, or -1 when the support is too small (fewer than 3
    points) for a plane."""
    if count < 3:
        return -1.0
    offset_moments(i, sub, count, x, y, z, True, cov)
    sym3_eigen_closed(cov, vecs)
    return _widest_gap(i, sub, count, x, y, z, vecs, scratch, screen)


@jit
def _spread(i, sub, count, x, y, z, cov, vecs):
    """How far from a curve the support ``sub[:count]`` of point i is (:func:`support_spread`).

    The offsets from i are taken along their first and second principal directions (u, v, the
    second moments about i); v is regressed on 1, u and u², and the spread is the square root of
    the variance of v that this leaves (per spare equation), over the variance of u. A scan row that bends with the
    surface lies in a plane: its v is the row's sagitta, a quadratic function of u, so its spread
    is about 0 where the plain ratio of eigenvalues read the sagitta as width. Across a surface
    patch v does not depend on u and the spread stays the square root of the eigenvalues' ratio.
    """
    offset_moments(i, sub, count, x, y, z, False, cov)
    sym3_eigen_closed(cov, vecs)
    if not vecs[3, 2] > 0.0:
        return 0.0
    scale = 1.0 / math.sqrt(vecs[3, 2])  # u in units of its RMS: the sums below stay of order 1
    s0 = s1 = s2 = s3 = s4 = t0 = t1 = t2 = vv = 0.0
    for j in range(count):
        q = sub[j]
        dx, dy, dz = x[q] - x[i], y[q] - y[i], z[q] - z[i]
        u = (dx * vecs[0, 2] + dy * vecs[1, 2] + dz * vecs[2, 2]) * scale
        v = (dx * vecs[0, 1] + dy * vecs[1, 1] + dz * vecs[2, 1]) * scale
        uu = u * u
        s0 += 1.0
        s1 += u
        s2 += uu
        s3 += uu * u
        s4 += uu * uu
        t0 += v
        t1 += u * v
        t2 += uu * v
        vv += v * v
    # the 3 x 3 normal equations of v ~ c0 + c1 u + c2 u^2, by Cramer's rule
    det = s0 * (s2 * s4 - s3 * s3) - s1 * (s1 * s4 - s3 * s2) + s2 * (s1 * s3 - s2 * s2)
    if count <= 3 or not abs(det) > 1e-12 * s0 * s2 * s4:
        return 0.0  # three points or fewer distinct u: any v is a quadratic function of them
    c0 = (t0 * (s2 * s4 - s3 * s3) - s1 * (t1 * s4 - s3 * t2) + s2 * (t1 * s3 - s2 * t2)) / det
    c1 = (s0 * (t1 * s4 - t2 * s3) - t0 * (s1 * s4 - s3 * s2) + s2 * (s1 * t2 - t1 * s2)) / det
    c2 = (s0 * (s2 * t2 - s3 * t1) - s1 * (s1 * t2 - t1 * s2) + t0 * (s1 * s3 - s2 * s2)) / det
    left = vv - (c0 * t0 + c1 * t1 + c2 * t2)
    # per spare equation: a small patch's v loses 3 of its s0 degrees of freedom to the regression
    return math.sqrt(max(left, 0.0) * s0 / ((s0 - 3.0) * s2))
