"""Figures 8-10 of the paper from a results table (matplotlib, Agg backend).

The paper stacks the bars of the four densities on top of each other, so only the lowest segment
can be read against the axis. Here the densities are *grouped* side by side (light to dark =
coarse to dense) so that every bar reads directly, the trend over density is visible within
each estimator, and a black tick marks the mean over densities (what the paper's total height
stands for). Estimators of one family sit together on alternating shaded bands. Error bars are
95 % bootstrap intervals over the random surfaces (:mod:`curv.study.uncertainty`), drawn when a
run has two or more samples.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .analysis import MEASURES, Analysis
from .protocol import Smoothing, short_name
from .uncertainty import interval

__all__ = ["figure_density_bars", "figure_smoothing", "write_figures"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _scale(ax, values: np.ndarray) -> None:
    v = values[np.isfinite(values) & (values > 0)]
    if v.size and v.max() / v.min() > 30:
        ax.set_yscale("log")
    ax.grid(axis="y", which="both", alpha=0.3)
    ax.set_axisbelow(True)


def _bands(ax, methods: list[str], positions: dict[str, list[float]]) -> None:
    for i, m in enumerate(methods):
        xs = positions[m]
        if i % 2 == 0:
            ax.axvspan(min(xs) - 0.5, max(xs) + 0.5, color="0.93", zorder=0)


def _error_bars(an: Analysis, statistic, values: np.ndarray) -> np.ndarray | None:
    """(2, ...) distances from ``values`` down and up to the bootstrap interval of ``statistic``
    over the random surfaces; None with fewer than two surfaces (no interval to draw)."""
    if an.n_samples < 2:
        return None
    lo, hi = interval(an, lambda a: np.asarray(statistic(a), float))
    down = np.where(np.isfinite(lo), values - lo, 0.0)
    up = np.where(np.isfinite(hi), hi - values, 0.0)
    return np.maximum(np.stack([down, up]), 0.0)


def _density_panel(ax, an: Analysis, variants, dens, noise: float, measure: str, *, legend: bool) -> None:
    plt = _pyplot()

    def values(a: Analysis) -> np.ndarray:
        return np.array([[a.err(v, measure=measure, density=d, noise=noise) for d in dens] for v in variants])

    vals = values(an)
    bars = _error_bars(an, values, vals)
    width = 0.8 / len(dens)
    colors = plt.get_cmap("viridis")(np.linspace(0.85, 0.15, len(dens)))
    x = np.arange(len(variants))
    for j, d in enumerate(dens):
        ax.bar(x - 0.4 + width * (j + 0.5), vals[:, j], width, color=colors[j], label=f"{d} vertices", zorder=2,
               yerr=None if bars is None else bars[:, :, j], error_kw={"elinewidth": 0.6, "ecolor": "0.25"})
    ax.scatter(x, np.nanmean(vals, axis=1), marker="_", s=300, color="black", zorder=3,
               label="mean over densities")
    methods = list(dict.fromkeys(v.method for v in variants))
    _bands(ax, methods, {m: [i for i, v in enumerate(variants) if v.method == m] for m in methods})
    paper = {v.method for v in an.paper().variants}
    ax.set_xticks(x, [f"{short_name(v.method)}{'' if v.method in paper else '*'}\n{v.range_label}" for v in variants],
                  fontsize=8)
    ax.set_xlim(-0.6, len(variants) - 0.4)
    _scale(ax, vals)
    ax.set_ylabel(MEASURES[measure].replace(" over ", "\nover "), fontsize=8)
    if legend:
        ax.legend(fontsize=7, ncol=len(dens) + 1, loc="upper center", bbox_to_anchor=(0.5, -0.16), frameon=False)


def figure_density_bars(an: Analysis, noise: float, path, *, title: str, companion: str | None = None) -> bool:
    """Grouped bars: error per plain variant (x) and density (bars), at one noise level.

    With ``companion`` (a measure name), a second panel below shows that measure (e.g. the median
    of e_rel, which stays readable when the trimmed RMS saturates on noisy meshes).
    Returns False (and writes nothing) when the table has no rows at that noise level.
    """
    plt = _pyplot()
    variants = list(an.plain)
    dens = an.levels("density")
    if not variants or not an.has(noise=noise):
        return False
    measures = [an.measure] + ([companion] if companion and companion != an.measure else [])
    fig, axes = plt.subplots(len(measures), 1, figsize=(max(8.0, 0.55 * len(variants) + 2), 1.0 + 3.4 * len(measures)),
                             dpi=110, squeeze=False)
    for i, (ax, m) in enumerate(zip(axes[:, 0], measures)):
        _density_panel(ax, an, variants, dens, noise, m, legend=i == len(measures) - 1)
    axes[0, 0].set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return True


def figure_smoothing(an: Analysis, path) -> bool:
    """Fig. 10: R2, R3, R2SM and R2SV of each estimator at the Fig. 10 density, without and with
    the highest noise (two panels). Returns False when there is nothing to draw."""
    plt = _pyplot()
    d = an.settings.fig10_density
    methods = [m for m in an.methods() if an.find(m, 2, Smoothing.MESH) is not None]
    if not methods or not an.has(density=d):
        return False
    kinds = [("R2", 2, Smoothing.NONE), ("R3", 3, Smoothing.NONE), ("R2SM", 2, Smoothing.MESH),
             ("R2SV", 2, Smoothing.VALUES)]
    colors = ["#4c72b0", "#55a868", "#dd8452", "#c44e52"]
    levels = [0.0, an.noise_max] if an.noise_max > 0 and 0.0 in an.noise_levels else [an.noise_levels[0]]
    fig, axes = plt.subplots(1, len(levels), figsize=(5.2 * len(levels), 3.8), dpi=110, squeeze=False)
    for ax, noise in zip(axes[0], levels):
        x = np.arange(len(methods))
        width = 0.8 / len(kinds)
        allv = []
        for j, (name, k, s) in enumerate(kinds):
            def values(a: Analysis, k=k, s=s, noise=noise) -> np.ndarray:
                return np.array([a.err(a.find(m, k, s), density=d, noise=noise) if a.find(m, k, s) else np.nan
                                 for m in methods])

            vals = values(an)
            bars = _error_bars(an, values, vals)
            allv.append(vals)
            ax.bar(x - 0.4 + width * (j + 0.5), vals, width, color=colors[j], label=name, zorder=2,
                   yerr=bars, error_kw={"elinewidth": 0.6, "ecolor": "0.25"})
        paper = {v.method for v in an.paper().variants}
        ax.set_xticks(x, [short_name(m) + ("" if m in paper else "*") for m in methods])
        _scale(ax, np.concatenate(allv))
        ax.set_title(f"{d} vertices, " + ("no noise" if noise == 0 else f"noise {noise:.0%}"), fontsize=10)
        ax.set_ylabel(MEASURES[an.measure].replace(" over ", "\nover "), fontsize=8)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.suptitle("Larger range (R3) versus smoothing the mesh (R2SM) or the values (R2SV)" + _caption(an), fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    fig.legend(handles, labels, fontsize=8, ncol=4, loc="lower center", frameon=False)
    fig.savefig(path)
    plt.close(fig)
    return True


def _caption(an: Analysis) -> str:
    """What every density figure's title adds: the sample count, the bars, the starred estimators."""
    extra = [f"N = {an.n_samples}"]
    if an.n_samples >= 2:
        extra.append("bars: 95 % bootstrap intervals")
    if len(an.paper().variants) < len(an.variants):
        extra.append("* beyond the paper")
    return " (" + "; ".join(extra) + ")"


def write_figures(an: Analysis, out_dir) -> list[Path]:
    """Write ``fig8.png``, ``fig9.png`` and ``fig10.png`` into ``out_dir``; returns the files written."""
    out = Path(out_dir)
    written = []
    if 0.0 in an.noise_levels and figure_density_bars(
        an, 0.0, out / "fig8.png", title="Fig. 8: error per estimator and density, no noise" + _caption(an)
    ):
        written.append(out / "fig8.png")
    if an.noise_levels and an.noise_max > 0 and figure_density_bars(
        an, an.noise_max, out / "fig9.png",
        title=f"Fig. 9: error per estimator and density, noise {an.noise_max:.0%} (σ = {an.noise_max * 10:g}% of mean edge)"
        + _caption(an),
        companion="median_erel" if an.measure == "rms_erel" else None,
    ):
        written.append(out / "fig9.png")
    if figure_smoothing(an, out / "fig10.png"):
        written.append(out / "fig10.png")
    return written
