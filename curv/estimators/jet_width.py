"""The jet's adaptive width (``curv.estimate(..., width="adaptive")``): a per-point choice of ball
and degree by the intersection of confidence intervals.

A wide ball averages noise away but carries the surface's higher-order terms as bias; a narrow one
has little bias and much noise. Which is better changes from point to point: on a sine patch a
degree-4 jet over 13 spacings is excellent where the curvature is large and biased where it is
small. The rule here is Lepskii's in the form of Goldenshluger & Nemirovski (1997) and Katkovnik
(1999), "intersection of confidence intervals" (ICI):

1. **Candidates**, in order of falling variance: the degree-``degree`` jet (the chosen ``weights``)
   over balls of :data:`WIDTH_FRACTIONS` of the given radius, then the degree-2 jet with smooth
   weights over the whole ball (:data:`LAST_DEGREE`, :data:`LAST_WEIGHTS`), the steadiest fit.
2. **Intervals.** Each candidate j gives ``k_i ± GAMMA * se_i`` for k1 and k2 (the fit's standard
   errors, :func:`curv.estimators.jet.jet_se`). A candidate takes part at a point only where its
   ball holds at least :data:`POINTS_PER_UNKNOWN` times the fit's unknowns: with fewer residuals
   the fit's own standard error is itself unreliable, and one too-narrow interval in a wrong place
   would stop the walk there.
3. **Choice.** Walking the candidates in order, a point keeps the last one whose intervals still
   share a point with those of every candidate before it (the running intersection is not empty
   for k1 and for k2). While the bias is below the noise the intervals overlap and the walk goes on
   to a steadier fit; once a fit's bias shows, its interval leaves the intersection and the walk
   stops. A candidate with no fit at a point (too few neighbours in a small ball, singular) is
   skipped there; a point with no fit at all keeps the reason of the widest degree-``degree`` fit.
4. **Estimate.** k1 and k2 are the midpoints of the final intersections (the intervals' common
   part, an average of the candidates the walk kept; it lowered the trimmed RMS on the noisy
   point clouds by 6-10 % against the chosen candidate's own value at 2 standard errors); where the midpoints would
   order k1 below k2 (near umbilics) the chosen candidate's own k1, k2 stay.

The directions, standard errors and reasons are those of the chosen candidate;
every candidate's support lies within the given ball, so the validity rules (borders) read the
given radius as for the fixed width. The cost is one jet per candidate (:data:`WIDTH_FRACTIONS`
and the last fit: 7 fits, the narrower ones cheaper; 4.2x the fixed degree-4 jet's CPU time on a
3169-point cloud at 13 spacings). Measured in docs/ACCURACY.md ("Adaptive width").
"""

from __future__ import annotations

import numpy as np

from ..core.mesh import Mesh
from ..geometry.neighbourhood import all_centres, support_sizes
from ..core.validity import Reason

__all__ = ["WIDTHS", "DEFAULT_WIDTH", "WIDTH_FRACTIONS", "GAMMA", "POINTS_PER_UNKNOWN", "LAST_DEGREE", "LAST_WEIGHTS",
           "iter_adaptive_jet", "ici_choice"]

WIDTHS = ("fixed", "adaptive")
"""The jet's width rules (``curv.estimate(..., width=...)``): ``"fixed"`` fits over the given ball;
``"adaptive"`` chooses per point among narrower balls and a steadier fit (this module)."""

DEFAULT_WIDTH = "fixed"

WIDTH_FRACTIONS = (0.5, 8 / 13, 9 / 13, 10 / 13, 11.5 / 13, 1.0)
"""Radii of the degree-``degree`` candidates as fractions of the given ball radius (tried on the
point-cloud protocol at 13 spacings: 6.5, 8, 9, 10, 11.5 and 13 spacings; a 5-spacing candidate
added noise, docs/ACCURACY.md)."""

GAMMA = 2.5
"""Half-width of the confidence intervals in standard errors (1.5-3 tried on the noisy point clouds
of docs/ACCURACY.md; 2.5 best with the midpoint estimate)."""

LAST_DEGREE = 2
LAST_WEIGHTS = "smooth"
"""The last, steadiest candidate: the degree-2 jet with smooth weights over the whole ball."""

POINTS_PER_UNKNOWN = 2.0
"""A candidate takes part only where its ball holds at least this many points per unknown of its fit
(30 for degree 4, the centre included)."""

_OK = int(Reason.OK)


def ici_choice(k1: np.ndarray, k2: np.ndarray, se1: np.ndarray, se2: np.ndarray,
               gamma: float = GAMMA) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Index of the chosen candidate per point by the intersection of confidence intervals.

    Parameters
    ----------
    k1, k2 : (m, n) float64
        The m candidates' curvatures in order of falling variance; NaN where a candidate has no fit.
    se1, se2 : (m, n) float64
        Their standard errors.
    gamma : float
        Interval half-width in standard errors.

    Returns
    -------
    choice : (n,) int64
        The last candidate (in order) whose intervals meet those of every earlier fitted candidate;
        -1 where no candidate has a fit.
    mid1, mid2 : (n,) float64
        Midpoints of the final intersections of the k1 and the k2 intervals (NaN where ``choice`` is -1).
    """
    m, n = k1.shape
    lo1 = np.full(n, -np.inf)
    hi1 = np.full(n, np.inf)
    lo2 = lo1.copy()
    hi2 = hi1.copy()
    going = np.ones(n, bool)
    choice = np.full(n, -1, np.int64)
    for j in range(m):  # over the few candidates; every point at once
        fitted = np.isfinite(k1[j]) & np.isfinite(k2[j]) & np.isfinite(se1[j]) & np.isfinite(se2[j])
        step = going & fitted
        nlo1 = np.maximum(lo1, k1[j] - gamma * se1[j])
        nhi1 = np.minimum(hi1, k1[j] + gamma * se1[j])
        nlo2 = np.maximum(lo2, k2[j] - gamma * se2[j])
        nhi2 = np.minimum(hi2, k2[j] + gamma * se2[j])
        meets = step & (nlo1 <= nhi1) & (nlo2 <= nhi2)
        going &= ~step | meets  # a fitted candidate outside the intersection ends the walk
        lo1 = np.where(meets, nlo1, lo1)
        hi1 = np.where(meets, nhi1, hi1)
        lo2 = np.where(meets, nlo2, lo2)
        hi2 = np.where(meets, nhi2, hi2)
        choice[meets] = j
    with np.errstate(invalid="ignore"):
        mid1, mid2 = 0.5 * (lo1 + hi1), 0.5 * (lo2 + hi2)
    unset = choice < 0
    mid1[unset] = np.nan
    mid2[unset] = np.nan
    return choice, mid1, mid2


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
        Per point, the chosen candidate's k1, k2, directions, standard errors and reason.
    """
    from .jet import iter_jet, unknowns  # the jet imports this module for its option

    radii = np.asarray(radii, dtype=np.float64)
    fits = [(f, degree, weights) for f in WIDTH_FRACTIONS] + [(1.0, LAST_DEGREE, LAST_WEIGHTS)]
    where = all_centres(mesh.n_vertices, centres)
    results, few = [], []
    for j, (fraction, deg, wts) in enumerate(fits):
        gen = iter_jet(mesh, normals, radii * fraction, chunk=chunk, degree=deg, weights=wts, centres=centres,
                       features=features, width="fixed")
        while True:
            try:
                done = next(gen)
            except StopIteration as stop:
                results.append(stop.value)
                break
            yield (j + done) / len(fits)
        # too few residuals for a trustworthy standard error: the candidate sits out at that point
        counts, _ = support_sizes(mesh, radii * fraction, where)
        few.append(where[counts + 1 < POINTS_PER_UNKNOWN * unknowns(deg)])
    se1 = np.stack([r.k1_se for r in results])
    for j, rows in enumerate(few):
        se1[j, rows] = np.nan
    choice, mid1, mid2 = ici_choice(np.stack([r.k1 for r in results]), np.stack([r.k2 for r in results]), se1,
                        np.stack([r.k2_se for r in results]))
    widest = len(WIDTH_FRACTIONS) - 1
    out = results[widest]  # its arrays take the chosen rows; unfitted points keep its reason
    for j, res in enumerate(results):
        if j == widest:
            continue
        rows = np.flatnonzero(choice == j)
        for name in ("k1", "k2", "k1_se", "k2_se", "d1", "d2"):
            getattr(out, name)[rows] = getattr(res, name)[rows]
        out.reason[rows] = _OK
    rows = np.flatnonzero((choice >= 0) & (mid1 >= mid2))
    out.k1[rows] = mid1[rows]
    out.k2[rows] = mid2[rows]
    return out
