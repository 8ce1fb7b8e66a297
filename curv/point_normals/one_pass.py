"""One ball search per point, every support from it: frames, jet normals and spreads (module notes, 5).

:func:`_one_pass` walks the points in the grid's cell order; :func:`local_frames` and
:func:`support_spread` are its public forms (a region's spreads search their own balls).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.jit import iter_chunks, jit_parallel, launch, prange, slice_bounds, threads
from ..core.grid_blocks import cell_runs
from ..core.knn import block_gather, cell_of
from ..core.pointcloud import PointCloud
from ..core.validity import OK
from ..estimators._jet_fit import fit_jet, jet_normal, jet_scratch
from ..estimators._handover import keep_fit
from ..estimators.jet import DEFAULT_DEGREE
from ..geometry.neighbourhood import (all_centres, ball_support, cached_with_mesh, coordinate_columns, expansion_adjacency,
                                      new_queues, new_scratch)
from .frames import _frame, _spread, _widest_gap, _within, gap_scratch

__all__ = ["local_frames", "support_spread", "ball_walk_inputs", "owe_spreads"]


@jit_parallel
def _pass_kernel(lo, hi, grid, radii, wanted, degree, scratch, out, kept):
    """One walk over the points in grid order (module notes, "One pass"): each point's ball at
    ``outer2``, and from it the supports at the radii of ``radii2``'s rows (nested in the ball).

    ``grid``: the ball grid ``(cells, coords)``; ``radii``: ``(outer2 (n,), radii2 (4, n), screens
    (2,))``, squared radii in the original order: row 0 the frame A (PCA normal into ``normal_a``,
    sorted order, gap exact from ``screens[0]`` on, and count), row 1 the frame B (PCA normal, gap
    exact from ``screens[1]`` on; and the jet normal fitted over it, oriented by frame A's normal,
    when ``wanted[2]``), rows 2 and 3 two spreads. ``wanted`` (5,) says which parts run (0: A, 1: B,
    2: jet, 3, 4: spreads). ``scratch``: ``(queues, dists, subs)``, a row per thread, one slot more
    than the points; ``out``: ``(normal_a, gap_a, count_a, normal_b, gap_b, fitted, reason, spread)``;
    ``kept``: the fits bundle an estimator reads (:mod:`curv.estimators._handover`), filled per point
    after its jet fit, or None (compiled without).

    The points are walked cell by cell: the cells of a cell's block are looked up once for all
    its points (:func:`curv.core.grid_blocks.cell_runs`), each point's ball read from them (those
    whose box lies within its radius).
    """
    cells, coords = grid
    outer2, radii2, screens = radii
    queues, dists, subs = scratch
    normal_a, gap_a, count_a, normal_b, gap_b, fitted, reason, spread = out
    order, cell_start = cells[3], cells[1]
    x, y, z = coords[1], coords[2], coords[3]
    parts = queues.shape[0]
    for t in prange(parts):
        queue = queues[t]
        dist2 = dists[t]
        sub = subs[t]
        cov = np.empty((3, 3))
        vecs = np.empty((4, 3))
        gaps = gap_scratch()
        block = (np.empty((64, 2), np.int64), 0, np.empty((64, 6)))
        m, vec, cov_jet, frame, evec = jet_scratch()
        keep_b = normal_b.shape[0] > 1
        start, stop = slice_bounds(lo, hi, t, parts)
        c = cell_of(start, cell_start) if start < stop else 0
        cell_end = start
        for i in range(start, stop):
            if i >= cell_end:
                c, cell_end, block = cell_runs(i, c, outer2, cells, coords[0], block)
            p = order[i]
            count = block_gather(i, outer2[p], block, coords, queue, dist2)
            if wanted[0]:
                # frame A's ball is usually the outer one: the ball search's queue itself, not a copy
                whole = radii2[0, p] == outer2[p]
                c_a = count if whole else _within(queue, dist2, count, radii2[0, p], sub)
                count_a[p] = c_a - 1
                g = _frame(i, queue if whole else sub, c_a, x, y, z, cov, vecs, gaps, screens[0])
                if g < 0.0:
                    normal_a[i, 0] = normal_a[i, 1] = normal_a[i, 2] = math.nan
                    gap_a[p] = 2.0 * math.pi
                else:
                    normal_a[i, 0], normal_a[i, 1], normal_a[i, 2] = vecs[0, 0], vecs[1, 0], vecs[2, 0]
                    gap_a[p] = g
            c_b = 0
            if wanted[1]:
                c_b = _within(queue, dist2, count, radii2[1, p], sub)
                g = -2.0
                if wanted[2]:
                    evec[3, 0] = math.nan
                    code, h, _ = fit_jet(i, c_b, sub, (x, y, z, normal_a), degree, (m, vec, cov_jet, frame, evec))
                    reason[p] = code
                    if code == OK:
                        jet_normal(vec, frame, fitted, p)
                    else:
                        fitted[p, 0] = fitted[p, 1] = fitted[p, 2] = math.nan
                    if kept is not None:
                        keep_fit(kept, p, i, (code, h, math.isfinite(normal_a[i, 0]), (m, vec, cov_jet, frame, evec)),
                                 (sub, c_b), (x, y, z), fitted)
                    if c_b >= 3 and math.isfinite(evec[3, 0]):
                        # the fit's own PCA of this support (its frame): the plane of the gap
                        g = _widest_gap(i, sub, c_b, x, y, z, evec, gaps, screens[1])
                if g == -2.0 or keep_b:
                    g = _frame(i, sub, c_b, x, y, z, cov, vecs, gaps, screens[1])
                    if keep_b:
                        if g < 0.0:
                            normal_b[p, 0] = normal_b[p, 1] = normal_b[p, 2] = math.nan
                        else:
                            normal_b[p, 0], normal_b[p, 1], normal_b[p, 2] = vecs[0, 0], vecs[1, 0], vecs[2, 0]
                gap_b[p] = 2.0 * math.pi if g < 0.0 else g
            for r in range(2):
                if wanted[3 + r]:
                    # the line check at the fits' own radius reads their support, still in sub
                    same = r == 0 and wanted[1] and radii2[2, p] == radii2[1, p]
                    c_s = c_b if same else _within(queue, dist2, count, radii2[2 + r, p], sub)
                    spread[r, p] = _spread(i, sub, c_s, x, y, z, cov, vecs)


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
    kept: tuple | None = None
    grid_radius: float = math.nan


def _one_pass(cloud: PointCloud, frame_a=None, frame_b=None, *, jet: bool = False, normals_b: bool = False,
              spreads=(), screens=(0.0, 0.0), kept=None, grid_radius: float | None = None,
              chunk: int | None = None):
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
    screens : (float, float)
        The two frames' gaps are exact from these angles on (radians; below, an upper bound below
        them, :func:`.frames._widest_gap`); 0 measures every gap exactly.
    kept : namedtuple, optional
        A fits bundle an estimator reads (:attr:`curv.estimators._handover.NormalFits.new` of frame
        B's radii), filled with ``jet`` (:mod:`curv.estimators._handover`).
    grid_radius : float, optional
        Search the grid of :meth:`PointCloud.ball_grid` for balls of this radius instead of the
        one for the radii asked (another pass's, :attr:`_Pass.grid_radius`: a ball's points then
        come in that pass's order, so sums over them round the same).

    Returns
    -------
    _Pass
        Unit PCA normals (n, 3) (NaN under 3 points), gaps (n,), frame A's support sizes (n,)
        int64, jet normals (n, 3) (NaN without a fit), the spreads (n,) each, ``kept`` filled (None
        without the jet), and the grid's radius (``grid_radius``).
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
    # the grid's cells follow the median radius (PointCloud.ball_grid): a one-entry array asks for that one
    grid_radius = float(np.median(outer)) if grid_radius is None else float(grid_radius)
    cells, coords = cloud.ball_grid(np.array([grid_radius]))
    outer2 = radii2.max(axis=0)
    parts = max(1, min(threads(), n))
    queues = new_queues(n + 1, parts)
    dists = np.empty((parts, n + 1))
    subs = new_queues(n, parts)
    normal_a = np.empty((n, 3)) if wanted[0] else np.empty((1, 3))
    gap_a = np.empty(n) if wanted[0] else np.empty(1)
    count_a = np.empty(n, np.int64) if wanted[0] else np.empty(1, np.int64)
    normal_b = np.empty((n, 3)) if wanted[1] and normals_b else np.empty((1, 3))
    gap_b = np.empty(n) if wanted[1] else np.empty(1)
    fitted = np.empty((n, 3)) if wanted[2] else np.empty((1, 3))
    reason = np.empty(n if wanted[2] else 1, np.uint8)
    spread = np.empty((2, n if len(spreads) else 1))
    kept = kept if wanted[2] else None

    def run(lo: int, hi: int) -> None:
        launch(_pass_kernel, lo, hi, (cells, coords), (outer2, radii2, np.array(screens, np.float64)), wanted,
               DEFAULT_DEGREE, (queues, dists, subs), (normal_a, gap_a, count_a, normal_b, gap_b, fitted, reason, spread),
               kept)

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
                 spreads=tuple(spread[r] for r in range(len(spreads))), kept=kept, grid_radius=grid_radius)


@jit_parallel
def _spread_kernel(centres, lo, hi, radius, support, usable, scratch, spread):
    """``spread[p]`` for ``centres[lo:hi]`` (:func:`support_spread`) over the usable points of each
    ball; ``support`` and ``scratch`` as :func:`ball_walk_inputs` makes them."""
    adj_ptr, adj, x, y, z = support
    stamps, queues = scratch
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


def ball_walk_inputs(cloud: PointCloud, radii: np.ndarray, centres: np.ndarray | None):
    """What a kernel over the balls of some centres reads (:func:`curv.geometry.neighbourhood.ball_support`).

    Returns
    -------
    centres : (c,) int64
        ``centres``, or every point when None.
    radius : (n,) float64
        The balls' radii.
    support : tuple
        ``(adj_ptr, adj, x, y, z)``: the cloud's search grid and its coordinate columns.
    scratch : tuple
        ``(stamps, queues)``, (parts, n) int64 each, a row per thread slice.
    """
    n = cloud.n_points
    centres = all_centres(n, centres)
    adj_ptr, adj = expansion_adjacency(cloud, radii=radii)
    x, y, z = coordinate_columns(cloud)
    parts = max(1, min(threads(), centres.size))
    return (centres, np.ascontiguousarray(radii, dtype=np.float64), (adj_ptr, adj, x, y, z),
            (new_scratch(n, parts), new_queues(n, parts)))


def support_spread(cloud: PointCloud, radii: np.ndarray, centres: np.ndarray | None = None,
                   *, usable: np.ndarray | None = None, chunk: int | None = None):
    """(n,) float64: how far from a line or a curve each support is, a generator (yields the
    fraction done).

    :func:`.frames._spread` of the points of p's ball (with ``usable`` (n,) bool, only those it marks, and
    p): about sqrt(second / largest eigenvalue of the second moments about p) on a surface patch
    (1 for an even disc), 0 for points along a line or a plane curve through p; compared with
    :data:`.frames.MIN_SPREAD`. Rows outside ``centres`` are left unset. The pass that found the cloud's
    normals and borders measured the spreads at the default range (:func:`.normals._frames`): radii equal to
    those are answered from it when every point is usable.
    """
    n = cloud.n_points
    every = usable is None or bool(np.all(usable))
    for known, spread in cached_with_mesh(cloud, "spreads", list) if every else ():
        if _same_radii(known, radii):
            yield 1.0
            return spread
    if centres is None and every:
        # a line check a pass left out (owe_spreads) searches that pass's grid: the same sums
        grid = next((r for known, r in cached_with_mesh(cloud, "spread grids", list) if _same_radii(known, radii)), None)
        found = yield from _one_pass(cloud, spreads=(np.asarray(radii, np.float64),), grid_radius=grid, chunk=chunk)
        return found.spreads[0]
    # a region (or points left out): its own centres through the ball search, at the cost of the region
    usable = np.ones(n, np.bool_) if every else np.ascontiguousarray(usable, dtype=np.bool_)
    centres, radius, support, scratch = ball_walk_inputs(cloud, radii, centres)
    spread = np.empty(n)

    def run(lo: int, hi: int) -> None:
        launch(_spread_kernel, centres, lo, hi, radius, support, usable, scratch, spread)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return spread


def _same_radii(known: np.ndarray, radii) -> bool:
    return known.shape == np.shape(radii) and np.array_equal(known, radii)


def owe_spreads(cloud: PointCloud, spread_radii, grid_radius: float) -> None:
    """Note line checks at ``spread_radii`` that a pass over the grid of ``grid_radius``
    (:attr:`_Pass.grid_radius`) could have measured and left out: :func:`support_spread` measures
    them on demand over that grid, so their supports' points come in the order that pass would have
    read them, and the spreads are the same to the bit."""
    owed = cached_with_mesh(cloud, "spread grids", list)
    owed.extend((np.asarray(radii, np.float64), grid_radius) for radii in spread_radii)
    del owed[:-4]


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
