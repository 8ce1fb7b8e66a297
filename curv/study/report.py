"""The written outputs of a study: ``table1.md``, ``report.md`` and the figures."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .analysis import MEASURES, Analysis, table1, table1_markdown
from .claims import Status, check, check_all
from .figures import write_figures
from .protocol import NOISE_FRACTION, StudySettings, short_name
from .table import Table
from .uncertainty import LEVEL, N_BOOT, interval, stability

__all__ = ["write_report", "report_markdown"]

_MARK = {Status.AGREES: "✅ agrees", Status.PARTLY: "🟡 partly", Status.DISAGREES: "❌ disagrees",
         Status.NOT_TESTED: "⚪ not tested"}


def _irregularity_lines(table: Table) -> list[str]:
    out = []
    for target in table.unique("irregularity"):
        rows = table.where(irregularity=target)
        ach = np.asarray(rows["irregularity_achieved"], float)
        out.append(f"{target:g}° → {ach.mean():.2f}° (range {ach.min():.2f}–{ach.max():.2f})")
    return out


def _summary_table(an: Analysis) -> list[str]:
    lv = an.noise_levels
    hi = an.noise_max
    cols = [("rms_erel", 0.0), ("median_erel", 0.0), ("excluded_share", 0.0), ("nrms_h", 0.0), ("nrms_k", 0.0)]
    if hi > 0:
        cols += [("rms_erel", hi), ("median_erel", hi), ("excluded_share", hi)]
    cols = [(m, n) for m, n in cols if n in lv]
    head = ["variant"] + [f"{m} @ noise {n:.0%}" for m, n in cols] + ["invalid", "s / estimate"]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    for v in an.variants:
        rows = an.table.where(variant=v.id)
        inv = np.asarray(rows["n_invalid"], float)
        ev = np.asarray(rows["n_evaluated"], float)
        inv_share = inv[inv >= 0].sum() / max(ev[inv >= 0].sum(), 1)
        cells = [f"{an.err(v, measure=m, noise=n):.3f}" for m, n in cols]
        lines.append(f"| {v.label} | " + " | ".join(cells)
                     + f" | {inv_share:.1%} | {an.err(v, measure='seconds'):.3f} |")
    return lines


def _table1_intervals(an: Analysis) -> dict | None:
    """95 % bootstrap intervals of every Table 1 cell (None with fewer than two samples)."""
    t1 = table1(an)
    if an.n_samples < 2 or not t1:
        return None
    cells = [(k, m, i) for k, ms in t1.items() for m, row in ms.items() for i in row]

    def flat(a: Analysis) -> np.ndarray:
        t = table1(a)
        return np.array([t.get(k, {}).get(m, {}).get(i, np.nan) for k, m, i in cells])

    lo, hi = interval(an, flat)
    out: dict = {}
    for (k, m, i), a, b in zip(cells, lo, hi):
        out.setdefault(k, {}).setdefault(m, {})[i] = (float(a), float(b))
    return out


def _mean_ci(an: Analysis, variant, **where) -> str:
    lo, hi = interval(an, lambda a: a.err(variant, **where))
    est = an.err(variant, **where)
    return f"{est:.3g} [{float(lo):.3g}–{float(hi):.3g}]" if np.isfinite(lo) else f"{est:.3g}"


def _best_per_setting(an: Analysis) -> list[str]:
    """The best variant overall and the best of the paper's, per density and noise level."""
    paper = an.paper()
    beyond = [v for v in an.plain if v not in paper.plain]
    if not beyond:
        return []
    lines = [
        "Mean over functions, irregularities and samples; 95 % bootstrap intervals in brackets. "
        "Beyond the paper: " + ", ".join(sorted({short_name(v.method) for v in beyond})) + ".",
        "",
        "| density | noise | best variant | best of the paper's | ratio |",
        "|---:|---:|---|---|---:|",
    ]
    for d in an.levels("density"):
        for n in an.noise_levels:
            errs = {v: an.err(v, density=d, noise=n) for v in an.plain}
            errs = {v: e for v, e in errs.items() if np.isfinite(e)}
            if not errs:
                continue
            best = min(errs, key=errs.get)
            best_p = min((v for v in errs if v in paper.plain), key=errs.get, default=None)
            if best_p is None:
                continue
            lines.append(f"| {d} | {n:.0%} | {best.label} {_mean_ci(an, best, density=d, noise=n)} | "
                         f"{best_p.label} {_mean_ci(an, best_p, density=d, noise=n)} | "
                         f"{errs[best] / errs[best_p]:.2f} |")
    return lines


def _claim_rows(an: Analysis, verdicts) -> tuple[list[str], dict]:
    """The claims' summary table (verdict, bootstrap stability, the verdict on the first two
    samples when there are more) and each claim's stability."""
    resampled = an.n_samples >= 2
    early = an.first_samples(2) if an.n_samples > 2 else None
    head = ["#", "claim", "verdict"] + (["stability"] if resampled else []) + (["N=2"] if early else [])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    stable = {}
    for i, (claim, verdict) in enumerate(verdicts, 1):
        cells = [str(i), claim.statement, _MARK[verdict.status]]
        if resampled:
            stable[claim.id] = stability(an, lambda a, c=claim: check(c, a).status)
            cells.append(f"{stable[claim.id]:.0%}")
        if early is not None:
            then = check(claim, early).status
            cells.append(_MARK[then] + ("" if then is verdict.status else " (changed)"))
        lines.append("| " + " | ".join(cells) + " |")
    return lines, stable


def report_markdown(table: Table, settings: StudySettings, *, measure: str = "rms_erel",
                    elapsed: float | None = None) -> str:
    """The study report: setup, achieved irregularity, Table 1, per-variant summary, claims."""
    an = Analysis(table, settings, measure)
    verdicts = check_all(an)
    counts = {s: sum(v.status is s for _, v in verdicts) for s in Status}
    errors = table.where(error=lambda e: np.array([bool(x) for x in e], bool)) if len(table) else table
    n = an.n_samples
    lines = [
        "# curvlab study report",
        "",
        "Reproduction of the evaluation in §5 of the paper (multivariate curvature estimators).",
        "",
        "## Setup",
        "",
        f"- samples per setting: **{settings.samples}** (the paper: 1000); seed {settings.seed}"
        + (f"; random surface draws with results: {n}" if n != settings.samples else ""),
        f"- densities: {', '.join(map(str, settings.densities))} vertices",
        f"- noise: {', '.join(f'{n:.0%}' for n in settings.noise)} of σ = {NOISE_FRACTION:.0%} of the mean edge length",
        f"- irregularity targets → achieved (mean, range): {'; '.join(_irregularity_lines(table)) if len(table) else 'n/a'}",
        f"- functions: {', '.join(settings.functions)}",
        f"- variants: {len(an.variants)} ({len(an.plain)} plain; R2SM/R2SV at {settings.fig10_density} vertices)",
        f"- rows: {len(table)} from {len(set(zip(*(table[k].tolist() for k in ('function', 'density', 'irregularity', 'noise', 'sample'))))) if len(table) else 0} meshes"
        + (f"; wall time {elapsed:.0f} s" if elapsed is not None else ""),
        f"- measure: {MEASURES[measure]} (mean over the meshes of a setting)",
        f"- verdicts: {', '.join(f'{counts[s]} {s.value}' for s in Status)}",
    ]
    if n >= 2:
        lines.append(f"- uncertainty: {LEVEL:.0%} percentile bootstrap over the {n} random surface draws "
                     f"({N_BOOT} resamples; a draw keeps all its settings together); a verdict's stability "
                     "is the share of resamples that give the same verdict")
    if len(errors):
        lines += ["", f"**{len(errors)} estimates raised** (first: {errors['variant'][0]}: {errors['error'][0]})"]
    lines += ["", "## Table 1: error increase with irregularity", "",
              table1_markdown(an, intervals=_table1_intervals(an)), "## Error per variant", ""]
    lines += _summary_table(an)
    lines += ["", "Invalid: share of evaluated vertices the estimator marked invalid (left out of every measure).", ""]
    best = _best_per_setting(an)
    if best:
        lines += ["## Best estimator per setting", ""] + best + [""]
    summary, stable = _claim_rows(an, verdicts)
    lines += ["## The paper's conclusions, checked", "",
              "On the paper's estimators only (the claims are about them).", ""] + summary + [""]
    for claim, verdict in verdicts:
        extra = f" Stable in {stable[claim.id]:.0%} of the resamples." if claim.id in stable else ""
        lines += [f"### {_MARK[verdict.status]}: {claim.statement}", "",
                  f"*{claim.source}.* Test: {claim.test}.", "", f"Measured: {verdict.measured}.{extra}", ""]
    lines += ["## Figures", "", "![Fig. 8](fig8.png)", "", "![Fig. 9](fig9.png)", "", "![Fig. 10](fig10.png)", ""]
    return "\n".join(lines)


def write_report(table: Table, settings: StudySettings, out_dir, *, measure: str = "rms_erel",
                 elapsed: float | None = None) -> list[Path]:
    """Write ``table1.md``, ``report.md``, ``fig8.png``, ``fig9.png``, ``fig10.png``; return the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    an = Analysis(table, settings, measure)
    (out / "table1.md").write_text("# Table 1: increase in error with irregularity\n\n"
                                   + table1_markdown(an, intervals=_table1_intervals(an)))
    (out / "report.md").write_text(report_markdown(table, settings, measure=measure, elapsed=elapsed))
    return [out / "table1.md", out / "report.md", *write_figures(an, out)]
