"""The paper's claims of §5.3 ("Interdependent factors": irregularity, functions, noise, range and
density, pairs of estimators, smoothing in Fig. 10) as checks against measured data
(:mod:`curv.study.claims`).
"""

from __future__ import annotations

import numpy as np

from .analysis import Analysis, table1
from .protocol import Smoothing, Variant, short_name
from .verdicts import Status, Verdict, at_highest_noise, number, not_tested, percent, share_verdict

__all__ = ["fig10_rows", "irregularity_rises", "csm_most_robust", "range_reduces_degradation", "csm_r1_dips",
           "function_order", "noise_increases", "noise_linear", "coarse_small_ranges", "dense_r4",
           "range_follows_density", "an_beats_r1", "nc_equal_range", "ru_dense_irregular",
           "noise_csm_then_mru", "r3_vs_smoothing"]


# ---------------------------------------------------------------------------------------- Table 1
def irregularity_rises(an: Analysis) -> Verdict:
    t1 = table1(an)
    irr = sorted(i for i in an.levels("irregularity"))
    if not t1 or len(irr) < 2:
        return not_tested("needs noise-free meshes at two or more irregularities")
    cells, hits = [], 0
    for k in (1, 2, 3):
        for m, row in t1.get(k, {}).items():
            seq = [100.0] + [row[i] for i in irr[1:]]
            ok = all(b > a for a, b in zip(seq, seq[1:]))
            hits += ok
            cells.append(f"{short_name(m)} (R{k}) " + "→".join(f"{x:.0f}%" for x in seq) + ("" if ok else " ✗"))
    total = len(cells)
    return Verdict(share_verdict(hits, total),
                   f"{hits}/{total} R1–R3 variants rise monotonically: " + "; ".join(cells))


def csm_most_robust(an: Analysis) -> Verdict:
    t1 = table1(an)
    top = max(an.levels("irregularity"), default=0.0)
    if not t1 or top == 0.0 or "csm" not in an.methods():
        return not_tested("needs CSM and noise-free meshes at 0° and a higher irregularity")
    hits, total, cells = 0, 0, []
    for k in (1, 2, 3):
        row = t1.get(k, {})
        if "csm" not in row or len(row) < 2:
            continue
        total += 1
        best = min(row, key=lambda m: row[m][top])
        hits += best == "csm"
        others = min(v[top] for m, v in row.items() if m != "csm")
        cells.append(f"R{k}: CSM {row['csm'][top]:.0f}% vs best other {others:.0f}%")
    status = Status.AGREES if hits == total else Status.PARTLY if hits else Status.DISAGREES
    return Verdict(status if total else Status.NOT_TESTED, f"at {top:g}°: " + "; ".join(cells))


def range_reduces_degradation(an: Analysis) -> Verdict:
    t1 = table1(an)
    top = max(an.levels("irregularity"), default=0.0)
    groups = {k: [row[top] for row in t1.get(k, {}).values()] for k in (1, 2, 3, 4) if t1.get(k)}
    if len(groups) < 2:
        return not_tested("needs two or more ranges at 0° and a higher irregularity")
    med = {k: float(np.median(v)) for k, v in groups.items()}
    ks = sorted(med)
    ok = [med[b] < med[a] for a, b in zip(ks, ks[1:])]
    status = Status.AGREES if all(ok) else Status.PARTLY if any(ok) else Status.DISAGREES
    return Verdict(status, f"median error at {top:g}° in % of 0°, per range: "
                   + ", ".join(f"R{k} {med[k]:.0f}%" for k in ks))


def csm_r1_dips(an: Analysis) -> Verdict:
    t1 = table1(an)
    row = t1.get(1, {}).get("csm")
    if not row or 14.0 not in row:
        return not_tested("needs CSM (R1) on noise-free meshes at 0° and 14°")
    r = row[14.0]
    return Verdict(Status.AGREES if r < 100 else Status.DISAGREES,
                   f"CSM (R1) at 14°: {r:.0f}% of its 0° error (paper: 86%)")


# ---------------------------------------------------------------------------------------- functions
def function_order(an: Analysis) -> Verdict:
    funcs = an.levels("function")
    if len(funcs) < 3:
        return not_tested("needs all three functions")
    mean = {f: float(np.nanmean([an.err(v, function=f) for v in an.plain])) for f in funcs}
    order = sorted(mean, key=mean.get)
    want = ["ellipsoid_patch", "trigonometric", "quadratic"]
    status = Status.AGREES if order == want else Status.PARTLY if order[0] == "ellipsoid_patch" else Status.DISAGREES
    return Verdict(status, "mean over all plain variants and settings: "
                   + ", ".join(f"{f} {number(mean[f])}" for f in order))


# ---------------------------------------------------------------------------------------- noise
def noise_increases(an: Analysis) -> Verdict:
    lv = an.noise_levels
    if len(lv) < 2:
        return not_tested("needs two or more noise levels")
    hits, bad = 0, []
    robust_hits = 0
    for v in an.plain:
        seq = [an.err(v, noise=n) for n in lv]
        ok = all(b > a for a, b in zip(seq, seq[1:]))
        hits += ok
        rseq = [an.err(v, noise=n, measure="median_erel") for n in lv]
        robust_hits += all(b > a for a, b in zip(rseq, rseq[1:]))
        if not ok:
            bad.append(f"{v.label} " + "→".join(number(x) for x in seq))
    total = len(an.plain)
    text = f"{hits}/{total} variants rise with every noise step (robust companion, median e_rel: {robust_hits}/{total})"
    if bad:
        text += "; not monotone: " + "; ".join(bad[:8]) + (" …" if len(bad) > 8 else "")
    return Verdict(share_verdict(hits, total, agree=0.9, partly=0.5), text)


def noise_linear(an: Analysis) -> Verdict:
    lv = an.noise_levels
    mids = [n for n in lv if 0 < n < max(lv)]
    if len(lv) < 3 or not mids or min(x for x in lv if x > 0) == max(lv):
        return not_tested("needs three non-zero noise levels")
    lo, hi = min(x for x in lv if x > 0), max(lv)
    hits, total, worst = 0, 0, []
    for v in an.plain:
        elo, ehi = an.err(v, noise=lo), an.err(v, noise=hi)
        dev = 0.0
        for m in mids:
            if m == lo:
                continue
            chord = elo + (ehi - elo) * (m - lo) / (hi - lo)
            dev = max(dev, abs(an.err(v, noise=m) - chord) / max(abs(ehi - elo), 1e-12))
        total += 1
        hits += dev < 0.15
        worst.append((dev, v.label))
    worst.sort(reverse=True)
    return Verdict(share_verdict(hits, total),
                   f"{hits}/{total} variants within 15% of the straight line from {lo:g} to {hi:g}; "
                   "largest deviations: " + ", ".join(f"{lab} {d:.0%}" for d, lab in worst[:4]))


# ---------------------------------------------------------------------------------------- density × range
def _best_range(an: Analysis, method: str, **where) -> int | None:
    errs = {k: an.err(Variant(method, k), **where) for k in an.ranges(method)}
    errs = {k: e for k, e in errs.items() if np.isfinite(e)}
    return min(errs, key=errs.get) if errs else None


def _multi_range_methods(an: Analysis) -> list[str]:
    return [m for m in an.methods() if len(an.ranges(m)) >= 3]


def coarse_small_ranges(an: Analysis) -> Verdict:
    d = min(an.levels("density"), default=None)
    if d != 217 or 0.0 not in an.noise_levels:
        return not_tested("needs noise-free meshes with 217 vertices")
    cells, hits = [], 0
    for m in _multi_range_methods(an):
        b = _best_range(an, m, density=d, noise=0.0)
        ok = b is not None and b <= 2
        hits += ok
        cells.append(f"{short_name(m)} best R{b}" + ("" if ok else " ✗"))
    return Verdict(share_verdict(hits, len(cells), agree=0.99, partly=0.5), "217 vertices, no noise: " + ", ".join(cells))


def dense_r4(an: Analysis) -> Verdict:
    if 12481 not in an.levels("density") or 0.0 not in an.noise_levels:
        return not_tested("needs noise-free meshes with 12481 vertices (not in this grid)")
    cells, hits = [], 0
    for m in _multi_range_methods(an):
        if 4 not in an.ranges(m):
            continue
        b = _best_range(an, m, density=12481, noise=0.0)
        r2, r4 = an.err(Variant(m, 2), density=12481, noise=0.0), an.err(Variant(m, 4), density=12481, noise=0.0)
        ok = b == 4
        hits += ok
        cells.append(f"{short_name(m)} best R{b} (R4/R2 = {percent(r4 / r2)})" + ("" if ok else " ✗"))
    return Verdict(share_verdict(hits, len(cells), agree=0.99, partly=0.5), "12481 vertices, no noise: " + ", ".join(cells))


def range_follows_density(an: Analysis) -> Verdict:
    dens = an.levels("density")
    if 817 not in dens or len(dens) < 2 or 0.0 not in an.noise_levels:
        return not_tested("needs noise-free meshes with 817 vertices and another density")
    cells, hits, mono = [], 0, 0
    methods = _multi_range_methods(an)
    for m in methods:
        best = [_best_range(an, m, density=d, noise=0.0) for d in dens]
        b817 = best[dens.index(817)]
        ok = b817 == 2
        up = all(b is not None and a is not None and b >= a for a, b in zip(best, best[1:]))
        hits += ok
        mono += up
        cells.append(f"{short_name(m)}: " + ", ".join(f"{d}→R{b}" for d, b in zip(dens, best))
                     + ("" if ok and up else " ✗"))
    n = len(methods)
    status = (Status.AGREES if hits == n and mono == n else
              Status.PARTLY if hits + mono >= n else Status.DISAGREES) if n else Status.NOT_TESTED
    return Verdict(status, f"best range per density (no noise); R2 at 817 for {hits}/{n}, "
                   f"non-decreasing with density for {mono}/{n}: " + "; ".join(cells))


# ---------------------------------------------------------------------------------------- pairs of estimators
def an_beats_r1(an: Analysis) -> Verdict:
    need = [an.find("an", 2), an.find("qs", 1), an.find("nc", 1)]
    if None in need or 0.0 not in an.noise_levels:
        return not_tested("needs AN (R2), QS (R1), NC (R1) on noise-free meshes")
    cells, hits = [], 0
    dens = an.levels("density")
    for d in dens:
        a, q, n = (an.err(v, density=d, noise=0.0) for v in need)
        ok = a < q and a < n
        hits += ok
        cells.append(f"{d}: AN {number(a)}, QS {number(q)}, NC {number(n)}" + ("" if ok else " ✗"))
    return Verdict(share_verdict(hits, len(dens), agree=0.99, partly=0.5), "; ".join(cells))


def nc_equal_range(an: Analysis) -> Verdict:
    if 0.0 not in an.noise_levels:
        return not_tested("needs noise-free meshes")
    hits, total, cells = 0, 0, []
    for k in (2, 3, 4):
        trio = [an.find(m, k) for m in ("nc", "qs", "an")]
        if None in trio:
            continue
        k_hits = 0
        for d in an.levels("density"):
            e = [an.err(v, density=d, noise=0.0) for v in trio]
            ok = e[0] < e[1] and e[0] < e[2]
            k_hits += ok
            total += 1
        hits += k_hits
        cells.append(f"R{k}: NC best in {k_hits}/{len(an.levels('density'))} densities")
    return Verdict(share_verdict(hits, total, agree=0.5, partly=0.25),
                   "NC vs QS and AN at the same range, no noise: " + "; ".join(cells))


def ru_dense_irregular(an: Analysis) -> Verdict:
    ru = an.find("ru", 2)
    r1 = [v for v in an.plain if v.range == 1]
    dens, irr = an.levels("density"), an.levels("irregularity")
    if ru is None or not r1 or len(dens) < 2 or len(irr) < 2 or 0.0 not in an.noise_levels:
        return not_tested("needs RU, R1 estimators, two densities and two irregularities")
    hi_d, lo_d, hi_i = max(dens), min(dens), max(irr)
    best_r1_dense = min(r1, key=lambda v: an.err(v, density=hi_d, irregularity=hi_i, noise=0.0))
    e_ru_dense = an.err(ru, density=hi_d, irregularity=hi_i, noise=0.0)
    e_r1_dense = an.err(best_r1_dense, density=hi_d, irregularity=hi_i, noise=0.0)
    best_r1_reg = min(r1, key=lambda v: an.err(v, density=lo_d, irregularity=0.0, noise=0.0))
    e_ru_reg = an.err(ru, density=lo_d, irregularity=0.0, noise=0.0)
    e_r1_reg = an.err(best_r1_reg, density=lo_d, irregularity=0.0, noise=0.0)
    a, b = e_ru_dense < e_r1_dense, e_r1_reg < e_ru_reg
    status = Status.AGREES if a and b else Status.PARTLY if a or b else Status.DISAGREES
    return Verdict(status, f"{hi_d} vertices at {hi_i:g}°: RU {number(e_ru_dense)} vs best R1 "
                   f"{best_r1_dense.label} {number(e_r1_dense)}{'' if a else ' ✗'}; {lo_d} vertices at 0°: "
                   f"best R1 {best_r1_reg.label} {number(e_r1_reg)} vs RU {number(e_ru_reg)}{'' if b else ' ✗'}")


@at_highest_noise
def noise_csm_then_mru(an: Analysis, hi: float) -> Verdict:
    cells, csm_hits, mru_hits, total, mtotal = [], 0, 0, 0, 0
    for k in (2, 3, 4):
        group = [v for v in an.plain if v.range == k]
        if an.find("csm", k) is None or len(group) < 2:
            continue
        ranked = sorted(group, key=lambda v: an.err(v, noise=hi))
        total += 1
        csm_hits += ranked[0].method == "csm"
        text = f"R{k}: " + " < ".join(f"{short_name(v.method)} {number(an.err(v, noise=hi))}" for v in ranked[:3])
        if k >= 3 and an.find("mru", k) is not None:
            mtotal += 1
            mru_hits += ranked[1].method == "mru"
        cells.append(text)
    if not total:
        return not_tested("needs CSM at R2–R4")
    status = (Status.AGREES if csm_hits == total and mru_hits == mtotal else
              Status.PARTLY if csm_hits or mru_hits else Status.DISAGREES)
    return Verdict(status, f"noise {hi:.0%}, three lowest per range: " + "; ".join(cells)
                   + f" (CSM first in {csm_hits}/{total}, MRU second in {mru_hits}/{mtotal} of R3/R4)")


# ---------------------------------------------------------------------------------------- smoothing (Fig. 10)
def fig10_rows(an: Analysis):
    """The Fig. 10 comparison's density and, per estimator with R3, R2SM and R2SV variants,
    ``(method, R2, R3, R2SM, R2SV)`` (R2 may be None)."""
    d = an.settings.fig10_density
    out = []
    for m in an.methods():
        r2, r3 = an.find(m, 2), an.find(m, 3)
        sm, sv = an.find(m, 2, Smoothing.MESH), an.find(m, 2, Smoothing.VALUES)
        if r3 is not None and sm is not None and sv is not None:
            out.append((m, r2, r3, sm, sv))
    return d, out


@at_highest_noise
def r3_vs_smoothing(an: Analysis, hi: float) -> Verdict:
    d, rows = fig10_rows(an)
    if not rows or 0.0 not in an.noise_levels:
        return not_tested("needs R3 and R2SM/R2SV variants at noise 0 and a noisy level")
    quiet = noisy = 0
    cells = []
    for m, _, r3, sm, sv in rows:
        e = {n: (an.err(r3, density=d, noise=n), min(an.err(sm, density=d, noise=n), an.err(sv, density=d, noise=n)))
             for n in (0.0, hi)}
        quiet += e[0.0][0] < e[0.0][1]
        noisy += e[hi][1] < e[hi][0]
        cells.append(f"{short_name(m)}: R3 {number(e[0.0][0])} vs smoothed {number(e[0.0][1])} (no noise), "
                     f"{number(e[hi][0])} vs {number(e[hi][1])} (noise)")
    n = len(rows)
    status = share_verdict(min(quiet, noisy), n)
    return Verdict(status, f"{d} vertices; R3 better without noise for {quiet}/{n}, smoothing better "
                   f"with noise for {noisy}/{n}: " + "; ".join(cells))
