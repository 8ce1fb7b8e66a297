"""The smooth twin's fits: weighted polynomial heights over many patches at once, insignificant terms dropped.

Every patch is fitted at the highest degree up to :data:`MAX_DEGREE` its points allow, in the basis
the weighted monomials (ordered by total degree) become when made orthonormal (one Cholesky
factorisation of their Gram matrix per patch; batched QR is far slower). In that basis each
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


def _n_unknowns(degree: int) -> int:
    return (degree + 1) * (degree + 2) // 2


def _power_table(x: np.ndarray, degree: int) -> np.ndarray:
    """(..., degree + 1) float64 ``x**0 .. x**degree`` by repeated products (exact and cheap)."""
    out = np.empty(x.shape + (degree + 1,))
    out[..., 0] = 1.0
    for i in range(1, degree + 1):
        out[..., i] = out[..., i - 1] * x
    return out


def _monomials(s: np.ndarray, t: np.ndarray, powers: np.ndarray) -> np.ndarray:
    """(..., P) float64 the monomials ``s^i t^j`` of ``powers``."""
    top = int(powers.max()) if powers.size else 0
    return _power_table(s, top)[..., powers[:, 0]] * _power_table(t, top)[..., powers[:, 1]]


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
    """
    c = s.shape[0]
    powers = monomial_powers(max_degree)
    coef = np.zeros((c, powers.shape[0]))
    degree = np.full(c, -1, np.int64)
    residual = np.zeros_like(z)
    dof = np.full(c, np.nan)
    resolved = np.zeros(c, bool)
    lower = np.full(c, np.nan)
    wsum = w.sum(axis=1)
    n_eff = wsum**2 / np.maximum((w * w).sum(axis=1), 1e-300)
    allowed = np.full(c, -1, np.int64)
    for d in range(2, max_degree + 1):
        p = _n_unknowns(d)
        allowed[(n_eff >= points_per_unknown * p) & (count > p)] = d
    for d in sorted(set(allowed[allowed >= 2].tolist())):
        rows = np.flatnonzero(allowed == d)
        p = _n_unknowns(d)
        order = powers[:p].sum(axis=1)
        ww = w[rows]
        root = np.sqrt(ww)
        a = _monomials(s[rows], t[rows], powers[:p]) * root[..., None]  # (k, N, p)
        col = np.sqrt(np.maximum(np.sum(a * a, axis=1), 1e-300))  # column scaling: a better-conditioned Gram
        a /= col[:, None, :]
        chol = np.linalg.cholesky(np.swapaxes(a, 1, 2) @ a + 1e-12 * np.eye(p))  # Q = A L^-T: orthonormal
        q = np.swapaxes(np.linalg.solve(chol, np.swapaxes(a, 1, 2)), 1, 2)  # (k, N, p)
        qb = (np.swapaxes(q, 1, 2) @ (root * z[rows])[..., None])[..., 0]  # (k, p)
        fitted = (q @ qb[..., None])[..., 0]
        res = np.where(root > 0, (root * z[rows] - fitted) / np.where(root > 0, root, 1.0), 0.0)
        spread = np.sum(ww[..., None] * q * q, axis=1)  # (k, p): each coefficient's variance over sigma^2
        dof_k = wsum[rows] - spread.sum(axis=1)
        sigma2 = np.sum(ww * res * res, axis=1) / np.maximum(dof_k, 1e-300)
        strength = qb * qb / np.maximum(sigma2[:, None] * spread, 1e-300)
        keep = strength > threshold**2
        coef[rows, :p] = np.linalg.solve(np.swapaxes(chol, 1, 2), (qb * keep)[..., None])[..., 0] / col
        degree[rows] = np.maximum(np.max(np.where(keep, order[None, :], 0), axis=1), 2)
        residual[rows] = res
        dof[rows] = dof_k
        resolved[rows] = np.mean(strength[:, order == d], axis=1) < RESOLVED_RATIO
        if d >= 4:
            low = _n_unknowns(d - 2)
            rss_low = np.sum(ww * res * res, axis=1) + np.sum(qb[:, low:] ** 2, axis=1)
            lower[rows] = rss_low / np.maximum(wsum[rows] - spread[:, :low].sum(axis=1), 1e-300)
    return Fits(coef=coef, degree=degree, residual=residual, dof=dof, resolved=resolved, lower=lower)


def evaluate(fits: Fits, s: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(c, N) each patch's polynomial and its first derivatives ``g, g_s, g_t`` at ``(s, t)``."""
    powers = fits.powers
    i, j = powers[:, 0], powers[:, 1]
    top = int(powers.max())
    sp, tp = _power_table(s, top), _power_table(t, top)
    mono = sp[..., i] * tp[..., j]
    ds = sp[..., np.maximum(i - 1, 0)] * tp[..., j] * i
    dt = sp[..., i] * tp[..., np.maximum(j - 1, 0)] * j

    def apply(m):
        return (m @ fits.coef[..., None])[..., 0]

    return apply(mono), apply(ds), apply(dt)
