"""From an estimator's raw rows to a :class:`~curv.core.result.Curvature`: the validity policy and the finish.

:func:`finish` applies the input's flags (:class:`curv.estimate_setup.Flags`) in the precedence
:mod:`curv.core.validity` owns, settles each row (:func:`settle`: non-finite values SINGULAR,
k1 >= k2, right-handed directions), smooths the values when asked, NaN-fills the invalid rows and
scatters a region's rows into full-length arrays. :func:`radius_note` says when a ``radius=`` left
most rows without an estimate.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .core.filled import filled
from .core.jit import jit_parallel, launch, prange
from .core.support import support_of
from .core.ranges import unit_lengths
from .core.result import Curvature
from .core.validity import OK, PRECEDENCE, SINGULAR, TOO_FEW, Reason, mark_ok_rows
from .estimate_setup import Smoothing
from .geometry.smoothing import smooth_values
from .locality import rows_back

__all__ = ["finish", "settle", "radius_note", "SHORT_SHARE"]

SHORT_SHARE = 0.5
"""A ``radius=`` estimate is said to fail when more than this share of its rows have too few
neighbours in the ball or a singular fit (:func:`radius_note`)."""

_SPACING_SAMPLE = 100_000
"""The median spacing of :func:`radius_note` is taken over at most about this many evenly spread vertices."""


def finish(mesh, spec, rng, radii, raw, flags, fused, used_normals, usable, centres, feats, on_crease, smooth,
           smooth_iterations, smooth_strength, standard_errors, normals_label, options, twin, t0):
    """The :class:`Curvature` of one range from the estimator's raw result: the validity rules,
    the settling pass, smoothing of the values, a region's full-length rows (a generator, as the
    support checks of a point cloud are)."""
    def at(flags: np.ndarray) -> np.ndarray:
        """The rows of a per-vertex array that this call estimates."""
        return flags if centres is None else flags[centres]

    found = {}
    for mask_of in flags.support_marks:
        # checks of the supports themselves (points: a support along a curve, or a few steps of the
        # coordinates' grid wide), on the estimated rows; the info counts each check's points
        mask, code, name = yield from mask_of(radii, centres, usable)
        flags = flags.marked(mask, code)
        found[name] = int(at(mask).sum())
    if fused:
        used_normals = raw.normals

    k1, k2, d1, d2, reason = at(raw.k1), at(raw.k2), at(raw.d1), at(raw.d2), at(raw.reason).copy()
    computed = standard_errors and raw.k1_se is not None and smooth is Smoothing.NONE
    k1_se, k2_se = _standard_errors(raw if computed else None, at, k1.shape[0])
    # root causes, whatever the estimator saw (no face or no other point at all; a normal whose
    # orientation was left undecided): later codes win
    for mask, code in flags.forced:
        reason[at(mask)] = code
    isolated = at(flags.isolated)
    if on_crease:
        # the smooth curvature is undefined on a crease; a large value there is the error to avoid
        reason[at(feats.vertices) & ~isolated] = Reason.FEATURE
    # the input's flags mark the rows the estimator left OK, in the one precedence (curv.core.validity)
    marks = np.zeros((len(PRECEDENCE), reason.size), bool)
    for mask, code in flags.marks:
        marks[PRECEDENCE.index(code)] |= at(mask)
    launch(mark_ok_rows, reason, marks)
    # non-finite values are SINGULAR; k1 >= k2 (the estimators order them already: the rare rows they
    # did not are repaired in place, the arrays are this call's own); (d1, d2, N) right-handed so
    # results are reproducible. One parallel pass over the rows.
    launch(settle, k1, k2, d1, d2, k1_se, k2_se, used_normals, _NO_ROWS if centres is None else centres, reason)
    if smooth is Smoothing.VALUES:
        ok = reason == Reason.OK
        k1, k2 = smooth_values(mesh, np.stack([k1, k2], axis=1), ok,
                               iterations=smooth_iterations, strength=smooth_strength).T
        swap = k2 > k1
        k1, k2 = np.where(swap, k2, k1), np.where(swap, k1, k2)
        d1, d2 = np.where(swap[:, None], d2, d1), np.where(swap[:, None], -d1, d2)
    valid = reason == Reason.OK
    for arr in (k1, k2, k1_se, k2_se) if computed else (k1, k2):
        arr[~valid] = np.nan
    d1[~valid] = np.nan
    d2[~valid] = np.nan
    if centres is not None:
        k1, k2, d1, d2, reason, valid = _full_length(mesh.n_vertices, centres, k1, k2, d1, d2, reason, valid)
        k1_se, k2_se = (_scatter(mesh.n_vertices, centres, se) for se in (k1_se, k2_se))
    result = Curvature(
        k1=k1, k2=k2, d1=d1, d2=d2, normals=used_normals, valid=valid, reason=reason.astype(np.uint8, copy=False),
        method=spec.name, range=rng.value, k1_se=k1_se, k2_se=k2_se,
        info={"seconds": time.perf_counter() - t0, "smooth": smooth.value, "range_label": rng.label,
              "normals": normals_label, **options,
              "radius": rng.radius,
              "smooth_iterations": smooth_iterations if smooth is not Smoothing.NONE else 0,
              "features": None if feats is None else feats.label,
              "feature_edges": 0 if feats is None else feats.count,
              "region": mesh.n_vertices if centres is None else int(centres.size), **flags.info, **found,
              **({"standard_errors": True} if computed else {})},
    )
    return result if twin is None else rows_back(result, twin[1])


def radius_note(mesh, radius: float, reason: np.ndarray, centres: np.ndarray | None = None) -> str | None:
    """What to tell a caller whose ``radius=`` is below the input's median spacing, or left more than
    :data:`SHORT_SHARE` of the estimated rows with too few neighbours or a singular fit; None otherwise.

    Parameters
    ----------
    mesh : Mesh or PointCloud
        The input; its spacing is :func:`curv.core.ranges.unit_lengths` (the longest 1-ring edge,
        a point's distance to its 6th nearest), the median of an even sample.
    radius : float
        The ball radius the call was given.
    reason : (n,) uint8
        The result's reason codes.
    centres : (c,) int64, optional
        The rows estimated (a region); default all.

    Returns
    -------
    str or None
        One sentence naming the radius, the median spacing, the share without an estimate and a
        radius or range to try.
    """
    unit = unit_lengths(mesh)
    sample = unit[:: max(1, unit.size // _SPACING_SAMPLE)]
    sample = sample[np.isfinite(sample) & (sample > 0)]
    if not sample.size:
        return None
    spacing = float(np.median(sample))
    rows = np.asarray(reason) if centres is None else np.asarray(reason)[centres]
    short = float(np.isin(rows, (TOO_FEW, SINGULAR)).mean()) if rows.size else 0.0
    if radius >= spacing and short <= SHORT_SHARE:
        return None
    support = support_of(mesh)
    items, unit_words = support.items, support.unit_words
    if radius < spacing:
        head = f"radius={radius:g} is below the median spacing {spacing:.4g} ({unit_words})"
    else:
        head = f"radius={radius:g} is only {radius / spacing:.2g} times the median spacing {spacing:.4g} ({unit_words})"
    return (f"{head}: {100 * short:.0f} % of the {items} have too few neighbours or a singular fit (NaN); "
            f"try radius={2 * spacing:.3g} (2 spacings) or range=2")


def _standard_errors(raw, at, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """This call's rows of the fit's standard errors (copies); NaN, at the cost of the rows later
    written (:func:`curv.core.filled.filled`), when none were computed (``raw`` None: not asked, an
    estimator without a fit, or a smoothing variant: smoothing correlates the noise of neighbouring
    vertices, before the fit with ``mesh``, after it with ``values``, which the residual model
    assumes independent)."""
    if raw is None:
        return filled(rows, np.nan), filled(rows, np.nan)
    return at(raw.k1_se).copy(), at(raw.k2_se).copy()


def _scatter(n: int, centres: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(n,) NaN with ``values`` at ``centres``, at the cost of the centres (:func:`curv.core.filled.filled`)."""
    out = filled(n, np.nan)
    out[centres] = values
    return out


def _full_length(n: int, centres: np.ndarray, k1, k2, d1, d2, reason, valid):
    """Scatter a region's rows into full-length outputs: NaN and ``NOT_COMPUTED`` elsewhere.

    At the cost of the region's rows, not of n (:func:`curv.core.filled.filled`).
    """
    out_k1, out_k2 = filled(n, np.nan), filled(n, np.nan)
    out_d1, out_d2 = filled((n, 3), np.nan), filled((n, 3), np.nan)
    out_reason = filled(n, Reason.NOT_COMPUTED, np.uint8)
    out_valid = np.zeros(n, bool)
    out_k1[centres], out_k2[centres], out_d1[centres], out_d2[centres] = k1, k2, d1, d2
    out_reason[centres], out_valid[centres] = reason, valid
    return out_k1, out_k2, out_d1, out_d2, out_reason, out_valid


_NO_ROWS = np.empty(0, np.int64)

@jit_parallel
def settle(k1, k2, d1, d2, k1_se, k2_se, normals, rows, reason):
    """In place, per row i of this call's outputs: ``reason`` SINGULAR where it is OK but k1 or k2 is not
    finite; k1 >= k2 (k1, k2, d1, d2 and the standard errors swapped where k2 > k1); d2 negated where
    ``(d1 x d2) . N < 0`` (N the row's normal, NaN: left as it is).

    Parameters
    ----------
    k1, k2, k1_se, k2_se : (c,) float64
    d1, d2 : (c, 3) float64
    normals : (n, 3) float64
        Row i's normal is ``normals[rows[i]]``, or ``normals[i]`` when ``rows`` is empty.
    rows : (c,) or (0,) int64
    reason : (c,) uint8
    """
    for i in prange(k1.size):
        if reason[i] == OK and not (math.isfinite(k1[i]) and math.isfinite(k2[i])):
            reason[i] = SINGULAR
        if k2[i] > k1[i]:
            k1[i], k2[i] = k2[i], k1[i]
            k1_se[i], k2_se[i] = k2_se[i], k1_se[i]
            for j in range(3):
                d1[i, j], d2[i, j] = d2[i, j], d1[i, j]
        p = np.int64(i)
        if rows.size:
            p = np.int64(rows[i])
        a0, a1, a2 = d1[i, 0], d1[i, 1], d1[i, 2]
        b0, b1, b2 = d2[i, 0], d2[i, 1], d2[i, 2]
        c0, c1, c2 = normals[p, 0], normals[p, 1], normals[p, 2]
        if (a1 * b2 - a2 * b1) * c0 + (a2 * b0 - a0 * b2) * c1 + (a0 * b1 - a1 * b0) * c2 < 0:
            d2[i, 0], d2[i, 1], d2[i, 2] = -b0, -b1, -b2
