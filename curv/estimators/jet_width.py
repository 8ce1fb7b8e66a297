"""The jet's adaptive width (``curv.estimate(..., width="adaptive")``): a per-point choice of ball
and degree by the intersection of confidence intervals.

A wide ball averages noise away but carries the surface's higher-order terms as bias; a narrow one
has little bias and much noise. Which is better changes from point to point: on a sine patch a
degree-4 jet over 13 spacings is excellent where the curvature is large and biased where it is
small. The rule here is Lepskii's in the form of Goldenshluger & Nemirovski (1997) and Katkovnik
(1999), "intersection of confidence intervals" (ICI), with the relative stop of Lerga, Vrankic &
Sucic (2008; "relative ICI", RICI):

1. **Candidates**, in order of falling variance: the degree-``degree`` jet (the chosen ``weights``)
   over balls of :data:`WIDTH_FRACTIONS` of the given radius, then the degree-2 jet with smooth
   weights over the whole ball (:data:`LAST_DEGREE`, :data:`LAST_WEIGHTS`), the steadiest fit.
2. **Intervals.** Each candidate j gives ``k_j ± GAMMA * se_j`` for k1 and for k2 (the fit's
   standard errors, :func:`curv.estimators.jet.jet_se`). A candidate takes part at a point only
   where its ball holds at least :data:`POINTS_PER_UNKNOWN` times the fit's unknowns: with fewer
   residuals the fit's own standard error is itself unreliable, and one too-narrow interval in a
   wrong place would stop the walk there.
3. **Walk**, for k1 and for k2 separately (a bias in one need not stop the other): a point keeps
   going from candidate to candidate while the running intersection of the intervals, the new one
   included, is at least :data:`RATIO` of the new interval's own width. Plain ICI (``RATIO = 0``)
   goes on while the intersection is not empty, so it needs a narrow interval to stop in time and
   then stops on noise; the relative stop takes wide intervals (few stops on noise) and still
   stops where a fit's interval has moved off towards its bias. A candidate with no fit at a point
   (too few neighbours in a small ball, singular) is skipped there.
4. **Estimate.** k1 (k2) is the inverse-variance mean (weights ``1 / se_j**2``) of the candidates
   its walk kept: an average of fits that agree, leaning on the steadiest. Where the two means would
   order k1 below k2 (near umbilics) the k1 walk's last candidate's own k1, k2 stay.

The directions and k1's standard error are those of the k1 walk's last candidate, k2's standard
error that of the k2 walk's (the mean also takes in the narrower, noisier fits: on a noisy sphere
at 4 spacings its spread is 1.15x that of the last candidate, whose standard error it reports, so
the reported one runs a little low there); a point with no fit at all keeps the reason of the widest degree-``degree`` fit.
Every candidate's support lies within the given ball, so the validity rules (borders) read the
given radius as for the fixed width. The cost is one jet per candidate (:data:`WIDTH_FRACTIONS`
and the last fit: 7 fits, the narrower ones cheaper; 4.2-4.5x the fixed degree-4 jet's CPU time
on a 3136-point cloud at 13 spacings). Measured and tuned in docs/ACCURACY.md ("Adaptive width").
"""

from __future__ import annotations

import numpy as np

from ..core.jit import rescaled
from ..core.mesh import Mesh
from ..geometry.neighbourhood import all_centres, support_sizes
from ..core.validity import OK

__all__ = ["WIDTHS", "DEFAULT_WIDTH", "WIDTH_FRACTIONS", "GAMMA", "RATIO", "POINTS_PER_UNKNOWN", "LAST_DEGREE",
           "LAST_WEIGHTS", "iter_adaptive_jet", "ici_walk", "adaptive_choice"]

WIDTHS = ("fixed", "adaptive")
"""The jet's width rules (``curv.estimate(..., width=...)``): ``"fixed"`` fits over the given ball;
``"adaptive"`` chooses per point among narrower balls and a steadier fit (this module)."""

DEFAULT_WIDTH = "fixed"

WIDTH_FRACTIONS = (0.5, 8 / 13, 9 / 13, 10 / 13, 11.5 / 13, 1.0)
"""Radii of the degree-``degree`` candidates as fractions of the given ball radius (tried on the
point-cloud protocol at 13 spacings: 6.5, 8, 9, 10, 11.5 and 13 spacings; a 5-spacing candidate
added noise, docs/ACCURACY.md)."""

GAMMA = 5.0
"""Half-width of the confidence intervals in standard errors. With :data:`RATIO` it was tuned on the
noisy point clouds of docs/ACCURACY.md (surfaces 0-2, checked on 3-5): a wider interval wants a
higher ratio (4 and 0.7, 5 and 0.75-0.85, 6 and 0.8-0.9 about the same); 5 and 0.8 in the middle."""

RATIO = 0.8
"""The relative stop: a walk goes on while the intersection keeps at least this share of the new
candidate's interval width (0 is plain ICI: go on while the intersection is not empty)."""

LAST_DEGREE = 2
LAST_WEIGHTS = "smooth"
"""The last, steadiest candidate: the degree-2 jet with smooth weights over the whole ball."""

POINTS_PER_UNKNOWN = 5.0
"""A candidate takes part only where its ball holds at least this many points per unknown of its fit
(75 for degree 4, the centre included). With 2 (30 points) a noisy sphere at 4 spacings let the
narrowest degree-4 fits in, whose values and standard errors are both erratic there: a walk that
stopped among them kept an outlier (k1 off the last candidate's by up to 2.6 where its spread is
0.1); with 5 no point is off it by more than 0.12. The point clouds of docs/ACCURACY.md (at least
119 points in the narrowest ball) do not reach the limit."""



def ici_walk(k: np.ndarray, se: np.ndarray, gamma: float = GAMMA,
             ratio: float = RATIO) -> tuple[np.ndarray, np.ndarray]:
    """One quantity's walk over the candidates: the relative intersection of confidence intervals.

    Parameters
    ----------
    k : (m, n) float64
        The m candidates' estimates of one quantity (k1 or k2) in order of falling variance; NaN
        where a candidate has no fit.
    se : (m, n) float64
        Their standard errors (NaN: the candidate sits out at that point).
    gamma : float
        Interval half-width in standard errors.
    ratio : float
        The walk takes candidate j while the running intersection, j's interval included, is at
        least ``ratio`` times j's interval width ``2 * gamma * se[j]``; it stops at the first
        fitted candidate that fails. 0 is plain ICI (the intersection is not empty).

    Returns
    -------
    choice : (n,) int64
        The last candidate the walk kept; -1 where no candidate has a fit.
    mean : (n,) float64
        Inverse-variance mean (weights ``se**-2``) of the kept candidates' values (NaN where
        ``choice`` is -1).
    """
    m, n = k.shape
    lo = np.full(n, -np.inf)
    hi = np.full(n, np.inf)
    going = np.ones(n, bool)
    choice = np.full(n, -1, np.int64)
    weight = np.zeros(n)
    total = np.zeros(n)
    for j in range(m):  # over the few candidates; every point at once
        fitted = np.isfinite(k[j]) & np.isfinite(se[j])
        step = going & fitted
        kj = np.where(fitted, k[j], 0.0)
        sj = np.where(fitted, se[j], 1.0)
        nlo = np.maximum(lo, kj - gamma * sj)
        nhi = np.minimum(hi, kj + gamma * sj)
        keeps = step & (nhi - nlo >= ratio * 2.0 * gamma * sj)
        going &= ~step | keeps  # a fitted candidate that fails ends the walk
        lo = np.where(keeps, nlo, lo)
        hi = np.where(keeps, nhi, hi)
        choice[keeps] = j
        w = np.where(keeps, 1.0 / np.maximum(sj * sj, np.finfo(float).tiny), 0.0)
        weight += w
        total += w * kj
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = total / weight
    mean[choice < 0] = np.nan
    return choice, mean


def adaptive_choice(k1: np.ndarray, k2: np.ndarray, se1: np.ndarray, se2: np.ndarray, gamma: float = GAMMA,
                    ratio: float = RATIO) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The two walks and the estimate from the candidates' values (steps 3 and 4 of the module notes).

    Parameters
    ----------
    k1, k2, se1, se2 : (m, n) float64
        The candidates' curvatures and standard errors in order of falling variance; NaN where a
        candidate has no fit or sits out (a candidate with any of the four NaN sits out of both walks).
    gamma, ratio : float
        As in :func:`ici_walk`.

    Returns
    -------
    choice1, choice2 : (n,) int64
        The last candidate each walk kept (-1: none fitted).
    est1, est2 : (n,) float64
        The estimate: the walks' means, or the k1 walk's last candidate's own k1, k2 where the
        means would order k1 below k2; NaN where no candidate has a fit.
    """
    out_of_walk = ~(np.isfinite(k1) & np.isfinite(k2) & np.isfinite(se1) & np.isfinite(se2))
    se1 = np.where(out_of_walk, np.nan, se1)
    se2 = np.where(out_of_walk, np.nan, se2)
    choice1, mean1 = ici_walk(k1, se1, gamma, ratio)
    choice2, mean2 = ici_walk(k2, se2, gamma, ratio)
    rows = np.arange(k1.shape[1])
    own = np.maximum(choice1, 0)
    ordered = (choice1 >= 0) & (choice2 >= 0) & (mean1 >= mean2)
    est1 = np.where(ordered, mean1, k1[own, rows])
    est2 = np.where(ordered, mean2, k2[own, rows])
    est1[choice1 < 0] = np.nan
    est2[choice1 < 0] = np.nan
    return choice1, choice2, est1, est2


def iter_adaptive_jet(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None, degree: int,
                      weights: str, centres: np.ndarray | None, features):
    """The jet with the adaptive width, a generator (parameters as :func:`curv.estimators.jet.iter_jet`).

    Yields
    ------
    float
        Fraction done.

    Returns
    -------
    Principal
        Per point, k1 and k2 the means of the two walks (:func:`ici_walk`), the directions, k1's
        standard error and the reason of the k1 walk's last candidate, k2's standard error of the k2
        walk's.
    """
    from .jet import iter_jet, unknowns  # the jet imports this module for its option

    radii = np.asarray(radii, dtype=np.float64)
    fits = [(f, degree, weights) for f in WIDTH_FRACTIONS] + [(1.0, LAST_DEGREE, LAST_WEIGHTS)]
    where = all_centres(mesh.n_vertices, centres)
    results, few = [], []
    for j, (fraction, deg, wts) in enumerate(fits):
        gen = iter_jet(mesh, normals, radii * fraction, chunk=chunk, degree=deg, weights=wts, centres=centres,
                       features=features, width="fixed")
        results.append((yield from rescaled(gen, j / len(fits), (j + 1) / len(fits))))
        # too few residuals for a trustworthy standard error: the candidate sits out at that point
        counts, _ = support_sizes(mesh, radii * fraction, where)
        few.append(where[counts + 1 < POINTS_PER_UNKNOWN * unknowns(deg)])
    k1, k2 = np.stack([r.k1 for r in results]), np.stack([r.k2 for r in results])
    se1, se2 = np.stack([r.k1_se for r in results]), np.stack([r.k2_se for r in results])
    for j, rows in enumerate(few):
        se1[j, rows] = np.nan
    choice1, choice2, est1, est2 = adaptive_choice(k1, k2, se1, se2)
    widest = len(WIDTH_FRACTIONS) - 1
    out = results[widest]  # its arrays take the chosen rows; unfitted points keep its reason
    for j, res in enumerate(results):
        rows = np.flatnonzero(choice1 == j)
        if j != widest:
            for name in ("k1", "k2", "k1_se", "d1", "d2"):
                getattr(out, name)[rows] = getattr(res, name)[rows]
        out.reason[rows] = OK
    rows = np.flatnonzero(choice2 >= 0)
    out.k2_se[rows] = se2[choice2[rows], rows]
    out.k1[:] = np.where(choice1 >= 0, est1, out.k1)
    out.k2[:] = np.where(choice1 >= 0, est2, out.k2)
    return out
