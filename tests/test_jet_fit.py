"""The jet fit's steps (curv.estimators._jet_fit): the degree-2 normal equations added in scalars
are the general loop's sums to the bit, and the ``SINGULAR`` verdict settled by the determinant
bound is the condition estimate's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from curv.core.small_linalg import cholesky_scaled, cholesky_solve_scaled, reciprocal_condition, scaled_norm_bound
from curv.estimators._jet_fit import MAX_UNKNOWNS, RCOND, V_SIGNS, _normal_equations, _solve, smooth_weight


def _loop_sums(points, p, queue, frame, scale):
    """The normal equations of degree 2 as the general loop adds them, one float at a time."""
    x, y, z = points
    r2, inv_h = scale
    m = np.zeros((6, 6))
    b = np.zeros(6)
    ww = 0.0
    for q in queue:
        dx, dy, dz = x[q] - x[p], y[q] - y[p], z[q] - z[p]
        wt = smooth_weight(dx * dx + dy * dy + dz * dz, r2)
        dx, dy, dz = dx * inv_h, dy * inv_h, dz * inv_h
        u = dx * frame[0, 0] + dy * frame[0, 1] + dz * frame[0, 2]
        v = dx * frame[1, 0] + dy * frame[1, 1] + dz * frame[1, 2]
        w = dx * frame[2, 0] + dy * frame[2, 1] + dz * frame[2, 2]
        mono = [1.0, 1.0 * u, 1.0 * v]
        mono += [mono[1] * u, mono[2] * u, mono[2] * v]
        ww += wt * w * w
        for a in range(6):
            ma = wt * mono[a]
            b[a] += ma * w
            for c in range(a, 6):
                m[a, c] += ma * mono[c]
    return m, b, ww


@pytest.mark.parametrize("smooth", [False, True])
def test_the_degree_two_normal_equations_are_the_loops_sums(smooth):
    rng = np.random.default_rng(5)
    pts = rng.normal(size=(40, 3)) * [1.0, 1.0, 0.1] + [3e5, -2e5, 10.0]
    points = tuple(np.ascontiguousarray(pts[:, k]) for k in range(3))
    frame, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    frame = np.ascontiguousarray(frame.T)
    queue = rng.permutation(40)[:27].astype(np.int64)
    p = int(queue[0])
    h = math.sqrt(max(float(np.sum((pts[q] - pts[p]) ** 2)) for q in queue))
    scale = ((1.1 * h) ** 2 if smooth else 0.0, 1.0 / h)
    m = np.full((MAX_UNKNOWNS + 1, MAX_UNKNOWNS), np.nan)
    vec = np.full((3, MAX_UNKNOWNS), np.nan)
    ww = _normal_equations((p, queue.size, queue), points, frame, scale, 2, (m, vec))
    m_ref, b_ref, ww_ref = _loop_sums(points, p, queue, frame, scale)
    assert ww == ww_ref
    assert np.array_equal(vec[0, :6], b_ref)
    upper = np.triu_indices(6)
    assert np.array_equal(m[:6, :6][upper], m_ref[upper])


def _system(rng, size, smallest):
    """A symmetric positive definite matrix in a jet fit's layout with the scaled smallest
    eigenvalue near ``smallest``, its right-hand side in ``vec[0]``."""
    q, _ = np.linalg.qr(rng.normal(size=(size, size)))
    a = q @ np.diag(np.r_[smallest, 10.0 ** rng.uniform(-3, 0, size - 1)]) @ q.T
    a *= np.outer(s := 10.0 ** rng.uniform(-3, 3, size), s)
    m = np.zeros((MAX_UNKNOWNS + 1, MAX_UNKNOWNS))
    m[:size, :size] = np.triu(a)
    vec = np.zeros((3, MAX_UNKNOWNS))
    vec[0, :size] = rng.normal(size=size)
    return m, vec


def test_the_singular_verdict_is_the_condition_estimates():
    """On systems from far-from-singular to singular (the threshold inside the range, where the
    bound cannot settle and the estimate decides), the verdict and the solution are those of the
    two-start estimate."""
    rng = np.random.default_rng(8)
    verdicts = set()
    for k in range(600):
        m, vec = _system(rng, 6, 10.0 ** rng.uniform(-17, -1))
        ref_m, ref_vec = m.copy(), vec.copy()
        lam = scaled_norm_bound(ref_m, 6, MAX_UNKNOWNS)
        factored = cholesky_scaled(ref_m, 6, MAX_UNKNOWNS)
        if factored:
            cholesky_solve_scaled(ref_m, MAX_UNKNOWNS, 6, ref_vec)
        expected = factored and reciprocal_condition(ref_m, 6, lam, ref_vec, 2, V_SIGNS) >= RCOND
        got = _solve(m, vec, 6)
        assert got == expected, k
        verdicts.add(bool(got))
        if factored:
            assert np.array_equal(m[:6, :6], ref_m[:6, :6]) and np.array_equal(vec[1, :6], ref_vec[1, :6])
    assert verdicts == {True, False}
