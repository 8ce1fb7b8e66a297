"""Reductions of the results table that the report, Table 1 and the figures share.

Every number is a mean over the rows of a setting, i.e. over samples and whatever parameters the
caller leaves open (the grid is balanced, so this averages the open parameters with equal weight,
as the paper does). The default measure is the paper's RMS of ``e_rel`` over vertices with
``e_rel < 1``; ``median_erel`` is the robust companion.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from .cube import AXES, Cube, unit_weights
from .protocol import Smoothing, StudySettings, Variant
from .table import Table

__all__ = ["Analysis", "MEASURES", "table1", "table1_markdown", "PAPER_TABLE1"]

MEASURES = {
    "rms_erel": "RMS of e_rel over vertices with e_rel < 1",
    "median_erel": "median of e_rel over all evaluated vertices",
    "excluded_share": "share of evaluated vertices with e_rel >= 1",
    "nrms_h": "RMS error of H / RMS of (|k1|+|k2|)/2",
    "nrms_k": "RMS error of K / RMS of ((|k1|+|k2|)/2)²",
}

PAPER_TABLE1: dict[int, dict[str, tuple[float, float]]] = {
    1: {"csm": (86, 111), "qs": (479, 828), "nc": (466, 810), "meyer": (343, 550)},
    2: {"csm": (110, 129), "qs": (207, 486), "nc": (212, 516), "an": (374, 820), "mru": (352, 526),
        "ru": (313, 476)},
    3: {"csm": (107, 124), "qs": (134, 214), "nc": (135, 221), "an": (279, 691), "mru": (127, 176)},
}
"""The paper's Table 1: error at 14° and 25° irregularity in % of the 0° error, no noise."""


@dataclass
class Analysis:
    """Mean errors of the variants of a results table.

    Parameters
    ----------
    table : Table
        Results rows (one per task and variant).
    settings : StudySettings
        The grid the table belongs to.
    measure : str
        Column averaged by :meth:`err`, one of :data:`MEASURES`.
    weights : (units,) float64, optional
        Weight of each random surface draw (see :class:`~curv.study.cube.Cube`): a bootstrap
        resample's counts, or 0/1 to use some samples only. Default: every draw once.
    paper_only : bool
        Only the estimators of the paper (``EstimatorSpec.in_paper``): the claims are about them.
    cube : Cube, optional
        The table as dense arrays; built on first use and shared by :meth:`resampled`,
        :meth:`paper` and :meth:`first_samples`.
    """

    table: Table
    settings: StudySettings
    measure: str = "rms_erel"
    weights: np.ndarray | None = None
    paper_only: bool = False
    cube: Cube | None = None

    def __post_init__(self):
        if self.cube is None:
            self.cube = Cube(self.table)

    @cached_property
    def variants(self) -> tuple[Variant, ...]:
        """The study's variants that have rows in the table, in registry order."""
        present = set(self.cube.variants)
        keep = _paper_methods() if self.paper_only else None
        return tuple(v for v in self.settings.variants()
                     if v.id in present and (keep is None or v.method in keep))

    @property
    def plain(self) -> tuple[Variant, ...]:
        """Variants without smoothing."""
        return tuple(v for v in self.variants if v.smooth is Smoothing.NONE)

    def methods(self) -> list[str]:
        """Estimator names present, in registry order."""
        return list(dict.fromkeys(v.method for v in self.plain))

    def ranges(self, method: str) -> list[int]:
        """Ranges of ``method`` present (plain variants)."""
        return [v.range for v in self.plain if v.method == method]

    @cached_property
    def noise_levels(self) -> list[float]:
        return list(self.cube.levels["noise"])

    @property
    def noise_max(self) -> float:
        """The highest noise level of the study; 0.0 when it has none (nothing noisy to report on)."""
        return max(self.noise_levels, default=0.0)

    def levels(self, column: str) -> list:
        if column in AXES:
            return list(self.cube.levels[column])
        return self.table.unique(column) if len(self.table) else []

    @property
    def n_samples(self) -> int:
        """Random surface draws that count (non-zero weight)."""
        if self.weights is None:
            return self.cube.n_units
        return int(np.count_nonzero(self.weights))

    @cached_property
    def _groups(self) -> dict:
        return {}

    def err(self, variant: Variant | str, *, measure: str | None = None, **where) -> float:
        """Mean of ``measure`` over the rows of ``variant`` matching ``where`` (NaN if none).

        ``where`` restricts the axes ``function``, ``density``, ``irregularity``, ``noise`` to a
        value or a collection of values; rows are weighted by :attr:`weights`.
        """
        vid = variant.id if isinstance(variant, Variant) else variant
        key = (vid, measure or self.measure, tuple(sorted((k, _hashable(v)) for k, v in where.items())))
        cache = self._groups
        if key not in cache:
            cache[key] = self.cube.mean(vid, measure or self.measure, self.weights, **where)
        return cache[key]

    def find(self, method: str, k: int, smooth: Smoothing = Smoothing.NONE) -> Variant | None:
        v = Variant(method, k, smooth)
        return v if v in self.variants else None

    def has(self, **where) -> bool:
        return len(self.table.where(**where)) > 0

    def resampled(self, weights: np.ndarray) -> "Analysis":
        """The same analysis with other weights per random surface draw (shares the cube)."""
        return replace(self, weights=np.asarray(weights, float))

    def paper(self) -> "Analysis":
        """The same analysis restricted to the paper's estimators."""
        return replace(self, paper_only=True)

    def first_samples(self, n: int) -> "Analysis":
        """The same analysis on samples ``0 .. n-1`` only (e.g. the N=2 medium run inside an N=100 run)."""
        return replace(self, weights=unit_weights(self.cube, range(n)))


def _paper_methods() -> set[str]:
    from ..estimators import ESTIMATORS

    return {name for name, spec in ESTIMATORS.items() if spec.in_paper}


def _hashable(v):
    if isinstance(v, (list, tuple, set, frozenset, np.ndarray)):
        return tuple(sorted(np.asarray(list(v)).tolist()))
    return v


def table1(an: Analysis) -> dict[int, dict[str, dict[float, float]]]:
    """The paper's Table 1 from our data: error at each irregularity in % of the 0° error.

    Noise-free meshes only, averaged over densities, functions and samples (ratio of the means).

    Returns
    -------
    dict
        ``{range k: {method: {irregularity: percent}}}`` for every range present; empty if the
        table has no 0° or no noise-free rows.
    """
    irr = an.levels("irregularity")
    if 0.0 not in irr or 0.0 not in an.noise_levels:
        return {}
    out: dict[int, dict[str, dict[float, float]]] = {}
    for v in an.plain:
        base = an.err(v, noise=0.0, irregularity=0.0)
        row = {i: 100.0 * an.err(v, noise=0.0, irregularity=i) / base for i in irr if i != 0.0}
        out.setdefault(v.range, {})[v.method] = row
    return dict(sorted(out.items()))


def table1_markdown(an: Analysis, *, with_paper: bool = True, intervals: dict | None = None) -> str:
    """Table 1 as Markdown: one block per range, our value and (where the paper has one) the paper's.

    ``intervals`` (same nesting as :func:`table1`, values ``(lo, hi)``) adds a confidence interval
    in square brackets after each of our values.
    """
    from .protocol import short_name

    t1 = table1(an)
    if not t1:
        return "_Table 1 needs noise-free meshes at 0° and at least one other irregularity._\n"
    paper = _paper_methods()
    lines = [
        f"Error at each irregularity in % of the error at 0° ({MEASURES[an.measure]}), noise-free "
        "meshes, averaged over densities, functions and samples (ratio of means)."
        + (" In square brackets: 95 % bootstrap interval over the random surfaces." if intervals else "")
        + (" In round brackets: the paper's Table 1." if with_paper else "")
        + (" Estimators marked * are beyond the paper." if any(m not in paper for ms in t1.values() for m in ms) else ""),
        "",
    ]
    for k, methods in t1.items():
        names = list(methods)
        lines.append(f"**R{k}**" + ("" if k in PAPER_TABLE1 else " (not in the paper's table)"))
        lines.append("")
        lines.append("| Irreg. | " + " | ".join(short_name(m) + ("" if m in paper else "*") for m in names) + " |")
        lines.append("|---|" + "---:|" * len(names))
        for irr in next(iter(methods.values())):
            cells = []
            for m in names:
                cell = f"{methods[m][irr]:.0f}%"
                lo, hi = (intervals or {}).get(k, {}).get(m, {}).get(irr, (np.nan, np.nan))
                if np.isfinite(lo) and np.isfinite(hi):
                    cell += f" [{lo:.0f}–{hi:.0f}]"
                ref = PAPER_TABLE1.get(k, {}).get(m)
                if with_paper and ref and irr in (14.0, 25.0):
                    cell += f" ({ref[0 if irr == 14.0 else 1]:.0f}%)"
                cells.append(cell)
            lines.append(f"| {irr:g}° | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)
