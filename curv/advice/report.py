"""The advice in words for a terminal: what was measured, what the check did, the ranking (``curv advise``)."""

from __future__ import annotations

__all__ = ["feature_lines", "check_lines", "ranking_lines"]


def feature_lines(name: str, adv) -> list[str]:
    """What was measured on the input, a line each."""
    out = []
    f = adv.features
    if adv.is_cloud:
        out.append(f"{name}: {f.n_points:,} points; spacing {f.spacing:.4g} (median); "
                   f"{'normals from the file' if f.has_normals else 'no normals (fitted, oriented ' + f.orientation_words + ')'}; "
                   f"{100 * f.border_share:.1f} % on the rim")
        if f.noise == f.noise:
            out.append(f"  noise        {f.noise:.3g} spacings along the normal (about the smooth twin)")
        return out
    kinds = ", ".join(f"{n} {k}-gons" if k != 3 else f"{n} triangles" for k, n in f.polygon_kinds.items())
    out.append(f"{name}: {f.n_vertices} vertices; {kinds}; {100 * f.border_share:.1f} % on a border")
    out.append(f"  noise        {f.noise:.4f} mean edges ({f.noise_level:.2f} of the paper's level)")
    out.append(f"  irregularity {f.irregularity_deg:.1f} degrees RMS from 60")
    out.append(f"  density      {f.density:.4f} (mean edge x median |k1|+|k2|)")
    out.append(f"  spreads      valence {f.valence_sd:.2f} (sd), curvature {f.curvature_spread:.2f} "
               f"(IQR of log |k1|+|k2|)")
    out.append(f"  shape        anisotropy {f.anisotropy:.2f}, model residual {f.residual_ratio:.2g} (quartic / "
               f"quadric fit residual: about 1 noise, near 0 the surface's own shape)")
    return out


def check_lines(adv) -> list[str]:
    """What the check did, or why it did not run."""
    report = adv.check
    if report is None:
        return [f"  not checked: {adv.note}"]
    noise = (f"noise {report.noise:.3g} along the normal (input units)" if report.noise > 0 else
             f"no noise the twin resolves (at most {report.noise_bound:.2g})")
    return [f"  checked: {len(report.measured)} calls on {report.copies} noisy copies of the smooth twin, "
            f"{report.centres} centres each; {noise}; {report.seconds:.1f} s",
            f"  ranked by {adv.ranked_by}"]


def ranking_lines(adv, top: int) -> list[str]:
    """The first ``top`` candidates: label, valid share, predicted, realized and measured error."""
    out = []
    shown = adv.ranking[:top]
    width = max((len(c.label) for c in shown), default=7)
    realized = adv.check is not None and not adv.is_cloud  # a mesh's check scores the calls on the input
    out.append(f"{'rank':>4}  {'variant':<{width}}  valid  {'predicted':>9}  " + (f"{'realized':>8}  " if realized else "")
               + "measured median e_rel (x spread over copies)")
    for i, c in enumerate(shown, 1):
        pred = f"{c.expected_erel:9.3g}" if c.expected_erel == c.expected_erel else f"{'-':>9}"
        m = c.measured
        meas = ""
        if m is not None and m.ok:
            meas = f"{m.erel:.3g}" + (f" x{m.spread:.2f}" if m.spread == m.spread else "")
            meas += "  within noise" if c.within_noise else ""
        real = (f"{c.realized_erel:8.3g}  " if c.realized_erel == c.realized_erel else f"{'-':>8}  ") if realized else ""
        out.append(f"{i:>4}  {c.label:<{width}}  {100 * c.valid_share:4.0f}%  {pred}  {real}{meas}")
    if len(adv.ranking) > len(shown):
        out.append(f"  ... {len(adv.ranking) - len(shown)} more (--top N, --json)")
    return out
