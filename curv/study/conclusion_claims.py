"""The paper's claims of §6 ("Results and conclusions": smoothing against a larger range, noise,
irregular meshes, MRU against CSM and RU, run time) as checks against measured data
(:mod:`curv.study.claims`).
"""

from __future__ import annotations

from .analysis import Analysis
from .factor_claims import fig10_rows
from .protocol import Variant, short_name
from .verdicts import Status, Verdict, at_highest_noise, number, not_tested, share_verdict

__all__ = ["mesh_beats_values", "range_differs_from_smoothing", "larger_range_noise", "ru_mru_best_irregular",
           "mru_vs_csm", "mru_larger_range", "runtime"]


@at_highest_noise
def mesh_beats_values(an: Analysis, hi: float) -> Verdict:
    d, rows = fig10_rows(an)
    if not rows:
        return not_tested("needs R2SM and R2SV variants on noisy meshes")
    hits, cells = 0, []
    for m, _, _, sm, sv in rows:
        a, b = an.err(sm, density=d, noise=hi), an.err(sv, density=d, noise=hi)
        hits += a < b
        cells.append(f"{short_name(m)} R2SM {number(a)} vs R2SV {number(b)}" + ("" if a < b else " ✗"))
    return Verdict(share_verdict(hits, len(rows)), f"{d} vertices, noise {hi:.0%}: " + "; ".join(cells))


def range_differs_from_smoothing(an: Analysis) -> Verdict:
    d, rows = fig10_rows(an)
    if not rows:
        return not_tested("needs R3 and R2SM/R2SV variants")
    hits, total, cells = 0, 0, []
    for m, _, r3, sm, sv in rows:
        for n in an.noise_levels:
            e3 = an.err(r3, density=d, noise=n)
            for s in (sm, sv):
                rel = abs(an.err(s, density=d, noise=n) - e3) / e3
                total += 1
                hits += rel > 0.10
        cells.append(f"{short_name(m)}")
    return Verdict(share_verdict(hits, total),
                   f"{hits}/{total} (estimator, noise, smoothing) cases where the R3 error and the smoothed R2 "
                   f"error differ by more than 10% ({d} vertices)")


@at_highest_noise
def larger_range_noise(an: Analysis, hi: float) -> Verdict:
    hits, cells = 0, []
    methods = [m for m in an.methods() if len(an.ranges(m)) >= 2]
    for m in methods:
        seq = [an.err(Variant(m, k), noise=hi) for k in an.ranges(m)]
        ok = all(b < a for a, b in zip(seq, seq[1:]))
        hits += ok
        cells.append(f"{short_name(m)} " + "→".join(number(x) for x in seq) + ("" if ok else " ✗"))
    return Verdict(share_verdict(hits, len(methods), agree=0.99, partly=0.5),
                   f"noise {hi:.0%}, error by increasing range: " + "; ".join(cells))


def ru_mru_best_irregular(an: Analysis) -> Verdict:
    irr = an.levels("irregularity")
    if len(irr) < 2 or 0.0 not in an.noise_levels:
        return not_tested("needs noise-free meshes at two irregularities")
    top = max(irr)
    hits, total, cells = 0, 0, []
    for k in (2, 3, 4):
        group = [v for v in an.plain if v.range == k]
        if not any(v.method in ("ru", "mru") for v in group) or len(group) < 2:
            continue
        best = min(group, key=lambda v: an.err(v, noise=0.0, irregularity=top))
        total += 1
        hits += best.method in ("ru", "mru")
        gi = [v for v in group if v.method in ("nc", "qs", "an")]
        best0 = min(group, key=lambda v: an.err(v, noise=0.0, irregularity=0.0))
        gi0 = min(gi, key=lambda v: an.err(v, noise=0.0, irregularity=0.0)) if gi else None
        ratio = (an.err(gi0, noise=0.0, irregularity=0.0) / an.err(best0, noise=0.0, irregularity=0.0)
                 if gi0 else float("nan"))
        cells.append(f"R{k}: best at {top:g}° {best.label}; at 0° best {best0.label}, best G&I "
                     f"{gi0.label if gi0 else 'n/a'} at {ratio:.2f}× of it")
    return Verdict(share_verdict(hits, total, agree=0.99, partly=0.5) if total else Status.NOT_TESTED,
                   "no noise, same range: " + "; ".join(cells))


@at_highest_noise
def mru_vs_csm(an: Analysis, hi: float) -> Verdict:
    if 0.0 not in an.noise_levels:
        return not_tested("needs noise-free and noisy meshes")
    quiet = noisy = total = 0
    cells = []
    for k in (2, 3, 4):
        m, c = an.find("mru", k), an.find("csm", k)
        if m is None or c is None:
            continue
        total += 1
        q = an.err(m, noise=0.0) < an.err(c, noise=0.0)
        z = an.err(c, noise=hi) < an.err(m, noise=hi)
        quiet += q
        noisy += z
        cells.append(f"R{k}: no noise MRU {number(an.err(m, noise=0.0))} vs CSM {number(an.err(c, noise=0.0))}"
                     f"{'' if q else ' ✗'}; noise MRU {number(an.err(m, noise=hi))} vs CSM {number(an.err(c, noise=hi))}"
                     f"{'' if z else ' ✗'}")
    return Verdict(share_verdict(quiet + noisy, 2 * total, agree=0.99, partly=0.5) if total else Status.NOT_TESTED,
                   "; ".join(cells))


def mru_larger_range(an: Analysis) -> Verdict:
    ru = an.find("ru", 2)
    big = [v for v in (an.find("mru", 3), an.find("mru", 4)) if v is not None]
    if ru is None or not big or 0.0 not in an.noise_levels:
        return not_tested("needs RU (R2) and MRU at R3/R4 on noise-free meshes")
    e_ru = an.err(ru, noise=0.0)
    hits = sum(an.err(v, noise=0.0) < e_ru for v in big)
    return Verdict(share_verdict(hits, len(big), agree=0.99, partly=0.5),
                   f"no noise: RU (R2) {number(e_ru)}; " + ", ".join(f"{v.label} {number(an.err(v, noise=0.0))}" for v in big))


def runtime(an: Analysis) -> Verdict:
    d = max(an.levels("density"), default=None)
    if d is None:
        return not_tested("no data")
    sec = {v: an.err(v, measure="seconds", density=d) for v in an.plain}
    hits, total, cells = 0, 0, []
    for k in sorted({v.range for v in an.plain}):
        group = [v for v in an.plain if v.range == k]
        mru = an.find("mru", k)
        if mru is None or len(group) < 2:
            continue
        total += 1
        fastest = min(group, key=sec.get)
        hits += fastest == mru
        cells.append(f"R{k}: " + ", ".join(f"{short_name(v.method)} {sec[v]:.2f}s" for v in sorted(group, key=sec.get)))
    return Verdict(share_verdict(hits, total, agree=0.99, partly=0.5) if total else Status.NOT_TESTED,
                   f"mean seconds per estimate at {d} vertices (normals precomputed): " + "; ".join(cells))
