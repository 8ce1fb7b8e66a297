"""The smooth twin's fits: weighted polynomial heights over many patches at once, insignificant terms dropped.

Every patch is fitted at the highest degree up to :data:`MAX_DEGREE` its points allow, in the basis
the weighted monomials (ordered by total degree) become when made orthonormal (one Cholesky
factorisation of their Gram matrix per patch, one numba kernel step per patch). In that basis each
coefficient has its own standard error from the residual noise, and the terms whose coefficient
stays below :data:`SIGNIFICANCE` standard errors are dropped: what is left is the shape the patch's
points show above their noise (measured from the patch's base, :mod:`curv.advice.twin_base`: over a
sphere that fits a spherical patch every term may go, and the twin is that sphere). Noise-free points keep every term; noisy ones lose
the terms that would only fit the noise (wiggles at the candidates' own scale, against which every
candidate would be judged as if they were the surface's).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.jit import jit, jit_inlined, jit_parallel, launch, prange

__all__ = ["Fits", "fit_heights", "evaluate", "monomial_powers", "MAX_DEGREE", "SIGNIFICANCE", "RESOLVED_RATIO",
           "POINTS_PER_UNKNOWN"]

MAX_DEGREE = 6
"""Highest degree of a twin's polynomial (28 unknowns): two above the highest of the candidates (the
jet at degree 4), so no candidate's model holds a twin surface exactly."""

POINTS_PER_UNKNOWN = 3.0
"""A degree is fitted only where the patch's effective point count is at least this many per unknown."""

SIGNIFICANCE = 3.0
"""Standard errors a term must reach to stay in the twin."""

RESOLVED_RATIO = 4.0
"""A patch's residual is its noise where its fit's highest-degree terms average below this many
variances (squared coefficient over its variance; 1 for pure noise)."""


def monomial_powers(degree: int) -> np.ndarray:
    """(P, 2) int64 exponents ``(i, j)`` of ``s^i t^j`` with ``i + j <= degree``, by total degree
    (so the first ``(d + 1)(d + 2) / 2`` rows are the monomials of degree ``d``)."""
    return np.array([(d - j, j) for d in range(degree + 1) for j in range(d + 1)], np.int64)


@jit_inlined
def _n_unknowns(degree: int) -> int:
    return (degree + 1) * (degree + 2) // 2


@dataclass(frozen=True)
class Fits:
    """The fits of c patches (padded to N points each).

    Attributes
    ----------
    coef : (c, P) float64
        The kept terms' coefficients over :func:`monomial_powers` of the highest degree (zero where
        dropped or beyond the patch's fit).
    degree : (c,) int64
        Highest degree of a kept term, at least 2 (-1 where not even a quadric could be fitted).
    residual : (c, N) float64
        The full fit's residual heights (before any term is dropped).
    dof : (c,) float64
        The full fit's residual degrees of freedom, ``sum(w) - sum(w h)`` with the hat matrix's
        diagonal ``h``: the weighted squared residuals over it estimate the noise variance without
        bias (Gaussian noise of one variance).
    resolved : (c,) bool
        Whether the fit's highest-degree terms are at the noise (mean squared coefficient over its
        variance below :data:`RESOLVED_RATIO`): the residual then is noise. Where they are still far
        above it, the residual is the surface's own terms beyond the fit, and the noise is below it.
    lower : (c,) float64
        The residual variance (leverage-corrected, scaled units) of the fit two degrees lower (NaN
        where the fit's degree is below 4): with the full fit's, it tells the noise from the
        surface's own terms (:attr:`noise_share`).
    """

    coef: np.ndarray
    degree: np.ndarray
    residual: np.ndarray
    dof: np.ndarray
    resolved: np.ndarray
    lower: np.ndarray

    def noise_share(self, full: np.ndarray) -> np.ndarray:
        """(c,) the share of the full fit's residual variance ``full`` that is noise, by the residuals'
        fall over the last two degrees: ``(2 v_D - v_{D-2}) / v_D``, clipped to 0..1. Pure noise
        leaves ``v_{D-2} = v_D`` (share 1); the surface's own terms, falling at least twofold over two
        degrees, leave ``v_{D-2} >= 2 v_D`` (share 0); in between, the part that did not fall.
        Where the fit's degree is below 4 the residual is taken as noise (share 1)."""
        share = np.where(np.isfinite(self.lower), (2.0 * full - self.lower) / np.maximum(full, 1e-300), 1.0)
        return np.clip(share, 0.0, 1.0)

    @property
    def powers(self) -> np.ndarray:
        """(P, 2) the exponents of :attr:`coef`'s columns."""
        top = int(round((np.sqrt(8 * self.coef.shape[1] + 1) - 3) / 2))
        return monomial_powers(top)

    def at_origin(self, i: int, j: int) -> np.ndarray:
        """(c,) the derivative ``d^(i+j) g / ds^i dt^j`` at the origin."""
        powers = self.powers
        col = int(np.flatnonzero((powers[:, 0] == i) & (powers[:, 1] == j))[0])
        return self.coef[:, col] * float(np.prod(np.arange(1, i + 1)) * np.prod(np.arange(1, j + 1)))


@jit
def _fitted_degree(n, w, max_degree, points_per_unknown):
    """The highest degree ``n`` points of weights ``w`` (n,) allow (-1: not even a quadric), and the
    weights' sum."""
    wsum = 0.0
    w2sum = 0.0
    for i in range(n):
        wsum += w[i]
        w2sum += w[i] * w[i]
    n_eff = wsum * wsum / max(w2sum, 1e-300)
    degree = -1
    for d in range(2, max_degree + 1):
        if n_eff >= points_per_unknown * _n_unknowns(d) and n > _n_unknowns(d):
            degree = d
    return degree, wsum


@jit
def _scaled_monomials(n, s, t, w, degree, a, norm):
    """``a[:n, :p]`` the monomials ``s^i t^j`` (by total degree, powers by repeated products) times the roots of the weights, each column divided by its norm ``norm`` (p,)."""
    p = _n_unknowns(degree)
    for i in range(n):
        root = np.sqrt(w[i])
        k = 0
        for d in range(degree + 1):
            for j in range(d + 1):
                si = 1.0
                for _ in range(d - j):
                    si *= s[i]
                tj = 1.0
                for _ in range(j):
                    tj *= t[i]
                a[i, k] = si * tj * root
                norm[k] += a[i, k] * a[i, k]
                k += 1
    for k in range(p):  # column scaling: a better-conditioned Gram
        norm[k] = np.sqrt(max(norm[k], 1e-300))
    for i in range(n):
        for k in range(p):
            a[i, k] /= norm[k]


@jit
def _gram_cholesky(n, p, a, lower):
    """``lower`` (p, p): the Cholesky factor L of ``a[:n, :p]``'s Gram matrix + 1e-12 I; False where
    it is not positive definite."""
    for k in range(p):
        lower[k, k] = 1e-12
    for i in range(n):  # the Gram matrix's lower triangle first, row by row of a
        for k in range(p):
            for m in range(k + 1):
                lower[k, m] += a[i, k] * a[i, m]
    for k in range(p):
        for m in range(k + 1):
            acc = lower[k, m]
            for j in range(m):
                acc -= lower[k, j] * lower[m, j]
            if m < k:
                lower[k, m] = acc / lower[m, m]
            elif acc > 0.0:
                lower[k, k] = np.sqrt(acc)
            else:
                return False
    return True


@jit
def _fit_row(r, data, count, settings, out, scratch):
    """Fit patch ``r`` (see :func:`_fit_rows`): ``scratch`` = (a (N, P), q (P, N))."""
    s, t, z, w = data
    qb, spread, chol, col, residual, sums, allowed = out
    a, q = scratch
    n = count[r]
    degree, sums[r, 1] = _fitted_degree(n, w[r], settings[0], settings[1])
    p = _n_unknowns(degree)
    if degree < 2:
        return
    _scaled_monomials(n, s[r], t[r], w[r], degree, a, col[r])
    if not _gram_cholesky(n, p, a, chol[r]):
        return
    lower = chol[r]
    rz = np.empty(n)
    for i in range(n):
        rz[i] = np.sqrt(w[r, i]) * z[r, i]
    # Q = A L^-T (orthonormal columns), a column at a time (the inner loops run along the points)
    for k in range(p):
        for i in range(n):
            q[k, i] = a[i, k]
        for j in range(k):
            for i in range(n):
                q[k, i] -= lower[k, j] * q[j, i]
        for i in range(n):
            q[k, i] /= lower[k, k]
        for i in range(n):
            qb[r, k] += q[k, i] * rz[i]
            spread[r, k] += w[r, i] * q[k, i] * q[k, i]
    fitted = np.zeros(n)
    for k in range(p):
        for i in range(n):
            fitted[i] += q[k, i] * qb[r, k]
    rss = 0.0
    for i in range(n):
        root = np.sqrt(w[r, i])
        if root > 0.0:
            residual[r, i] = (rz[i] - fitted[i]) / root
            rss += w[r, i] * residual[r, i] * residual[r, i]
    sums[r, 0] = rss
    allowed[r] = degree


@jit_parallel
def _fit_rows(data, count, settings, out):
    """Every patch's full least-squares fit in the orthonormalised basis, one patch per step.

    ``data`` = (s, t, z, w), (c, N) each; ``count`` (c,); ``settings`` = (max_degree,
    points_per_unknown); ``out`` = (qb (c, P), spread (c, P), chol (c, P, P), col (c, P), residual
    (c, N), sums (c, 2): weighted residual sum of squares and weight sum, allowed (c,): the degree
    fitted, -1 where none). Every sum runs over the patch's own ``count`` points only, so a patch's fit
    does not depend on the padding or on the other patches."""
    width = data[0].shape[1]
    cols = out[0].shape[1]
    for r in prange(count.size):
        _fit_row(r, data, count, settings, out, (np.empty((width, cols)), np.empty((cols, width))))


def fit_heights(s, t, z, w, count, max_degree: int = MAX_DEGREE, *, threshold: float = SIGNIFICANCE,
                points_per_unknown: float = POINTS_PER_UNKNOWN) -> Fits:
    """Fit ``z = g(s, t)`` in every patch (see the module's docstring).

    Parameters
    ----------
    s, t, z, w : (c, N) float64
        Scaled tangent coordinates (about -1..1), heights and weights, padded with zero weight.
    count : (c,) int64
        Points per patch (the rest is padding).
    max_degree : int
    threshold : float
        Standard errors a term must reach to be kept (0: keep every term).
    points_per_unknown : float
        A degree is fitted where the patch's effective point count is at least this many per
        unknown (and its point count above the unknowns).

    Returns
    -------
    Fits
        Each patch's fit depends on its own points only (its row of ``s, t, z, w`` up to its count).
    """
    c = s.shape[0]
    powers = monomial_powers(max_degree)
    n_powers = powers.shape[0]
    qb, spread, col = (np.zeros((c, n_powers)) for _ in range(3))
    chol = np.zeros((c, n_powers, n_powers))
    residual = np.zeros(np.shape(z))
    sums = np.zeros((c, 2))
    allowed = np.full(c, -1, np.int64)
    data = tuple(np.ascontiguousarray(a, np.float64) for a in (s, t, z, w))
    launch(_fit_rows, data, np.ascontiguousarray(count, np.int64), (int(max_degree), float(points_per_unknown)),
           (qb, spread, chol, col, residual, sums, allowed))
    coef = np.zeros((c, n_powers))
    degree = np.full(c, -1, np.int64)
    dof = np.full(c, np.nan)
    resolved = np.zeros(c, bool)
    lower = np.full(c, np.nan)
    rss, wsum = sums[:, 0], sums[:, 1]
    for d in sorted(set(allowed[allowed >= 2].tolist())):
        rows = np.flatnonzero(allowed == d)
        p = _n_unknowns(d)
        order = powers[:p].sum(axis=1)
        qb_d, spread_d = qb[rows, :p], spread[rows, :p]
        dof_k = wsum[rows] - spread_d.sum(axis=1)
        sigma2 = rss[rows] / np.maximum(dof_k, 1e-300)
        strength = qb_d * qb_d / np.maximum(sigma2[:, None] * spread_d, 1e-300)
        keep = strength > threshold**2
        upper = np.swapaxes(chol[rows, :p, :p], 1, 2)
        coef[rows, :p] = np.linalg.solve(upper, (qb_d * keep)[..., None])[..., 0] / col[rows, :p]
        degree[rows] = np.maximum(np.max(np.where(keep, order[None, :], 0), axis=1), 2)
        dof[rows] = dof_k
        resolved[rows] = np.mean(strength[:, order == d], axis=1) < RESOLVED_RATIO
        if d >= 4:
            low = _n_unknowns(d - 2)
            rss_low = rss[rows] + np.sum(qb_d[:, low:] ** 2, axis=1)
            lower[rows] = rss_low / np.maximum(wsum[rows] - spread_d[:, :low].sum(axis=1), 1e-300)
    residual[degree < 2] = 0.0
    return Fits(coef=coef, degree=degree, residual=residual, dof=dof, resolved=resolved, lower=lower)


@jit
def _evaluate_row(r, st, count, coef, out):
    """Patch ``r``'s polynomial and slopes at its points (see :func:`evaluate`)."""
    s, t = st
    g, gs, gt = out
    n_powers = coef.shape[1]
    top = int(round((np.sqrt(8 * n_powers + 1) - 3) / 2))
    sp = np.empty(top + 1)
    tp = np.empty(top + 1)
    for i in range(count[r]):
        sp[0] = 1.0
        tp[0] = 1.0
        for e in range(1, top + 1):
            sp[e] = sp[e - 1] * s[r, i]
            tp[e] = tp[e - 1] * t[r, i]
        k = 0
        for d in range(top + 1):
            for j in range(d + 1):
                e = d - j
                g[r, i] += (sp[e] * tp[j]) * coef[r, k]
                gs[r, i] += (sp[max(e - 1, 0)] * tp[j] * e) * coef[r, k]
                gt[r, i] += (sp[e] * tp[max(j - 1, 0)] * j) * coef[r, k]
                k += 1


@jit_parallel
def _evaluate_rows(st, count, coef, out):
    for r in prange(count.size):
        _evaluate_row(r, st, count, coef, out)


def evaluate(fits: Fits, s: np.ndarray, t: np.ndarray, count: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(c, N) each patch's polynomial and its first derivatives ``g, g_s, g_t`` at ``(s, t)`` (c, N), at
    its first ``count`` (c,) points (zero in the padding)."""
    out = tuple(np.zeros(np.shape(s)) for _ in range(3))
    launch(_evaluate_rows, tuple(np.ascontiguousarray(a, np.float64) for a in (s, t)),
           np.ascontiguousarray(count, np.int64), np.ascontiguousarray(fits.coef), out)
    return out
