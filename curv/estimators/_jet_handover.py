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

So the pass keeps, per point (:func:`keep_fit`), in a :class:`JetFits` bundle: a state (the fit's
reason, or that it stopped before its solve: :data:`NO_FIT` without a reference, :data:`OFF_NORMAL`
at the reference test) and a row of :data:`ROW_WIDTH` floats: the support's PCA normal, ``e1``, the
coefficients of the first and second order turned to the side of that PCA normal, and the scale
``h``. The estimator (:func:`handed_fit`, through :func:`curv.estimators._handover.iter_handed`)
turns them to its reference's side and finishes as a fit would
(:func:`~curv.estimators._jet_fit.jet_principal`); the points the pass did not fit to the end, or
whose radius is not the pass's, are fitted as before. The result is the fit's over the pass's
support, whose points the pass met in its own grid's order: the sums, and so the last bits, follow
that order (docs/BENCHMARKS.md says by how much).

What matches (:data:`curv.estimators.jet.JET_FITS`): the estimator's degree and weights equal the
pass's, the fixed width, no standard errors (they read the fit's normal matrix, which is not kept),
and per point the same radius. The normals the estimator is given need not be the pass's: each is
tested as a fit would test it.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..core.jit import jit
from ..core.validity import DEGENERATE, OK, SINGULAR, TOO_FEW
from ._handover import Handover, register_handover
from ._jet_fit import MIN_NORMAL_COSINE, V_SIGNS, jet_principal, jet_scratch

__all__ = ["ROW_WIDTH", "NO_FIT", "OFF_NORMAL", "BYTES_PER_POINT", "JetFits", "new_jet_fits", "keep_fit",
           "handed_fit"]

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

JetFits = namedtuple("JetFits", ["radii", "state", "rows"])
"""The jet fits a pass keeps: the radius of every point's ball (n,), the states (n,) uint8 and the
rows (n, :data:`ROW_WIDTH`)."""


def new_jet_fits(radii: np.ndarray) -> JetFits:
    """An unfilled :class:`JetFits` for a pass over balls of these radii (n,)."""
    n = radii.shape[0]
    return JetFits(np.asarray(radii, np.float64), np.empty(n, np.uint8), np.empty((n, ROW_WIDTH)))


@jit
def keep_fit(fits, p, i, fit, support, coords, fitted):
    """Keep point p's jet fit (``fit = (code, h, referenced, scratch)``: :func:`~curv.estimators._jet_fit.fit_jet`'s
    code and h, whether its reference normal was finite, its scratch) in row p of ``fits``
    (:class:`JetFits`; :class:`~curv.estimators._handover.Handover`'s ``keep``). The caller set the
    scratch's smallest eigenvalue (``evec[3, 0]``) to NaN before the fit, so that a fit stopped
    before its PCA shows it."""
    code, h, referenced, scratch = fit
    state, rows = fits.state, fits.rows
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
def handed_fit(fits, p, normals, scratch, out):
    """Row p of ``out`` (:class:`~curv.estimators._principal.Rows`, as the jet's fit with the
    reference ``normals[p]`` would write it) from ``fits`` (:class:`JetFits`): returns False when
    only a fit can tell (nothing written).

    Not inlined, and the reason written here: written in the parallel loop itself, numba 0.68 lost
    the write (as :func:`curv.estimators.jet._jet_fit_at` notes)."""
    code = _handed_reason(p, (fits.state, fits.rows), normals, scratch, out)
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


@jit
def _scratch(fits):
    return jet_scratch()


register_handover(JetFits, Handover(keep_fit, handed_fit, _scratch))
