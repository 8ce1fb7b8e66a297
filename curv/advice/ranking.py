"""The ranking: the check's measured errors first, the table's predictions after, coverage above both.

The order is:

1. coverage: the candidates that leave at most :data:`~curv.advice.shares.VALID_SHARE_SLACK` more
   of the input invalid than the best-covering one come first (a call that leaves most of the
   input without a value is no answer, whatever its error);
2. within each group, the calls the check measured (:attr:`curv.advice.check.Measured.ok`), by
   their measured error, errors below :data:`ERROR_FLOOR` counted as the floor (they are rounding:
   every such call is as good as the others) and ties broken by the prediction;
3. then the calls not measured, by the table's prediction (or, without a table, in the order
   given);
4. the prior's choice (the first measured call of the covering group in the table's order, or
   the order given) stays first unless the check tells the measured best from it by more than
   its judge can be trusted to: unless on every copy the prior's choice measured more than
   ``band`` times the best's error. Where the prior is the table's prediction for this very
   input (a mesh), ``band`` is :data:`JUDGE_BIAS`, how far the smooth twin itself sets two calls'
   measured errors apart from their true ratio; where it is only an order (a point cloud: no
   table), ``band`` is 1 and the copies' own spread is the only doubt.

A measured call that covers the input as well is *within noise* of the recommendation when on at
least one noisy copy its median error was at or below the recommendation's: the copies do not tell
them apart.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

__all__ = ["rank_candidates", "ERROR_FLOOR", "JUDGE_BIAS"]

ERROR_FLOOR = 1e-6
"""Measured errors below this count as this (the advisor table's ``erel_floor``): rounding."""

JUDGE_BIAS = 3.0
"""How many times the table's first choice's measured error must exceed the measured best's, on
every copy, for the check to override the table (meshes). The check's judge, the smooth twin, is
biased per call: on the held-out meshes of seeds 23000 and 24000 (docs/ADVISOR.md, "The judge's
bias against the table") two calls of one short list were measured a median 1.17x, a 90th percentile
2.0x and at most 7x off their true ratio, and where the check disagreed with the table it was
right on 6 meshes and wrong on 11, with no separation telling the two apart. Above that 90th
percentile, and at the advice's worst-regret bound (3): the check overrides only a first choice
it measured worse than any advice may be; on those meshes it never did (the table's choice)."""


def _floored(x: float) -> float:
    return max(float(x), ERROR_FLOOR) if math.isfinite(x) else math.inf


def rank_candidates(candidates: list, measured: dict | None, slack: float, *,
                    judge_bias: float = JUDGE_BIAS) -> list:
    """The candidates in the advisor's order, each with its measure and its within-noise flag.

    Parameters
    ----------
    candidates : list of Candidate
        In the table's order (or any prior order where no table applies).
    measured : dict or None
        :attr:`Candidate.key` -> :class:`curv.advice.check.Measured` of the checked calls.
    slack : float
        Coverage slack (:data:`curv.advice.shares.VALID_SHARE_SLACK`).
    judge_bias : float
        The band of rule 4 where the candidates carry the table's predictions (``inf``: the table's
        first choice always kept; 0: the measured best always first).

    Returns
    -------
    list of Candidate
        With :attr:`~Candidate.measured` and :attr:`~Candidate.within_noise` set.
    """
    measured = measured or {}
    cands = [dataclasses.replace(c, measured=measured.get(c.key)) for c in candidates]
    if not cands:
        return []
    top = max(c.valid_share for c in cands)
    prior = {id(c): i for i, c in enumerate(cands)}

    def key(c):
        m = c.measured
        checked = m is not None and m.ok
        predicted = c.expected_erel if math.isfinite(c.expected_erel) else math.inf
        return (c.valid_share < top - slack, not checked, _floored(m.erel) if checked else 0.0, predicted,
                prior[id(c)])

    ordered = sorted(cands, key=key)
    first = next((c for c in cands if c.valid_share >= top - slack and c.measured is not None and c.measured.ok), None)
    band = judge_bias if first is not None and math.isfinite(first.expected_erel) else 1.0
    if first is not None and first is not ordered[0] and not _separated(ordered[0].measured, first.measured, band):
        ordered.remove(first)
        ordered.insert(0, first)
    best = ordered[0].measured
    if best is None or not best.ok:
        return ordered
    return [ordered[0]] + [dataclasses.replace(c, within_noise=c.valid_share >= top - slack
                                               and _within_noise(best, c.measured)) for c in ordered[1:]]


def _separated(best, other, band: float) -> bool:
    """Whether ``other`` measured more than ``band`` times ``best``'s error on every copy (both floored);
    False where no copy measured both (nothing tells them apart)."""
    a = np.array([_floored(x) for x in best.copies])
    b = np.array([_floored(x) for x in other.copies])
    ok = np.isfinite(a) & np.isfinite(b)
    return bool(ok.any() and np.all(b[ok] > band * a[ok]))


def _within_noise(best, other) -> bool:
    """Whether ``other`` did as well as ``best`` on at least one copy (both floored)."""
    if other is None or not other.ok:
        return False
    a = np.array([_floored(x) for x in best.copies])
    b = np.array([_floored(x) for x in other.copies])
    ok = np.isfinite(a) & np.isfinite(b)
    return bool(np.any(b[ok] <= a[ok]))
