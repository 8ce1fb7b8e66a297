"""Normals and borders of a point cloud: local PCA, consistent orientation, the open-scan border.

1. **PCA** (one kernel, :func:`local_frames`): over each point's range support (the ball of
   ``k`` spacings through the neighbour graph, :mod:`curv.core.ranges`), the eigenvector of the
   smallest eigenvalue of the covariance about the centroid is the unoriented normal. The same
   pass measures the largest **angular gap** between the support's offsets projected on that
   plane: about pi on the rim of an open scan, small inside (:func:`border_points`).
2. **Orientation** (:func:`orient_normals`), by one of four rules (:data:`ORIENTATIONS`):

   - ``"up"``: every normal with nz >= 0, point by point (the convention of PDAL's
     ``filters.normal`` for aerial and terrestrial scans). Nothing propagates, so one bad point
     or a fold cannot turn a whole region over, and a tile of a scan is oriented as the whole
     scan is. A normal within :data:`GRAZING_COSINE` of horizontal (a wall, a fence) has no
     decidable "up": it is left undecided (step 3), never guessed.
   - ``"top"``: Hoppe et al. 1992 (Surface reconstruction from unorganized points, §3.3): a
     minimum spanning tree of the neighbour graph with weights ``1 - |n_p . n_q|`` (so that the
     propagation crosses nearly parallel normals first), walked from one root per connected
     part, flipping each normal to agree with its parent; the root is the part's highest point,
     its normal turned up (+z). On a closed object the top's outward normal is up, so this is
     outward; on an open patch it is up where the patch is a height field. Kruskal's algorithm
     in numba (the edges in the order of a stable radix sort of their weights, a union-find
     forest) and a breadth-first walk of each part's tree: no sparse matrices are built.
   - ``"outward"``: the same propagation, each part's root the point farthest from the part's
     centroid, turned away from it (closed objects).
   - a viewpoint (x, y, z): every normal towards it (a scanner's position), without propagation.

   **The default** (:func:`default_orientation`): ``"up"`` for a georeferenced cloud (LAS/LAZ:
   aerial and terrestrial LiDAR in a map's coordinates; on such scans one wrong turn of the
   propagation flipped most of a file: 95.5 % of ``autzen_trim.laz``'s normals pointed down),
   ``"top"`` for any other cloud (objects, closed or not, and synthetic patches). An estimate's
   ``info["orientation"]`` says which rule ran.
3. **Ambiguity.** After the propagation, a point whose oriented normal agrees clearly
   (|cos| >= :data:`AGREE_COSINE`) with fewer graph neighbours than disagree with it, or with
   none, cannot be oriented by its neighbourhood (a thin sheet, a fold, a sparse spot). With
   ``"up"``, where the side comes from the vertical and not from the neighbours, a point that
   as many of its :data:`curv.core.knn.GRAPH_NEIGHBOURS` nearest clearly oppose as agree with
   (and at least one) is undecided: only normals within 60 degrees of horizontal can oppose
   each other once both are up, so these are the sides of a wall or a fence whose normals
   wobble across the horizontal. With ``"up"`` or a viewpoint, a normal seen edge-on (``|cos| <``
   :data:`GRAZING_COSINE` with the vertical or the view ray) is undecided too. Such points get a
   NaN normal and ``Reason.ORIENTATION`` in an estimate: no guess.
4. ``method="jet"`` (the default): the PCA normals, oriented, then refined by the jet fit that
   :func:`curv.fitted_normals.fitted_normals` uses on meshes (:func:`curv.estimators.jet.fit_jet`).
5. **One pass.** Steps 1 and 4 and the line check of an estimate (:func:`support_spread`) read
   nested supports of the same point (R2 inside R3), so one kernel (:func:`_one_pass`) searches
   each point's ball once, at the largest radius, and takes every support from it. It walks the
   points in the grid's cell order and reads their coordinates there (:func:`curv.core.knn.grid_gather`),
   so that neighbours are near in memory; in the cloud's own order (random for a scan saved
   unsorted) every neighbour was a cache miss. The jet is fitted with the unoriented PCA normal
   as its reference: a fit turned the other way is the same fit with its sign changed exactly,
   so the normal is turned afterwards, once the orientation is known.
6. **Grid order.** An estimate of a whole cloud runs on its twin in grid order
   (:func:`grid_ordered`) and maps the rows back: the neighbour graph, the orientation and the
   estimators' kernels then read neighbours that are near in memory too (a cloud saved in random
   order made each of their neighbour reads a cache miss). The sort is stable and the twin's grid
   has the same cells as the cloud's (the same cell size below 65,536 points), so coincident points
   keep their order and the nearest neighbours are the same points, ties included.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .core.connectivity import find_root
from .core.errors import EstimatorError
from .estimators import get_spec
from .estimators._local_fit import slice_bounds
from .estimators._small_linalg import sym3_eigen
from .estimators.jet import DEFAULT_DEGREE, fit_jet, jet_normal
from .estimators.jet import _scratch as jet_scratch
from .core.jit import iter_chunks, jit, jit_parallel, launch, prange, run_to_end, threads
from .core.knn import GRAPH_NEIGHBOURS, build_grid, grid_gather
from .geometry.neighbourhood import (all_centres, ball_support, cached_with_mesh, coordinate_columns, expansion_adjacency,
                            latest_with_mesh, new_queues, new_scratch)
from .core.pointcloud import PointCloud
from .core.ranges import TIE_TOLERANCE, ball_radii, point_spacing, resolve
from .core.validity import Reason

_FIT_OK = int(Reason.OK)

__all__ = ["PointNormals", "point_normals", "grid_ordered", "local_frames", "orient_normals", "default_orientation",
           "describe_orientation", "border_points", "border_radii", "ORIENTATIONS",
           "support_spread", "support_floor", "quantised_supports", "range_above_grid",
           "MIN_SPREAD", "MIN_SUPPORT_STEPS", "ONE_SIDED_GAP", "BORDER_RANGE",
           "NORMAL_RANGE", "BORDER_GAP", "AGREE_COSINE", "GRAZING_COSINE", "NORMAL_METHODS"]

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

AGREE_COSINE = 0.5
"""Neighbours whose normals are within 60 degrees (or opposed within 60) count as agreeing (or not)."""

GRAZING_COSINE = 0.05
"""Orienting towards a viewpoint, or up, fails for normals within ~3 degrees of perpendicular to the
view ray (to the vertical): the side is then within the normals' own error (a jet normal at R2
errs by about a degree on a clean sample, several on a scan's noise). A side that noise flips
above this shows up as neighbours that oppose each other (module notes, step 3), which are left
undecided too. On ``autzen_trim.laz`` (110,000 aerial points: ground, roofs, walls, trees) 0.5 %
of the jet normals are within it, 1.0 % within 0.1 and 2.6 % within 0.25: a wider band would
leave out steep roofs and slopes whose up side is clear."""

ORIENTATIONS = ("up", "top", "outward")
"""The named orientation rules (module notes, step 2); a viewpoint (x, y, z) is the fourth."""

NORMAL_METHODS = ("pca", "jet")

ONE_SIDED_GAP = math.radians(150.0)
"""A fitted normal is not trusted when its own support leaves an angular gap wider than this (150
degrees): the fit then extrapolates across the empty side. On scan rows 4:1 apart an R2 support
often holds the point's row and one neighbouring row only; its jet normal tilts, and qs at R2 gave
errors in H up to 40x the largest |H| of the patch there (99th percentile 22.7). Leaving those
points' normals out (NaN, ``Reason.SINGULAR``) brought the 99th percentile to 0.022 and cost 0.3 %
of the points of a uniform random sphere (0.8 % at 135 degrees)."""

MIN_SUPPORT_STEPS = 10
"""A support must be at least this many coordinate steps wide (in radius) for its fit to be trusted
(:func:`support_floor`). On coordinates stored on a grid of step q (a LAS file's scale; ``plane.laz``
in laspy's samples: a plane on a 1 cm grid with 1.4 cm spacing), a fit over a ball of radius r sees
the grid's stairs: measured on that plane and on a sphere of radius 1 rounded to 1 cm (0.5 cm
spacing), the error in H that the grid alone causes is about q / r² in the median (0.7-1.0 x at
r = 6-16 q, qs and jet) and up to about 10 x that at the extremes. Below r = 10 q that reaches 1 / r,
the largest curvature a support of radius r can hold: the value can be anything (qs on the plane at
R2, r = 2.8 q: |H| up to 1.1e5 where the truth is 0). Such estimates are ``SINGULAR`` (ill-conditioned
at the coordinates' resolution), and the normals are fitted over at least this radius
(:func:`point_normals`): with R2 normals qs on the plane at R8 still reached |H| 506, with normals
over 10 q at most 4.7."""

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
def _widest_gap(i, queue, count, x, y, z, vecs, bins, occupied):
    """Widest angle between consecutive offsets ``q - i`` projected on the plane of ``vecs``'s
    last two eigenvectors (2 pi with fewer than two); ``bins``: (6, GAP_BINS) and ``occupied``:
    (GAP_BINS,) int64 scratch.

    The offsets fall in :data:`GAP_BINS` bins of their pseudo-angle (:func:`_pseudo_angle`); each
    bin keeps its least and greatest (a bit mask says which bins hold any: no bin is cleared
    before). Between consecutive occupied bins the step of the pseudo-angle bounds the angle
    within a factor 2, so only the steps within a factor 2 of the largest are measured with
    ``atan2`` (as the difference of the two ends' angles).
    """
    e1x, e1y, e1z = vecs[0, 2], vecs[1, 2], vecs[2, 2]
    e2x, e2y, e2z = vecs[0, 1], vecs[1, 1], vecs[2, 1]
    px, py, pz = x[i], y[i], z[i]
    # rows: least key, its u, v; greatest key, its u, v
    scale = GAP_BINS / 4.0
    mask = np.uint64(0)
    one = np.uint64(1)
    used = 0
    for j in range(1, count):
        q = queue[j]
        dx, dy, dz = x[q] - px, y[q] - py, z[q] - pz
        u = dx * e1x + dy * e1y + dz * e1z
        v = dx * e2x + dy * e2y + dz * e2z
        if u * u + v * v > 0.0:
            key = _pseudo_angle(u, v)
            b = min(max(int((key + 2.0) * scale), 0), GAP_BINS - 1)
            bit = one << np.uint64(b)
            if mask & bit:
                if key < bins[0, b]:
                    bins[0, b], bins[1, b], bins[2, b] = key, u, v
                if key > bins[3, b]:
                    bins[3, b], bins[4, b], bins[5, b] = key, u, v
            else:
                mask |= bit
                bins[0, b], bins[1, b], bins[2, b] = key, u, v
                bins[3, b], bins[4, b], bins[5, b] = key, u, v
            used += 1
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
def _frame(i, sub, count, x, y, z, cov, vecs, bins, occupied):
    """PCA normal (``vecs[:3, 0]``) and widest gap of the support ``sub[:count]``; the gap, or -1
    when the support is too small (fewer than 3 points) for a plane."""
    if count < 3:
        return -1.0
    offset_moments(i, sub, count, x, y, z, True, cov)
    sym3_eigen(cov, vecs)
    return _widest_gap(i, sub, count, x, y, z, vecs, bins, occupied)


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
    sym3_eigen(cov, vecs)
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


@jit_parallel
def _pass_kernel(lo, hi, cells, coords, outer2, radii2, wanted, degree, queues, dists, subs,
                 normal_a, gap_a, count_a, normal_b, gap_b, fitted, reason, spread):
    """One walk over the points in grid order (module notes, "One pass"): each point's ball at
    ``outer2``, and from it the supports at the radii of ``radii2``'s rows (nested in the ball).

    ``radii2`` (4, n) squared radii, original order: row 0 the frame A (PCA normal into
    ``normal_a``, sorted order, gap and count), row 1 the frame B (PCA normal, gap; and the jet
    normal fitted over it, oriented by frame A's normal, when ``wanted[2]``), rows 2 and 3 two
    spreads. ``wanted[r]`` (5,) says which parts run (0: A, 1: B, 2: jet, 3, 4: spreads).
    """
    order = cells[3]
    x, y, z = coords[1], coords[2], coords[3]
    parts = queues.shape[0]
    for t in prange(parts):
        queue = queues[t]
        dist2 = dists[t]
        sub = subs[t]
        cov = np.empty((3, 3))
        vecs = np.empty((4, 3))
        bins = np.empty((6, GAP_BINS))
        occupied = np.empty(GAP_BINS, np.int64)
        m, vec, cov_jet, frame, evec = jet_scratch()
        keep_b = normal_b.shape[0] > 1
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = order[i]
            count = grid_gather(i, outer2[p], cells, coords, queue, dist2)
            if wanted[0]:
                c = _within(queue, dist2, count, radii2[0, p], sub)
                count_a[p] = c - 1
                g = _frame(i, sub, c, x, y, z, cov, vecs, bins, occupied)
                if g < 0.0:
                    normal_a[i, 0] = normal_a[i, 1] = normal_a[i, 2] = math.nan
                    gap_a[p] = 2.0 * math.pi
                else:
                    normal_a[i, 0], normal_a[i, 1], normal_a[i, 2] = vecs[0, 0], vecs[1, 0], vecs[2, 0]
                    gap_a[p] = g
            if wanted[1]:
                c = _within(queue, dist2, count, radii2[1, p], sub)
                g = -2.0
                if wanted[2]:
                    evec[3, 0] = math.nan
                    code, _, _ = fit_jet(i, c, sub, x, y, z, normal_a, degree, m, vec, cov_jet, frame, evec)
                    reason[p] = code
                    if code == _FIT_OK:
                        jet_normal(vec, frame, fitted, p)
                    else:
                        fitted[p, 0] = fitted[p, 1] = fitted[p, 2] = math.nan
                    if c >= 3 and math.isfinite(evec[3, 0]):
                        # the fit's own PCA of this support (its frame): the plane of the gap
                        g = _widest_gap(i, sub, c, x, y, z, evec, bins, occupied)
                if g == -2.0 or keep_b:
                    g = _frame(i, sub, c, x, y, z, cov, vecs, bins, occupied)
                    if keep_b:
                        if g < 0.0:
                            normal_b[p, 0] = normal_b[p, 1] = normal_b[p, 2] = math.nan
                        else:
                            normal_b[p, 0], normal_b[p, 1], normal_b[p, 2] = vecs[0, 0], vecs[1, 0], vecs[2, 0]
                gap_b[p] = 2.0 * math.pi if g < 0.0 else g
            for r in range(2):
                if wanted[3 + r]:
                    c = _within(queue, dist2, count, radii2[2 + r, p], sub)
                    spread[r, p] = _spread(i, sub, c, x, y, z, cov, vecs)


@dataclass(frozen=True, eq=False)
class _Pass:
    """What one :func:`_one_pass` found; None for the parts it was not asked."""

    normal_a: np.ndarray | None
    gap_a: np.ndarray | None
    count_a: np.ndarray | None
    normal_b: np.ndarray | None
    gap_b: np.ndarray | None
    fitted: np.ndarray | None
    spreads: tuple


def _one_pass(cloud: PointCloud, frame_a=None, frame_b=None, *, jet: bool = False, normals_b: bool = False,
              spreads=(), chunk: int | None = None):
    """Frames, jet normals and spreads of every point from one ball search per point (a generator).

    Parameters
    ----------
    cloud : PointCloud
    frame_a, frame_b : (n,) float64, optional
        Radii of the two PCA frames (normal, angular gap); the jet normals (``jet``) are fitted
        over frame B's supports and oriented by frame A's normals (either sign: the caller orients).
    normals_b : bool
        Keep frame B's normals (else only its gaps).
    spreads : sequence of (n,) float64
        Up to two radii of :func:`support_spread`.

    Returns
    -------
    _Pass
        Unit PCA normals (n, 3) (NaN under 3 points), gaps (n,), frame A's support sizes (n,)
        int64, jet normals (n, 3) (NaN without a fit), and the spreads (n,) each.
    """
    n = cloud.n_points
    rows = [frame_a, frame_b] + list(spreads) + [None] * (2 - len(spreads))
    wanted = np.array([r is not None for r in rows[:2]] + [jet and frame_b is not None and frame_a is not None]
                      + [r is not None for r in rows[2:]], np.bool_)
    radii2 = np.zeros((4, n))
    for r, radii in enumerate(rows):
        if radii is not None:
            np.square(np.asarray(radii, np.float64), out=radii2[r])
    outer = np.sqrt(radii2.max(axis=0))
    cells, coords = cloud.ball_grid(outer)
    outer2 = radii2.max(axis=0)
    parts = max(1, min(threads(), n))
    queues = new_queues(n, parts)
    dists = np.empty((parts, n))
    subs = new_queues(n, parts)
    normal_a = np.empty((n, 3)) if wanted[0] else np.empty((1, 3))
    gap_a = np.empty(n) if wanted[0] else np.empty(1)
    count_a = np.empty(n, np.int64) if wanted[0] else np.empty(1, np.int64)
    normal_b = np.empty((n, 3)) if wanted[1] and normals_b else np.empty((1, 3))
    gap_b = np.empty(n) if wanted[1] else np.empty(1)
    fitted = np.empty((n, 3)) if wanted[2] else np.empty((1, 3))
    reason = np.empty(n if wanted[2] else 1, np.uint8)
    spread = np.empty((2, n if len(spreads) else 1))

    def run(lo: int, hi: int) -> None:
        launch(_pass_kernel, lo, hi, cells, coords, outer2, radii2, wanted, DEFAULT_DEGREE, queues, dists, subs,
               normal_a, gap_a, count_a, normal_b, gap_b, fitted, reason, spread)

    yield from iter_chunks(n, run, chunk=chunk)
    del queues, dists, subs, radii2, outer2
    if wanted[0]:
        # frame A's normals were kept in grid order (the jet fits read them there)
        unsorted = np.empty_like(normal_a)
        unsorted[cells[3]] = normal_a
        normal_a = unsorted
    return _Pass(normal_a=normal_a if wanted[0] else None, gap_a=gap_a if wanted[0] else None,
                 count_a=count_a if wanted[0] else None, normal_b=normal_b if wanted[1] and normals_b else None,
                 gap_b=gap_b if wanted[1] else None, fitted=fitted if wanted[2] else None,
                 spreads=tuple(spread[r] for r in range(len(spreads))))


@jit_parallel
def _spread_kernel(centres, lo, hi, radius, adj_ptr, adj, x, y, z, usable, stamps, queues, spread):
    parts = stamps.shape[0]
    for t in prange(parts):
        queue = queues[t]
        stamp = stamps[t]
        cov = np.empty((3, 3))
        vecs = np.empty((4, 3))
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            count, queue = ball_support(p, radius[p] ** 2, adj_ptr, adj, x, y, z, stamp, queue)
            kept = 0
            for j in range(count):  # the neighbours the estimator can use, and p
                q = queue[j]
                if q == p or usable[q]:
                    queue[kept] = q
                    kept += 1
            spread[p] = _spread(p, queue, kept, x, y, z, cov, vecs)


def support_spread(cloud: PointCloud, radii: np.ndarray, centres: np.ndarray | None = None,
                   *, usable: np.ndarray | None = None, chunk: int | None = None):
    """(n,) float64: how far from a line or a curve each support is, a generator (yields the
    fraction done).

    :func:`_spread` of the points of p's ball (with ``usable`` (n,) bool, only those it marks, and
    p): about sqrt(second / largest eigenvalue of the second moments about p) on a surface patch
    (1 for an even disc), 0 for points along a line or a plane curve through p; compared with
    :data:`MIN_SPREAD`. Rows outside ``centres`` are left unset. The pass that found the cloud's
    normals and borders measured the spreads at the default range (:func:`_frames`): radii equal to
    those are answered from it when every point is usable.
    """
    n = cloud.n_points
    every = usable is None or bool(np.all(usable))
    for known, spread in cached_with_mesh(cloud, "spreads", list) if every else ():
        if known.shape == np.shape(radii) and np.array_equal(known, radii):
            yield 1.0
            return spread
    if centres is None and every:
        found = yield from _one_pass(cloud, spreads=(np.asarray(radii, np.float64),), chunk=chunk)
        return found.spreads[0]
    # a region (or points left out): its own centres through the ball search, at the cost of the region
    usable = np.ones(n, np.bool_) if every else np.ascontiguousarray(usable, dtype=np.bool_)
    centres = all_centres(n, centres)
    adj_ptr, adj = expansion_adjacency(cloud, radii=radii)
    x, y, z = coordinate_columns(cloud)
    radius = np.ascontiguousarray(radii, dtype=np.float64)
    parts = max(1, min(threads(), centres.size))
    stamps = new_scratch(n, parts)
    queues = new_queues(n, parts)
    spread = np.empty(n)

    def run(lo: int, hi: int) -> None:
        launch(_spread_kernel, centres, lo, hi, radius, adj_ptr, adj, x, y, z, usable, stamps, queues, spread)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return spread


def support_floor(cloud: PointCloud) -> float:
    """The narrowest support radius trusted on this cloud: :data:`MIN_SUPPORT_STEPS` steps of the
    grid its coordinates are stored on (:attr:`curv.PointCloud.coordinate_step`; about 1e-5 of the
    spacing for coordinates of full precision, where it changes nothing)."""
    return MIN_SUPPORT_STEPS * cloud.coordinate_step


def range_above_grid(cloud: PointCloud, *, uses_normals: bool = False) -> int:
    """The smallest whole range Rk whose supports reach :func:`support_floor` at 95 % of the points
    (those with the 5 % smallest spacings may stay below): what to ask for on a coarse grid."""
    spacing = point_spacing(cloud)
    low = float(np.percentile(spacing[np.isfinite(spacing)], 5)) if np.isfinite(spacing).any() else 0.0
    if not low > 0.0:
        return NORMAL_RANGE
    k = max(NORMAL_RANGE, math.ceil(support_floor(cloud) / low - 1e-9))
    return k + 1 if uses_normals else k


def quantised_supports(cloud: PointCloud, radii: np.ndarray) -> np.ndarray:
    """(n,) bool: the supports of these radii (n,) narrower than :func:`support_floor`, whose fits
    see the coordinates' grid rather than the surface (``SINGULAR`` in an estimate)."""
    return np.asarray(radii) < support_floor(cloud)


def local_frames(cloud: PointCloud, radii: np.ndarray, *, chunk: int | None = None):
    """Unoriented PCA normals and angular gaps over each point's ball support (a generator).

    Parameters
    ----------
    cloud : PointCloud
    radii : (n,) float64
        Ball radius of every point (:func:`curv.core.ranges.ball_radii`).
    chunk : int, optional
        Points per kernel call (default adaptive).

    Yields
    ------
    float
        Fraction done.

    Returns
    -------
    normals : (n, 3) float64
        Unit, unoriented; NaN where the support has fewer than 3 points.
    gap : (n,) float64
        Widest angle (radians) between consecutive projected neighbours; 2 pi without any.
    count : (n,) int64
        Support size, the point excluded.
    """
    found = yield from _one_pass(cloud, np.asarray(radii, np.float64), chunk=chunk)
    return found.normal_a, found.gap_a, found.count_a


@jit
def _edge_pass(indptr, neighbours, normal, finite, rows, cols, weight):
    """Count (``rows`` None) or write the edges of :func:`_tree_edges`; returns their number."""
    n = indptr.size - 1
    m = 0
    for p in range(n):
        if finite[p]:
            for j in range(indptr[p], indptr[p + 1]):
                q = neighbours[j]
                if q > p and finite[q]:
                    if rows is not None:
                        rows[m] = p
                        cols[m] = q
                        c = normal[p, 0] * normal[q, 0] + normal[p, 1] * normal[q, 1] + normal[p, 2] * normal[q, 2]
                        # kept positive (a sparse MST once read zero as no edge), so the tree and its ties stay as they were
                        weight[m] = 1.0 - abs(c) + 1e-9
                    m += 1
    return m


@jit
def _tree_edges(indptr, neighbours, normal, finite):
    """The neighbour graph's edges ``p < q`` between finite normals, and their weights ``1 - |n_p . n_q|``."""
    m = _edge_pass(indptr, neighbours, normal, finite, None, None, None)
    rows = np.empty(m, np.int32)
    cols = np.empty(m, np.int32)
    weight = np.empty(m)
    _edge_pass(indptr, neighbours, normal, finite, rows, cols, weight)
    return rows, cols, weight


RADIX_BITS = 11
"""Bits per pass of :func:`_stable_rank` (2048 buckets: their counts stay in the cache)."""


@jit
def _radix_rank(weight, rank, spare_rank):
    """:func:`_stable_rank` into one of the two (m,) int scratch arrays, which it returns."""
    m = weight.size
    keys = weight.view(np.int64).copy()
    spare_keys = np.empty(m, np.int64)
    for i in range(m):
        rank[i] = i
    buckets = 1 << RADIX_BITS
    count = np.empty(buckets + 1, np.int64)
    for shift in range(0, 64, RADIX_BITS):
        count[:] = 0
        for i in range(m):
            count[((keys[i] >> shift) & (buckets - 1)) + 1] += 1
        if count.max() == m:
            continue
        for d in range(buckets):
            count[d + 1] += count[d]
        for i in range(m):
            d = (keys[i] >> shift) & (buckets - 1)
            at = count[d]
            count[d] = at + 1
            spare_keys[at] = keys[i]
            spare_rank[at] = rank[i]
        keys, spare_keys = spare_keys, keys
        rank, spare_rank = spare_rank, rank
    return rank


def _stable_rank(weight: np.ndarray) -> np.ndarray:
    """(m,) ``np.argsort(weight, kind="stable")`` of non-negative finite floats (int32 below 2^31
    weights), by a least-significant-digit radix sort of their bit patterns (which order such
    floats as their values): each pass keeps the order of equal digits, so ties keep their order.
    Passes whose digit is the same for every weight are skipped (the high bits of weights in [0, 2))."""
    weight = np.ascontiguousarray(weight, dtype=np.float64)
    dtype = np.int32 if weight.size < 2 ** 31 else np.int64
    return _radix_rank(weight, np.empty(weight.size, dtype), np.empty(weight.size, dtype))


@jit
def _spanning_forest(n, rank, rows, cols):
    """Kruskal: the edges of the minimum spanning forest, lightest first (``rank`` sorts the
    weights), as a CSR adjacency ``(ptr (n+1,), adj)``, and each point's part (a representative)."""
    parent = np.arange(n)
    take = np.zeros(rank.size, np.bool_)
    degree = np.zeros(n + 1, np.int64)
    for e in rank:
        a = find_root(parent, rows[e])
        b = find_root(parent, cols[e])
        if a != b:
            parent[max(a, b)] = min(a, b)
            take[e] = True
            degree[rows[e] + 1] += 1
            degree[cols[e] + 1] += 1
    ptr = np.cumsum(degree)
    adj = np.empty(ptr[n], np.int64)
    fill = ptr[:n].copy()
    for e in range(rank.size):
        if take[e]:
            adj[fill[rows[e]]] = cols[e]
            fill[rows[e]] += 1
            adj[fill[cols[e]]] = rows[e]
            fill[cols[e]] += 1
    part = np.empty(n, np.int64)
    for p in range(n):
        part[p] = find_root(parent, p)
    return ptr, adj, part


@jit
def _propagate(ptr, adj, part, key, root_sign, normal):
    """Walk each part's tree breadth first from its root (the greatest ``key``, the smallest index
    on ties), turning the root by ``root_sign`` (its value < 0: flip) and every other normal to
    agree with its tree parent."""
    n = part.size
    root = np.full(n, -1, np.int64)
    for p in range(n):
        r = part[p]
        if root[r] < 0 or key[p] > key[root[r]]:
            root[r] = p
    seen = np.zeros(n, np.bool_)
    queue = np.empty(n, np.int64)
    for r in range(n):
        s = root[r]
        if s < 0:
            continue
        if root_sign[s] < 0.0:
            normal[s, 0] = -normal[s, 0]
            normal[s, 1] = -normal[s, 1]
            normal[s, 2] = -normal[s, 2]
        seen[s] = True
        queue[0] = s
        head, tail = 0, 1
        while head < tail:
            p = queue[head]
            head += 1
            for j in range(ptr[p], ptr[p + 1]):
                q = adj[j]
                if seen[q]:
                    continue
                seen[q] = True
                if normal[p, 0] * normal[q, 0] + normal[p, 1] * normal[q, 1] + normal[p, 2] * normal[q, 2] < 0.0:
                    normal[q, 0] = -normal[q, 0]
                    normal[q, 1] = -normal[q, 1]
                    normal[q, 2] = -normal[q, 2]
                queue[tail] = q
                tail += 1


@jit_parallel
def _agreement(indptr, neighbours, normal, cosine, ambiguous):
    """``ambiguous[p]``: p's normal agrees (cos >= ``cosine``) with none of its neighbours
    ``neighbours[indptr[p]:indptr[p + 1]]``, or with no more of them than disagree (cos <= -``cosine``)."""
    n = indptr.size - 1
    for p in prange(n):
        agree = 0
        oppose = 0
        for j in range(indptr[p], indptr[p + 1]):
            q = neighbours[j]
            c = normal[p, 0] * normal[q, 0] + normal[p, 1] * normal[q, 1] + normal[p, 2] * normal[q, 2]
            if c >= cosine:
                agree += 1
            elif c <= -cosine:
                oppose += 1
        ambiguous[p] = agree == 0 or oppose >= agree


@jit_parallel
def _opposed(indptr, neighbours, normal, cosine, ambiguous):
    """``ambiguous[p]``: as many of p's neighbours (-1 entries skipped) disagree with its normal
    (cos <= -``cosine``) as agree with it (cos >= ``cosine``), and at least one does."""
    n = indptr.size - 1
    for p in prange(n):
        agree = 0
        oppose = 0
        for j in range(indptr[p], indptr[p + 1]):
            q = neighbours[j]
            if q < 0:
                continue
            c = normal[p, 0] * normal[q, 0] + normal[p, 1] * normal[q, 1] + normal[p, 2] * normal[q, 2]
            if c >= cosine:
                agree += 1
            elif c <= -cosine:
                oppose += 1
        ambiguous[p] = oppose > 0 and oppose >= agree


def default_orientation(cloud: PointCloud) -> str:
    """The orientation rule of a cloud's estimated normals when none is asked for (module notes, 2):
    ``"up"`` for a georeferenced scan (:attr:`curv.PointCloud.georeferenced`), else ``"top"``."""
    return "up" if cloud.georeferenced else "top"


def describe_orientation(orient) -> str:
    """The orientation rule in words, e.g. ``up (nz >= 0 at every point)`` (the summaries' wording)."""
    if isinstance(orient, str):
        return {"up": "up (nz >= 0 at every point)",
                "top": "by propagation from each part's top, turned up (Hoppe)",
                "outward": "outward (propagated from each part's farthest point, Hoppe)"}.get(orient, orient)
    return "towards " + " ".join(f"{v:g}" for v in np.asarray(orient, dtype=np.float64).reshape(-1))


def _orient_up(cloud: PointCloud, out: np.ndarray, finite: np.ndarray) -> np.ndarray:
    """``"up"``, point by point, in place: flip every normal with nz < 0; the edge-on ones and those
    their nearest points oppose (module notes, step 3) are undecided (NaN). Returns those (n,) bool."""
    out[out[:, 2] < 0.0] *= -1.0
    nearest = cloud.nearest[0]
    k = nearest.shape[1]
    indptr = np.arange(0, k * nearest.shape[0] + 1, k, dtype=np.int64)
    ambiguous = np.zeros(out.shape[0], bool)
    launch(_opposed, indptr, nearest.reshape(-1), np.where(finite[:, None], out, 0.0), AGREE_COSINE, ambiguous)
    ambiguous |= ~(np.abs(out[:, 2]) >= GRAZING_COSINE)
    ambiguous &= finite
    out[ambiguous] = np.nan
    return ambiguous


def orient_normals(cloud: PointCloud, normals: np.ndarray, *, orient=None) -> tuple[np.ndarray, np.ndarray]:
    """Orient unoriented normals (module notes, step 2) and find the undecided ones (step 3).

    Parameters
    ----------
    cloud : PointCloud
    normals : (n, 3) float64
        Unit normals, either sign; NaN rows take no part.
    orient : {"up", "top", "outward"} or (3,) array_like, optional
        Every normal up (nz >= 0), propagation from each connected part's top turned up or from its
        farthest point turned away from its centroid, or every normal towards this viewpoint;
        default :func:`default_orientation`.

    Returns
    -------
    normals : (n, 3) float64
        Oriented copy; NaN at undecided points.
    ambiguous : (n,) bool
        Points whose orientation could not be decided (module notes, step 3).
    """
    out = np.array(normals, dtype=np.float64, copy=True)
    n = out.shape[0]
    finite = np.isfinite(out).all(axis=1)
    if orient is None:
        orient = default_orientation(cloud)
    if not isinstance(orient, str):
        view = np.asarray(orient, dtype=np.float64).reshape(3)
        ray = view - cloud.points
        ray /= np.linalg.norm(ray, axis=1, keepdims=True)
        cosine = np.einsum("ij,ij->i", out, ray)
        out[cosine < 0] *= -1.0
        ambiguous = finite & ~(np.abs(cosine) >= GRAZING_COSINE)
        out[ambiguous] = np.nan
        return out, ambiguous
    if orient not in ORIENTATIONS:
        raise EstimatorError(f"orient must be 'up', 'top', 'outward' or a viewpoint (x, y, z); got {orient!r}")
    if orient == "up":
        return out, _orient_up(cloud, out, finite)
    graph = cloud.adjacency
    indptr, neighbours = graph.indptr, graph.indices
    safe = np.where(finite[:, None], out, 0.0)
    rows, cols, weight = _tree_edges(indptr, neighbours, safe, finite)
    # Kruskal in the order of the weights (stable: ties keep the edges' order)
    ptr, adj, part = _spanning_forest(n, _stable_rank(weight), rows, cols)
    del rows, cols, weight
    # one root per part: its highest point (turned up), or the point farthest from its centroid (turned away)
    if orient == "top":
        key = cloud.points[:, 2].copy()
        root_sign = out[:, 2].copy()
    else:
        centroid = np.stack([np.bincount(part, cloud.points[:, c], n) for c in range(3)], axis=1)
        centroid /= np.maximum(np.bincount(part, minlength=n), 1)[:, None]
        away = cloud.points - centroid[part]
        key = np.linalg.norm(away, axis=1)
        root_sign = np.einsum("ij,ij->i", out, away)
    key[~finite] = -np.inf
    root_sign[~finite] = 0.0
    _propagate(ptr, adj, part, key, root_sign, out)
    ambiguous = np.zeros(n, bool)
    safe = np.where(finite[:, None], out, 0.0)
    launch(_agreement, indptr, neighbours, safe, AGREE_COSINE, ambiguous)
    ambiguous &= finite
    out[ambiguous] = np.nan
    return out, ambiguous


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
        7.2 degrees (:data:`GAP_BINS`).
    border : (n,) bool
        ``gap > BORDER_GAP``: on the border of an open scan.
    (``gap`` and ``border`` are measured at :data:`BORDER_RANGE` whatever the normals' range.)
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
    :data:`curv.core.knn.GRAPH_NEIGHBOURS` nearest. A point whose own six nearest sit in a tight clump
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
    """The radii of the line check of an estimate at the default range, with and without the
    neighbours' normals (``mru``, ``an``: ``k - 1``): the pass measures those on the way."""
    return [_radii(cloud, NORMAL_RANGE), _radii(cloud, NORMAL_RANGE, uses_normals=True)]


def _frames(cloud: PointCloud):
    """PCA normals and angular gaps at :data:`BORDER_RANGE`, computed once per cloud (read-only)."""
    def build():
        spread_radii = _default_spreads(cloud)
        found = run_to_end(_one_pass(cloud, border_radii(cloud), spreads=spread_radii))
        _keep(cloud, found, spread_radii)
        return found.normal_a, found.gap_a

    return cached_with_mesh(cloud, "frames", build)


def point_normals(cloud: PointCloud, *, method: str = "jet", range=NORMAL_RANGE, radius: float | None = None,
                  knn: int | None = None, orient=None) -> PointNormals:
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
    # the jet normals at the fits' range (module notes, "One pass"), the default line checks
    spread_radii = _default_spreads(cloud)
    found = latest_with_mesh(cloud, "normals pass", (rng.label, method, floor),
                             lambda: run_to_end(_one_pass(cloud, border_radii(cloud), radii,
                                                    jet=method == "jet", normals_b=method == "pca",
                                                    spreads=spread_radii)))
    _keep(cloud, found, spread_radii)
    pca, gap = _frames(cloud)
    if method == "pca" and (rng.label != resolve(get_spec("jet"), BORDER_RANGE).label or widened.any()):
        pca = found.normal_b
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
            one_sided = (found.gap_b > ONE_SIDED_GAP) & ~(gap > BORDER_GAP) & np.isfinite(oriented).all(axis=1)
            oriented[one_sided] = np.nan
        return PointNormals(normals=oriented, ambiguous=ambiguous, one_sided=one_sided, gap=gap,
                            border=gap > BORDER_GAP, method=method, label=rng.label, orient=orient,
                            widened=widened)
    oriented, ambiguous = orient_normals(cloud, pca, orient=orient)
    if method == "jet":
        fitted = found.fitted.copy()
        # fitted with the unoriented PCA normal as reference: the same fit up to its sign
        fitted[np.einsum("ij,ij->i", fitted, oriented) < 0] *= -1.0
        fitted[~np.isfinite(oriented).all(axis=1)] = np.nan
        # on the border of the scan every fit is one-sided: those points are BORDER, and keep their normal
        one_sided = (found.gap_b > ONE_SIDED_GAP) & ~(gap > BORDER_GAP) & np.isfinite(fitted).all(axis=1)
        fitted[one_sided] = np.nan
        oriented = fitted
    return PointNormals(normals=oriented, ambiguous=ambiguous, one_sided=one_sided, gap=gap,
                        border=gap > BORDER_GAP, method=method, label=rng.label, orient=orient, widened=widened)


def grid_ordered(cloud: PointCloud):
    """The cloud with its points in its grid's cell order, and that order (module notes, 6).

    Returns
    -------
    (twin, order) or None
        ``twin`` a :class:`PointCloud` of ``cloud.points[order]`` (and its normals), ``order``
        (n,) int64 read-only; None for a twin itself (it is in that order). Made once per cloud
        and kept with it, so that the twin's own caches (neighbours, frames, normals) serve every
        estimate of the cloud.
    """
    def build():
        order = build_grid(cloud.points, GRAPH_NEIGHBOURS)[0][3]
        normals = None if cloud.normals is None else cloud.normals[order]
        twin = PointCloud(cloud.points[order], normals, georeferenced=cloud.georeferenced)
        cached_with_mesh(twin, "grid order", lambda: None)
        cloud.same_points_as(twin, order)
        return twin, order

    return cached_with_mesh(cloud, "grid order", build)


def border_points(cloud: PointCloud) -> np.ndarray:
    """(n,) bool: points on the border of an open scan: angular gap above :data:`BORDER_GAP` at
    :data:`BORDER_RANGE` (the border belongs to the cloud, not to an estimate)."""
    return _frames(cloud)[1] > BORDER_GAP
