"""The normals of a point cloud and its border: :func:`point_normals`, :func:`border_points` (module notes).

The radii of the border test (:func:`border_radii`), the cloud's frames at :data:`BORDER_RANGE`
kept with it (:func:`_frames`), and the driver that runs one pass, orients and refines.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import EstimatorError
from ..core.jit import announce, jit_parallel, launch, prange, run_to_end, slice_bounds
from ..core.pointcloud import PointCloud
from ..core.ranges import TIE_TOLERANCE, ball_radii, point_spacing, resolve
from ..estimators import get_spec
from ..estimators._handover import Kept, keep_for
from ..estimators.jet import JET_FITS
from ..geometry.neighbourhood import cached_with_mesh, latest_with_mesh
from .one_pass import _one_pass, _Pass, owe_spreads
from .orientation import default_orientation, orient_normals
from .quantised import support_floor

__all__ = ["PointNormals", "point_normals", "border_points", "border_radii", "border_test_radii", "NORMAL_RANGE", "BORDER_RANGE",
           "BORDER_GAP", "ONE_SIDED_GAP", "EXACT_GAP", "NORMAL_METHODS"]

NORMAL_RANGE = 2
"""Range Rk of the normals' fit unless told otherwise (~20-25 points)."""

BORDER_RANGE = 3
"""Range Rk of the border test and of the PCA that orients the jet normals (~50 points). At R2
(~23 points) a uniform random sample of a closed sphere had 1.2 % of its points over
:data:`BORDER_GAP`; at R3 0.02 % (20,000 points), and 0.1 % of a disc's interior points. The unit
is the larger of the point's spacing and its neighbours' (:func:`border_radii`): 62 of 200,000
uniform random points of a sphere read as borders with the point's own, 10 with this."""

BORDER_GAP = 0.75 * math.pi
"""A point is on the border of an open scan when its projected neighbours leave an angular gap
wider than this (135 degrees; a point on a straight rim sees about 180)."""

NORMAL_METHODS = ("pca", "jet")

EXACT_GAP = math.radians(60.0)
"""The gaps a cloud keeps (:attr:`PointNormals.gap`, the border test's) are exact from this angle on;
below it the pass measures only an upper bound, itself below it (the occupied bins alone,
:func:`.frames._widest_gap`): about a third of the exact measure's cost, which 90 % of a closed
sample's points need no more. Any rule that reads a gap compares it with this angle or more."""

ONE_SIDED_GAP = math.radians(150.0)
"""A fitted normal is not trusted when its own support leaves an angular gap wider than this (150
degrees): the fit then extrapolates across the empty side. On scan rows 4:1 apart an R2 support
often holds the point's row and one neighbouring row only; its jet normal tilts, and qs at R2 gave
errors in H up to 40x the largest |H| of the patch there (99th percentile 22.7). Leaving those
points' normals out (NaN, ``Reason.SINGULAR``) brought the 99th percentile to 0.022 and cost 0.3 %
of the points of a uniform random sphere (0.8 % at 135 degrees)."""



@dataclass(frozen=True, eq=False)
class PointNormals:
    """Normals estimated on a point cloud and what the same pass found.

    Attributes
    ----------
    normals : (n, 3) float64
        Unit, oriented; NaN where there is no fit or the orientation is ambiguous.
    ambiguous : (n,) bool
        Orientation undecided (``Reason.ORIENTATION``).
    one_sided : (n,) bool
        A jet normal whose own support leaves a gap wider than :data:`ONE_SIDED_GAP` away from the
        border: NaN, not trusted (``Reason.SINGULAR``); all False for PCA normals (the PCA plane
        does not extrapolate).
    gap : (n,) float64
        Widest angular gap of the projected support (radians); exact whenever at least
        :data:`EXACT_GAP` (below it an upper bound below :data:`EXACT_GAP`).
    border : (n,) bool
        On the border of an open scan (:func:`border_points`: ``gap > BORDER_GAP``, or a one-sided
        support).
    (``gap`` is measured at :data:`BORDER_RANGE`, ``border`` there and over twice that ball, whatever
    the normals' range.)
    method, label : str
        ``"pca"`` or ``"jet"``; the range label, e.g. ``"R2"``.
    orient : str or (3,) float64
        The orientation rule that ran (:data:`ORIENTATIONS`, or the viewpoint).
    widened : (n,) bool or None
        Points whose fit was widened to :func:`support_floor` (coordinates on a coarse grid).
    """

    normals: np.ndarray
    ambiguous: np.ndarray
    one_sided: np.ndarray
    gap: np.ndarray
    border: np.ndarray
    method: str
    label: str
    orient: object = "top"
    widened: np.ndarray | None = None


def _radii(cloud: PointCloud, k, *, uses_normals: bool = False, knn=None) -> np.ndarray:
    rng = resolve(get_spec("jet"), None if knn is not None else k, None, knn)
    return ball_radii(cloud, rng, uses_normals=uses_normals)


@jit_parallel
def _calm_spacing(spacing, nearest, out):
    """``out[p]``: the larger of p's spacing and the median spacing of its nearest points."""
    n, k = nearest.shape
    parts = max(1, min(n, 64))
    for t in prange(parts):
        values = np.empty(k)
        start, stop = slice_bounds(0, n, t, parts)
        for p in range(start, stop):
            m = 0
            for j in range(k):
                q = nearest[p, j]
                if q >= 0:
                    # insertion into the sorted few
                    v = spacing[q]
                    b = m
                    while b > 0 and values[b - 1] > v:
                        values[b] = values[b - 1]
                        b -= 1
                    values[b] = v
                    m += 1
            if m == 0:
                out[p] = spacing[p]
            else:
                middle = values[m // 2] if m % 2 else 0.5 * (values[m // 2 - 1] + values[m // 2])
                out[p] = max(spacing[p], middle)


def border_radii(cloud: PointCloud) -> np.ndarray:
    """(n,) float64 radius of the border test (and of the PCA that orients the fits) at each point.

    :data:`BORDER_RANGE` times the larger of the point's spacing and the median spacing of its
    :data:`curv.core.neighbour_graph.GRAPH_NEIGHBOURS` nearest. A point whose own six nearest sit in a tight clump
    has a spacing far below its surroundings'; at R3 of its own spacing its ball held only the
    clump (15 points against 51, median), all on one side, and read as a border: 62 of 200,000
    uniform random points of a closed sphere (0.03 %, the false borders of closed scans). With the
    neighbours' median spacing: 10, while the rim of an open scan keeps its one-sided ball (an open
    patch's 241 border points became 240). On scan rows 4:1 apart, 651 points are borders
    instead of 820 and 1 orientation is ambiguous instead of 19 (the balls reach the next rows).
    """
    spacing = point_spacing(cloud)
    calm = np.empty_like(spacing)
    launch(_calm_spacing, spacing, cloud.nearest[0], calm)
    radii = _radii(cloud, BORDER_RANGE)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(spacing > 0, calm / spacing, 1.0)
    return np.where(np.isfinite(scale), radii * scale, radii)


def _keep(cloud: PointCloud, found: _Pass, spread_radii) -> None:
    """Keep a pass's frames at :data:`BORDER_RANGE` and its spreads with the cloud (read-only)."""
    for arr in (found.normal_a, found.gap_a, *found.spreads):
        arr.setflags(write=False)
    entry = cached_with_mesh(cloud, "frames", lambda: (found.normal_a, found.gap_a))
    del entry
    known = cached_with_mesh(cloud, "spreads", list)
    for radii, spread in zip(spread_radii, found.spreads):
        if not any(held is spread for _, held in known):
            known.append((radii, spread))
    del known[:-4]


def _default_spreads(cloud: PointCloud) -> list:
    """The radii of the line check of an estimate at the default range, without and with the
    neighbours' normals (``mru``, ``an``: ``k - 1``): the passes measure those on the way (the
    normals' pass the first, :func:`point_normals`)."""
    return [_radii(cloud, NORMAL_RANGE), _radii(cloud, NORMAL_RANGE, uses_normals=True)]


def _frames(cloud: PointCloud):
    """PCA normals and angular gaps at :data:`BORDER_RANGE`, computed once per cloud (read-only)."""
    def build():
        spread_radii = _default_spreads(cloud)
        found = run_to_end(_one_pass(cloud, border_radii(cloud), spreads=spread_radii, screens=(EXACT_GAP, 0.0)))
        _keep(cloud, found, spread_radii)
        return found.normal_a, found.gap_a

    return cached_with_mesh(cloud, "frames", build)


def point_normals(cloud: PointCloud, *, method: str = "jet", range=NORMAL_RANGE, radius: float | None = None,
                  knn: int | None = None, orient=None, keep_fits_at=(), keep_fits=None) -> PointNormals:
    """Estimate and orient the normals of a point cloud (module notes).

    Parameters
    ----------
    cloud : PointCloud
    method : {"jet", "pca"}
        The degree-2 jet fit over the support, oriented by the PCA normals at
        :data:`BORDER_RANGE` (the default: on 20,000 random points of a sphere the fits then err
        by 0.1 % in H, against 10-20 % with the PCA normals), or the PCA of the support.
    range, radius, knn
        The support of the fits, as for an estimate (:func:`curv.core.ranges.resolve`); default R2.
    orient : {"up", "top", "outward"} or (3,) array_like, optional
        See :func:`orient_normals`; default :func:`default_orientation`.
    keep_fits_at : sequence of curv.core.ranges.Range
        The ranges of an estimate that reads the pass's fits (:mod:`curv.estimators._handover`):
        with ``method="jet"`` and the normals' range among them, the fits ``keep_fits`` names are
        kept with the cloud.
    keep_fits : curv.estimators._handover.NormalFits, optional
        The fits that estimate reads (its registry entry's ``reads_normal_fits``); default the
        jet's (:data:`curv.estimators.jet.JET_FITS`).

    Returns
    -------
    PointNormals
    """
    if method not in NORMAL_METHODS:
        raise EstimatorError(f"point normals method must be one of {', '.join(NORMAL_METHODS)}; got {method!r}")
    if radius is not None or knn is not None:
        range = None
    rng = resolve(get_spec("jet"), range, radius, knn)
    radii = ball_radii(cloud, rng, uses_normals=False)
    # on coordinates stored on a coarse grid, fits over fewer than MIN_SUPPORT_STEPS steps see its
    # stairs: the normals are fitted over at least that radius (the estimates there are SINGULAR)
    floor = support_floor(cloud)
    widened = radii < floor
    if widened.any():
        radii = np.where(widened, floor * (1.0 + TIE_TOLERANCE), radii)
    # one pass: the frames at BORDER_RANGE (borders; the PCA normals that orient), the frame and
    # the jet normals at the fits' range (module notes, "One pass"), the line check on the fits'
    # supports. The one that leaves the neighbours without a normal out (mru, an: k - 1) is measured
    # when one asks (owe_spreads): over fitted normals some are NaN (one-sided, ambiguous) and that
    # check then searches its own balls, so the pass would measure it for nothing.
    spread_radii, owed = _default_spreads(cloud)[:1], _default_spreads(cloud)[1:]
    keep = (keep_fits or JET_FITS) if method == "jet" and rng in tuple(keep_fits_at) else None
    found = latest_with_mesh(cloud, "normals pass", (rng.label, method, floor, keep and keep.options),
                             lambda: run_to_end(_one_pass(cloud, border_radii(cloud), radii,
                                                    jet=method == "jet", normals_b=method == "pca",
                                                    spreads=spread_radii, screens=(EXACT_GAP, ONE_SIDED_GAP),
                                                    kept=keep and keep.new(radii))))
    if found.kept is not None:
        keep_for(cloud, Kept(found.kept, keep.options))
    _keep(cloud, found, spread_radii)
    owe_spreads(cloud, owed, found.grid_radius)
    pca, gap = _frames(cloud)
    if method == "pca" and (rng.label != resolve(get_spec("jet"), BORDER_RANGE).label or widened.any()):
        pca = found.normal_b
    announce("orientation")  # a phase of the estimate's progress (curv.core.jit.iter_watched)
    orient = default_orientation(cloud) if orient is None else orient
    one_sided = np.zeros(cloud.n_points, bool)
    if isinstance(orient, str) and orient == "up":
        # point by point: the normal used is the one turned up (a fit's sign is free, module notes 5)
        normals = pca
        if method == "jet":
            normals = found.fitted.copy()
            normals[~np.isfinite(pca).all(axis=1)] = np.nan
        oriented, ambiguous = orient_normals(cloud, normals, orient="up")
        if method == "jet":
            one_sided = (found.gap_b > ONE_SIDED_GAP) & ~border_points(cloud) & np.isfinite(oriented).all(axis=1)
            oriented[one_sided] = np.nan
        return PointNormals(normals=oriented, ambiguous=ambiguous, one_sided=one_sided, gap=gap,
                            border=border_points(cloud), method=method, label=rng.label, orient=orient,
                            widened=widened)
    oriented, ambiguous = orient_normals(cloud, pca, orient=orient)
    if method == "jet":
        fitted = found.fitted.copy()
        # fitted with the unoriented PCA normal as reference: the same fit up to its sign
        fitted[np.einsum("ij,ij->i", fitted, oriented) < 0] *= -1.0
        fitted[~np.isfinite(oriented).all(axis=1)] = np.nan
        # on the border of the scan every fit is one-sided: those points are BORDER, and keep their normal
        one_sided = (found.gap_b > ONE_SIDED_GAP) & ~border_points(cloud) & np.isfinite(fitted).all(axis=1)
        fitted[one_sided] = np.nan
        oriented = fitted
    return PointNormals(normals=oriented, ambiguous=ambiguous, one_sided=one_sided, gap=gap,
                        border=border_points(cloud), method=method, label=rng.label, orient=orient, widened=widened)


def border_points(cloud: PointCloud) -> np.ndarray:
    """(n,) bool: points on the border of an open scan (the border belongs to the cloud, not to an
    estimate), computed once per cloud (read-only): an angular gap above :data:`BORDER_GAP` at
    :data:`BORDER_RANGE`, or a one-sided support (:func:`.rim.one_sided_points`: a point a fraction
    of a spacing inside the rim, whose gap the points between it and the rim hide)."""
    def build():
        from .rim import one_sided_points

        normals, gap = _frames(cloud)
        border = (gap > BORDER_GAP) | one_sided_points(cloud, normals, gap, border_radii(cloud))
        border.setflags(write=False)
        return border

    return cached_with_mesh(cloud, "border", build)


def border_test_radii(cloud: PointCloud) -> np.ndarray:
    """(n,) float64 radius of the widest ball a point's border flag (:func:`border_points`) reads:
    the gap test's (:func:`border_radii`) or, where the gap sends the point to the one-sided test,
    that test's wider ball (:func:`.rim.rim_radii`)."""
    from .rim import rim_radii

    radii = border_radii(cloud)
    return np.maximum(radii, rim_radii(_frames(cloud)[1], radii))
