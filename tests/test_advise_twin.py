"""The smooth twin's batched fits against a straightforward per-patch least-squares fit, and the check's
report with either fit."""

import numpy as np
import pytest
from scipy.linalg import solve_triangular

import curv.advice.twin as twin_module
from curv.advice.check import iter_check
from curv.advice.twin import _row_wise
from curv.advice.twin_fit import (MAX_DEGREE, POINTS_PER_UNKNOWN, RESOLVED_RATIO, SIGNIFICANCE, Fits, evaluate,
                                  fit_heights, monomial_powers)
from curv.core.jit import run_to_end
from curv.study.protocol import Task
from curv.study.testmesh import build_test_mesh

FIELDS = [f.name for f in Fits.__dataclass_fields__.values()]


def _unknowns(d):
    return (d + 1) * (d + 2) // 2


def reference_fit(s, t, z, w, count, max_degree=MAX_DEGREE, *, threshold=SIGNIFICANCE,
                  points_per_unknown=POINTS_PER_UNKNOWN) -> Fits:
    """:func:`fit_heights` the plain way: one patch at a time, its weighted monomials' QR factorisation
    (Householder, numpy's) for the orthonormal basis, the kept terms' coefficients from R."""
    powers = monomial_powers(max_degree)
    c = s.shape[0]
    coef, residual = np.zeros((c, powers.shape[0])), np.zeros(np.shape(z))
    degree, dof, resolved, lower = np.full(c, -1), np.full(c, np.nan), np.zeros(c, bool), np.full(c, np.nan)
    for r in range(c):
        n = count[r]
        ws, zs = w[r, :n], z[r, :n]
        n_eff = ws.sum() ** 2 / np.sum(ws * ws)
        allowed = [d for d in range(2, max_degree + 1) if n_eff >= points_per_unknown * _unknowns(d) and n > _unknowns(d)]
        if not allowed:
            continue
        d, p = max(allowed), _unknowns(max(allowed))
        root = np.sqrt(ws)
        design = s[r, :n, None] ** powers[:p, 0] * t[r, :n, None] ** powers[:p, 1] * root[:, None]
        q, upper = np.linalg.qr(design)
        sign = np.sign(np.diag(upper))  # the basis of the Cholesky factor: R's diagonal positive
        q, upper = q * sign, upper * sign[:, None]
        qb = q.T @ (root * zs)
        residual[r, :n] = (root * zs - q @ qb) / root
        spread = np.sum(ws[:, None] * q * q, axis=0)
        dof[r] = ws.sum() - spread.sum()
        rss = np.sum(ws * residual[r, :n] ** 2)
        strength = qb * qb / (rss / dof[r] * spread)
        keep = strength > threshold**2
        coef[r, :p] = solve_triangular(upper, qb * keep)
        order = powers[:p].sum(axis=1)
        degree[r] = max(order[keep].max(initial=0), 2)
        resolved[r] = np.mean(strength[order == d]) < RESOLVED_RATIO
        if d >= 4:
            low = _unknowns(d - 2)
            lower[r] = (rss + np.sum(qb[low:] ** 2)) / (ws.sum() - spread[:low].sum())
    return Fits(coef=coef, degree=degree, residual=residual, dof=dof, resolved=resolved, lower=lower)


def reference_evaluate(fits, s, t, count):
    """:func:`evaluate` the plain way: every monomial and its derivatives at every point."""
    i, j = fits.powers[:, 0], fits.powers[:, 1]
    s, t = s[..., None], t[..., None]
    inside = (np.arange(s.shape[1]) < count[:, None])
    values = (s**i * t**j, i * s ** np.maximum(i - 1, 0) * t**j, j * s**i * t ** np.maximum(j - 1, 0))
    return tuple(np.where(inside, np.einsum("cnp,cp->cn", v, fits.coef), 0.0) for v in values)


def _patches(seed=0, c=40, width=300, noise=0.01):
    """Random padded patches of a smooth surface (s, t, z, w (c, width), counts (c,)): counts from too
    few for a quadric to the full width, so every degree is fitted somewhere."""
    rng = np.random.default_rng(seed)
    count = rng.integers(5, width + 1, c)
    count[0] = width
    s, t = rng.uniform(-1, 1, (2, c, width))
    z = 0.4 * s**2 - 0.3 * s * t + 0.2 * t**3 + 0.1 * s**2 * t**2 + 0.05 * s**5 + rng.normal(scale=noise, size=s.shape)
    w = np.exp(-0.5 * (s * s + t * t) / 0.35**2)
    inside = np.arange(width)[None, :] < count[:, None]
    return tuple(np.where(inside, a, 0.0) for a in (s, t, z, w)) + (count,)


@pytest.mark.parametrize("threshold", [SIGNIFICANCE, 0.0])
@pytest.mark.parametrize("noise", [0.01, 1e-6])
def test_the_batched_fits_equal_a_per_patch_least_squares_fit(threshold, noise):
    s, t, z, w, count = _patches(noise=noise)
    got = fit_heights(s, t, z, w, count, threshold=threshold)
    want = reference_fit(s, t, z, w, count, threshold=threshold)
    assert {-1, 2} <= set(want.degree.tolist()) and want.degree.max() >= 5 and np.isfinite(want.lower).sum() > 10
    np.testing.assert_array_equal(got.degree, want.degree)
    np.testing.assert_array_equal(got.resolved, want.resolved)
    scale = np.abs(want.coef).max(axis=1, keepdims=True)
    np.testing.assert_allclose(got.coef, want.coef, rtol=0, atol=1e-9 * scale.max())
    np.testing.assert_allclose(got.residual, want.residual, rtol=0, atol=1e-9 * np.abs(z).max())  # normal equations: cond^2
    np.testing.assert_allclose(got.dof, want.dof, rtol=1e-10)
    np.testing.assert_allclose(got.lower, want.lower, rtol=1e-8)
    height = evaluate(got, s, t, count)
    for a, b in zip(height, reference_evaluate(got, s, t, count)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)


def test_a_patchs_fit_depends_on_its_own_points_only():
    """Padded wider, in another batch or another order, a patch's fit is the same bit for bit: what lets
    the twin keep each patch's fit from its own base's batch instead of fitting the mixture again."""
    s, t, z, w, count = _patches(seed=1)
    one = fit_heights(s, t, z, w, count)
    other = _patches(seed=2)
    chosen = np.random.default_rng(3).random(count.size) < 0.5
    wide = [np.pad(a, ((0, 0), (0, 57))) for a in other[:4]]
    mixed = fit_heights(*(_row_wise(chosen, a, b) for a, b in zip(wide + [other[4]], (s, t, z, w, count))))
    two = fit_heights(*wide, other[4])
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(mixed, name),
                                      _row_wise(chosen, getattr(two, name), getattr(one, name)))
    backwards = fit_heights(*(a[::-1] for a in (s, t, z, w, count)))
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(backwards, name)[::-1], getattr(one, name))


def test_the_checks_report_is_the_straightforward_fits(monkeypatch):
    """The check on a study mesh with the batched fits and with the per-patch reference: the same noise,
    degrees and measured errors (to rounding)."""
    tm = build_test_mesh(Task(19002, "trigonometric", 3169, 10.0, 0.5, 0))
    calls = {"mru": {"method": "mru", "range": 2}, "qs": {"method": "qs", "range": 3},
             "jet": {"method": "jet", "range": 4, "degree": 4}}

    def check():
        return run_to_end(iter_check(tm.mesh, calls, np.flatnonzero(tm.evaluated), copies=2, centres=24))

    got = check()
    monkeypatch.setattr(twin_module, "fit_heights", reference_fit)
    monkeypatch.setattr(twin_module, "evaluate", reference_evaluate)
    want = check()
    assert got.degrees == want.degrees and got.noise_resolved == want.noise_resolved
    assert got.noise == pytest.approx(want.noise, rel=1e-9)
    for key, m in want.measured.items():
        np.testing.assert_allclose(got.measured[key].copies, m.copies, rtol=1e-7)
        assert got.measured[key].measured == m.measured
