"""The jet normals' fits handed to the jet estimator: one least-squares fit per point instead of two.

A point cloud's jet normals (:mod:`curv.point_normals`, the one pass) fit the degree-2 jet over each
point's ball at the normals' range with uniform weights. ``curv.estimate(cloud, "jet", k)`` at that
range with those options solves the same least-squares problem over the same ball again. Only the
reference normal differs: the pass's is frame A's unoriented PCA normal, the estimator's the
oriented normal (or any given normals). The reference decides three things of a fit
(:func:`~curv.estimators._jet_fit.fit_jet`), each answered here again from what the pass kept:

- whether there is one (a NaN reference is ``DEGENERATE``);
- the ``DEGENERATE`` test of the support's PCA normal against it
  (:data:`~curv.estimators._jet_fit.MIN_NORMAL_COSINE`), asked with the PCA normal the pass kept;
- the side the frame's height axis ``e3`` takes (and with it ``e2 = e3 x e1``). A frame turned over
  gives the same fit with the signs :data:`~curv.estimators._jet_fit.V_SIGNS` and the heights' (IEEE
  rounding is symmetric in sign, so to the bit), and the same condition estimate
  (:func:`~curv.core.small_linalg.reciprocal_condition`), so ``SINGULAR`` holds on either side.

So the pass keeps, per point (:func:`keep_fit`): a state (the fit's reason, or that it stopped before
its solve: :data:`NO_FIT` without a reference, :data:`OFF_NORMAL` at the reference test) and a row
of :data:`ROW_WIDTH` floats: the support's PCA normal, ``e1``, the coefficients of the first and
second order turned to the side of that PCA normal, and the scale ``h``. The estimator
(:func:`iter_handed`) turns them to its reference's side and finishes as a fit would
(:func:`~curv.estimators._jet_fit.jet_principal`); the points the pass did not fit to the end, or
whose radius is not the pass's, are fitted as before. The result is the fit's over the pass's
support, whose points the pass met in its own grid's order: the sums, and so the last bits, follow
that order (docs/BENCHMARKS.md says by how much).

What matches (:func:`kept_fits`): the estimator's degree and weights equal the pass's, the fixed
width, no standard errors (they read the fit's normal matrix, which is not kept), and per point the
same radius. The normals the estimator is given need not be the pass's: each is tested as a fit
would test it.
"""

from __future__ import annotations

import math
import weakref
from collections import namedtuple

import numpy as np

from ..core.jit import iter_chunks, jit, jit_parallel, launch, prange, slice_bounds, threads
from ..core.validity import DEGENERATE, OK, SINGULAR, TOO_FEW
from ._jet_fit import MIN_NORMAL_COSINE, V_SIGNS, jet_principal, jet_scratch

__all__ = ["ROW_WIDTH", "NO_FIT", "OFF_NORMAL", "BYTES_PER_POINT", "new_kept", "keep_fit", "keep_for", "kept_fits",
           "iter_handed"]

ROW_WIDTH = 12
"""Floats kept per point: the support's PCA normal (3, the eigen-solve's sign), ``e1`` (3), the
coefficients ``J10, J01, J20, J11, J02`` in the frame whose ``e3`` is that PCA normal (5), ``h`` (1)."""

NO_FIT = np.uint8(250)
"""State of a point the pass did not fit: its reference normal was missing (a refit decides)."""

OFF_NORMAL = np.uint8(251)
"""State of a point whose PCA normal the pass's reference did not accept: no solve (a reference
that accepts it refits)."""

BYTES_PER_POINT = 8 * ROW_WIDTH + 1 + 8
"""What the kept fits hold per point: the rows, the state and the pass's radius."""

Kept = namedtuple("Kept", ["radii", "state", "rows", "degree", "smooth"])
"""The fits a pass kept: the radius of every point's ball (n,), the states (n,) uint8, the rows
(n, :data:`ROW_WIDTH`), and the fit's options."""

_KEPT: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def new_kept(n: int) -> tuple:
    """``(state (n,) uint8, rows (n, ROW_WIDTH) float64)`` for a pass to fill (:func:`keep_fit`)."""
    return np.empty(n, np.uint8), np.empty((n, ROW_WIDTH))


@jit
def keep_fit(code, h, p, referenced, scratch, kept):
    """Keep point p's fit (:func:`~curv.estimators._jet_fit.fit_jet`'s ``code`` and ``h``, its
    ``scratch``) in row p of ``kept = (state, rows)``. ``referenced``: the fit's reference normal
    was finite. The caller set ``scratch``'s smallest eigenvalue (``evec[3, 0]``) to NaN before the
    fit, so that a fit stopped before its PCA shows it."""
    state, rows = kept
    _, vec, _, frame, evec = scratch
    if code == TOO_FEW or code == OK or code == SINGULAR:
        st = code
    elif not math.isfinite(evec[3, 0]):
        # stopped before its PCA: a support of one place (any reference), or no reference
        st = DEGENERATE if referenced else NO_FIT
    else:
        st = OFF_NORMAL
    state[p] = st
    if st == OK or st == SINGULAR or st == OFF_NORMAL:
        for a in range(3):
            rows[p, a] = evec[a, 0]
    if st == OK:
        side = 1.0 if frame[2, 0] * evec[0, 0] + frame[2, 1] * evec[1, 0] + frame[2, 2] * evec[2, 0] >= 0.0 else -1.0
        for a in range(3):
            rows[p, 3 + a] = frame[0, a]
        for k in range(1, 6):
            rows[p, 5 + k] = vec[1, k] if side > 0.0 else -V_SIGNS[k] * vec[1, k]
        rows[p, 11] = h


@jit
def handed_fit(p, kept, normals, scratch, out):
    """Row p of ``out`` (:class:`~curv.estimators._principal.Rows`, as the jet's fit with the
    reference ``normals[p]`` would write it) from ``kept = (state, rows)``: returns False when only
    a fit can tell (nothing written).

    Not inlined, and the reason written here: written in the parallel loop itself, numba 0.68 lost
    the write (as :func:`curv.estimators.jet._jet_fit_at` notes)."""
    code = _handed_reason(p, kept, normals, scratch, out)
    if code == NO_FIT:
        return False
    out.reason[p] = code
    return True


@jit
def _handed_reason(p, kept, normals, scratch, out):
    """:func:`handed_fit`'s reason, or :data:`NO_FIT`; the checks in :func:`~curv.estimators._jet_fit.fit_jet`'s order."""
    state, rows = kept
    st = state[p]
    if st == TOO_FEW:
        return TOO_FEW
    rx, ry, rz = normals[p, 0], normals[p, 1], normals[p, 2]
    if not (math.isfinite(rx) and math.isfinite(ry) and math.isfinite(rz)):
        return DEGENERATE
    if st == NO_FIT or st == DEGENERATE:
        return st
    along = rows[p, 0] * rx + rows[p, 1] * ry + rows[p, 2] * rz
    if not abs(along) >= MIN_NORMAL_COSINE * math.sqrt(rx * rx + ry * ry + rz * rz):
        return DEGENERATE
    if st == OFF_NORMAL:
        return NO_FIT
    if st == SINGULAR:
        return SINGULAR
    _, vec, _, frame, _ = scratch
    # the frame a fit turned towards this reference builds (fit_jet), and its coefficients
    side = 1.0 if along >= 0.0 else -1.0
    for a in range(3):
        frame[2, a] = side * rows[p, a]
        frame[0, a] = rows[p, 3 + a]
    frame[1, 0] = frame[2, 1] * frame[0, 2] - frame[2, 2] * frame[0, 1]
    frame[1, 1] = frame[2, 2] * frame[0, 0] - frame[2, 0] * frame[0, 2]
    frame[1, 2] = frame[2, 0] * frame[0, 1] - frame[2, 1] * frame[0, 0]
    for k in range(1, 6):
        vec[1, k] = rows[p, 5 + k] if side > 0.0 else -V_SIGNS[k] * rows[p, 5 + k]
    return jet_principal(scratch, rows[p, 11], normals, out, p)


@jit_parallel
def _handed_kernel(centres, lo, hi, radii, kept, normals, out, refit, parts):
    """Rows ``centres[lo:hi]`` of ``out`` from ``kept = (radii, state, rows)`` where the radius is
    the pass's and it fitted to the end; ``refit[p]`` True where a fit must tell."""
    fit_radii, state, rows = kept
    for t in prange(parts):
        scratch = jet_scratch()
        start, stop = slice_bounds(lo, hi, t, parts)
        for c in range(start, stop):
            p = centres[c]
            refit[p] = not (radii[p] == fit_radii[p] and handed_fit(p, (state, rows), normals, scratch, out))


def keep_for(cloud, kept: Kept) -> None:
    """Keep a pass's fits with ``cloud`` (the latest pass's; they go with the cloud)."""
    _KEPT[cloud] = kept


def kept_fits(cloud, degree: int, smooth: bool) -> Kept | None:
    """The fits a pass kept with ``cloud`` when they are the fits of these options (the owner of the
    match: degree and weights; the caller asks only for a fixed width without standard errors), else None."""
    try:
        kept = _KEPT.get(cloud)
    except TypeError:  # an input that cannot be referenced weakly keeps nothing
        return None
    if kept is None or kept.degree != degree or kept.smooth != smooth:
        return None
    return kept


def iter_handed(kept: Kept, normals: np.ndarray, radii: np.ndarray, centres: np.ndarray, out, *,
                chunk: int | None = None):
    """Rows ``centres`` of ``out`` from the kept fits, a generator (yields the fraction done).

    Parameters
    ----------
    kept : Kept
    normals : (n, 3) float64
        The estimator's reference normals (any layout).
    radii : (n,) float64
        The estimator's radii.
    centres : (c,) int64
    out : Rows

    Returns
    -------
    (r,) int64
        The centres still to fit (their rows unset), in the order of ``centres``.
    """
    refit = np.zeros(kept.radii.shape[0], np.bool_)
    parts = max(1, min(threads(), centres.size))
    state = (np.asarray(kept.radii, np.float64), kept.state, kept.rows)
    radius = np.asarray(radii, np.float64)
    normals = np.asarray(normals, np.float64)

    def run(lo: int, hi: int) -> None:
        launch(_handed_kernel, centres, lo, hi, radius, state, normals, out, refit, parts)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return centres[refit[centres]]
