"""The written outputs of a study: ``table1.md``, ``report.md`` and the figures."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .analysis import MEASURES, Analysis, table1_markdown
from .claims import Status, check_all
from .figures import write_figures
from .protocol import NOISE_FRACTION, StudySettings
from .table import Table

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


def report_markdown(table: Table, settings: StudySettings, *, measure: str = "rms_erel",
                    elapsed: float | None = None) -> str:
    """The study report: setup, achieved irregularity, Table 1, per-variant summary, claims."""
    an = Analysis(table, settings, measure)
    verdicts = check_all(an)
    counts = {s: sum(v.status is s for _, v in verdicts) for s in Status}
    errors = table.where(error=lambda e: np.array([bool(x) for x in e], bool)) if len(table) else table
    lines = [
        "# curvlab study report",
        "",
        "Reproduction of the evaluation in §5 of the paper (multivariate curvature estimators).",
        "",
        "## Setup",
        "",
        f"- samples per setting: **{settings.samples}** (the paper: 1000); seed {settings.seed}",
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
    if len(errors):
        lines += ["", f"**{len(errors)} estimates raised** (first: {errors['variant'][0]}: {errors['error'][0]})"]
    lines += ["", "## Table 1: error increase with irregularity", "", table1_markdown(an), "## Error per variant", ""]
    lines += _summary_table(an)
    lines += ["", "Invalid: share of evaluated vertices the estimator marked invalid (left out of every measure).", "",
              "## The paper's conclusions, checked", ""]
    for claim, verdict in verdicts:
        lines += [f"### {_MARK[verdict.status]}: {claim.statement}", "",
                  f"*{claim.source}.* Test: {claim.test}.", "", f"Measured: {verdict.measured}", ""]
    lines += ["## Figures", "", "![Fig. 8](fig8.png)", "", "![Fig. 9](fig9.png)", "", "![Fig. 10](fig10.png)", ""]
    return "\n".join(lines)


def write_report(table: Table, settings: StudySettings, out_dir, *, measure: str = "rms_erel",
                 elapsed: float | None = None) -> list[Path]:
    """Write ``table1.md``, ``report.md``, ``fig8.png``, ``fig9.png``, ``fig10.png``; return the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    an = Analysis(table, settings, measure)
    (out / "table1.md").write_text("# Table 1: increase in error with irregularity\n\n" + table1_markdown(an))
    (out / "report.md").write_text(report_markdown(table, settings, measure=measure, elapsed=elapsed))
    return [out / "table1.md", out / "report.md", *write_figures(an, out)]
