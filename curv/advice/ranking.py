"""The ranking: coverage first; on a mesh the table's prediction weighed against the realized error,
on a point cloud the check's measured error.

On a mesh (the candidates carry the table's predictions) the order is:

1. coverage, as below;
2. within the covering group, the calls with a realized score (:func:`realized_score`: each call's
   error on the input itself at the check's centres, against the smooth twin's curvature there), by
   ``(1 - w) log predicted + w log realized`` with ``w`` = :data:`REALIZED_WEIGHT`, ties in the
   table's order; where no covering call has one (``check=False``, every call failed on the input),
   the table's first covering call leads;
3. then the rest in the order below (rules 2 and 3), without its rule 4: the check's copies only
   order the calls the realized score did not score, and nothing vetoes the weighed first.

Why: replayed on the 288 held-out meshes of seeds 23000-34000 (docs/ADVISOR.md, "Where the p90 is
lost"), this rule had regret p90 1.234, worst 3.02, mean 1.083, against the table-first rule's
1.312 / 3.02 / 1.115; then on 96 fresh meshes (seeds 35000-38000, "The realized score shipped")
p90 1.126, worst 1.93, against the table-first rule's 1.456 / 3.34 on the same checks. The realized
score is the one judge that sees the input's own noise draw (the copies draw it afresh).

On a point cloud (no table), and on a mesh with ``realized_weight=None`` (the table-first rule shipped
before), the order is:

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

__all__ = ["rank_candidates", "realized_score", "ranked_by", "ERROR_FLOOR", "JUDGE_BIAS", "REALIZED_WEIGHT"]

ERROR_FLOOR = 1e-6
"""Measured errors below this count as this (the advisor table's ``erel_floor``): rounding."""

JUDGE_BIAS = 3.0
"""The table-first rule (``realized_weight=None``; the mesh rule before the realized score): how many
times the table's first choice's measured error must exceed the measured best's, on every copy, for
the check to override the table. The check's judge, the smooth twin, is
biased per call: on the held-out meshes of seeds 23000 and 24000 (docs/ADVISOR.md, "The judge's
bias against the table") two calls of one short list were measured a median 1.17x, a 90th percentile
2.0x and at most 7x off their true ratio, and where the check disagreed with the table it was
right on 6 meshes and wrong on 11, with no separation telling the two apart. Above that 90th
percentile, and at the advice's worst-regret bound (3): the check overrides only a first choice
it measured worse than any advice may be; on those meshes it never did (the table's choice)."""


REALIZED_WEIGHT = 0.5
"""The realized score's weight against the table's prediction in a mesh's ranking (a weighted geometric
mean of the two errors). 0.5 is the replayed candidate of docs/ADVISOR.md (weights 0.5, 0.7 and 1
were replayed: 1, the realized score alone, had a worst regret of 10.7; 0.7 a worst of 3.5 over the
288 meshes)."""


def realized_score(measured) -> float:
    """A call's realized score: the geometric mean of its positive realized medians (one per centre
    set, :attr:`curv.advice.check.Measured.realized`), each floored at :data:`ERROR_FLOOR`; NaN where
    it has none (not measured, a point cloud, no value on the input at any centre set)."""
    if measured is None:
        return math.nan
    v = np.asarray([x for x in measured.realized if math.isfinite(x) and x > 0], float)
    return float(np.exp(np.mean(np.log(np.maximum(v, ERROR_FLOOR))))) if v.size else math.nan


def _weighed(c, weight: float) -> float:
    """The weighted log error of rule 2 (mesh): predicted and realized, both floored."""
    return (1 - weight) * math.log(max(c.expected_erel, ERROR_FLOOR)) + weight * math.log(realized_score(c.measured))


def _floored(x: float) -> float:
    return max(float(x), ERROR_FLOOR) if math.isfinite(x) else math.inf


def rank_candidates(candidates: list, measured: dict | None, slack: float, *,
                    judge_bias: float = JUDGE_BIAS, realized_weight: float | None = REALIZED_WEIGHT) -> list:
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
        The band of rule 4 where the candidates carry the table's predictions and ``realized_weight``
        is None (``inf``: the table's first choice always kept; 0: the measured best always first).
    realized_weight : float or None
        The realized score's weight in a mesh's ranking; None: the table-first rule (rule 4 with
        ``judge_bias``) instead.

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
    covering = [c for c in cands if c.valid_share >= top - slack]
    if realized_weight is not None and math.isfinite(covering[0].expected_erel):
        scored = [c for c in covering if math.isfinite(realized_score(c.measured))]
        lead = sorted(scored, key=lambda c: (_weighed(c, realized_weight), prior[id(c)])) or covering[:1]
        ordered = lead + [c for c in ordered if all(c is not x for x in lead)]
    else:
        _table_first(ordered, covering, judge_bias)
    best = ordered[0].measured
    if best is None or not best.ok:
        return ordered
    return [ordered[0]] + [dataclasses.replace(c, within_noise=c.valid_share >= top - slack
                                               and _within_noise(best, c.measured)) for c in ordered[1:]]


def _table_first(ordered: list, covering: list, judge_bias: float) -> None:
    """Rule 4 in place: the prior's first measured covering call moved first unless the measured best is
    told from it by more than the band."""
    first = next((c for c in covering if c.measured is not None and c.measured.ok), None)
    band = judge_bias if first is not None and math.isfinite(first.expected_erel) else 1.0
    if first is not None and first is not ordered[0] and not _separated(ordered[0].measured, first.measured, band):
        ordered.remove(first)
        ordered.insert(0, first)


def ranked_by(ranking: list, realized_weight: float | None = REALIZED_WEIGHT) -> str:
    """What decided the first of ``ranking`` (:func:`rank_candidates`' result), in words for a person."""
    best = ranking[0] if ranking else None
    if best is None:
        return ""
    if not math.isfinite(best.expected_erel):
        measured = best.measured is not None and best.measured.ok
        return ("the error measured on noisy copies of the smooth twin (the prior order's first kept within noise)"
                if measured else "the prior order")
    if realized_weight is not None:
        if math.isfinite(realized_score(best.measured)):
            return (f"the table's predicted error and the error on the input itself against its smooth twin "
                    f"(realized), a geometric mean weighing the realized {realized_weight:g}")
        return "the table's prediction (no call was scored on the input)"
    return f"the table's prediction, unless the check measured its first more than {JUDGE_BIAS:g}x the best"


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
