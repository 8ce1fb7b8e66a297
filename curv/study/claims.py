"""The paper's conclusions (§5.3 and §6) as checks against measured data.

Each claim is a function of an :class:`~curv.study.analysis.Analysis` returning a :class:`Verdict`:
``agrees``, ``partly``, ``disagrees`` or ``not tested`` (the grid lacks what the claim needs), with
the measured numbers that decided it. The thresholds are stated in each claim's ``test`` text so a
reader can judge them.
"""

from __future__ import annotations

import enum
import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .analysis import Analysis, table1
from .protocol import Smoothing, Variant, short_name

__all__ = ["Status", "Verdict", "Claim", "CLAIMS", "check", "check_all"]


class Status(str, enum.Enum):
    AGREES = "agrees"
    PARTLY = "partly"
    DISAGREES = "disagrees"
    NOT_TESTED = "not tested"


@dataclass
class Verdict:
    status: Status
    measured: str
    """The numbers that decided the verdict (Markdown)."""


@dataclass(frozen=True)
class Claim:
    id: str
    source: str
    statement: str
    test: str
    check: Callable[[Analysis], Verdict]


def _share_verdict(hits: int, total: int, *, agree: float = 2 / 3, partly: float = 1 / 3) -> Status:
    if total == 0:
        return Status.NOT_TESTED
    share = hits / total
    return Status.AGREES if share >= agree else Status.PARTLY if share >= partly else Status.DISAGREES


def _pct(x: float) -> str:
    return "n/a" if not np.isfinite(x) else f"{100 * x:.0f}%"


def _f(x: float) -> str:
    return "n/a" if not np.isfinite(x) else f"{x:.3g}"


def _not(reason: str) -> Verdict:
    return Verdict(Status.NOT_TESTED, reason)


def _at_highest_noise(claim: Callable[[Analysis, float], Verdict]) -> Callable[[Analysis], Verdict]:
    """A claim about the study's highest noise level: ``claim(an, hi)``, not tested unless ``hi > 0``."""
    @functools.wraps(claim)
    def check(an: Analysis) -> Verdict:
        return claim(an, an.noise_max) if an.noise_max > 0.0 else _not("needs noisy meshes")
    return check


# ---------------------------------------------------------------------------------------- Table 1
def _irregularity_rises(an: Analysis) -> Verdict:
    t1 = table1(an)
    irr = sorted(i for i in an.levels("irregularity"))
    if not t1 or len(irr) < 2:
        return _not("needs noise-free meshes at two or more irregularities")
    cells, hits = [], 0
    for k in (1, 2, 3):
        for m, row in t1.get(k, {}).items():
            seq = [100.0] + [row[i] for i in irr[1:]]
            ok = all(b > a for a, b in zip(seq, seq[1:]))
            hits += ok
            cells.append(f"{short_name(m)} (R{k}) " + "→".join(f"{x:.0f}%" for x in seq) + ("" if ok else " ✗"))
    total = len(cells)
    return Verdict(_share_verdict(hits, total),
                   f"{hits}/{total} R1–R3 variants rise monotonically: " + "; ".join(cells))


def _csm_most_robust(an: Analysis) -> Verdict:
    t1 = table1(an)
    top = max(an.levels("irregularity"), default=0.0)
    if not t1 or top == 0.0 or "csm" not in an.methods():
        return _not("needs CSM and noise-free meshes at 0° and a higher irregularity")
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


def _range_reduces_degradation(an: Analysis) -> Verdict:
    t1 = table1(an)
    top = max(an.levels("irregularity"), default=0.0)
    groups = {k: [row[top] for row in t1.get(k, {}).values()] for k in (1, 2, 3, 4) if t1.get(k)}
    if len(groups) < 2:
        return _not("needs two or more ranges at 0° and a higher irregularity")
    med = {k: float(np.median(v)) for k, v in groups.items()}
    ks = sorted(med)
    ok = [med[b] < med[a] for a, b in zip(ks, ks[1:])]
    status = Status.AGREES if all(ok) else Status.PARTLY if any(ok) else Status.DISAGREES
    return Verdict(status, f"median error at {top:g}° in % of 0°, per range: "
                   + ", ".join(f"R{k} {med[k]:.0f}%" for k in ks))


def _csm_r1_dips(an: Analysis) -> Verdict:
    t1 = table1(an)
    row = t1.get(1, {}).get("csm")
    if not row or 14.0 not in row:
        return _not("needs CSM (R1) on noise-free meshes at 0° and 14°")
    r = row[14.0]
    return Verdict(Status.AGREES if r < 100 else Status.DISAGREES,
                   f"CSM (R1) at 14°: {r:.0f}% of its 0° error (paper: 86%)")


# ---------------------------------------------------------------------------------------- functions
def _function_order(an: Analysis) -> Verdict:
    funcs = an.levels("function")
    if len(funcs) < 3:
        return _not("needs all three functions")
    mean = {f: float(np.nanmean([an.err(v, function=f) for v in an.plain])) for f in funcs}
    order = sorted(mean, key=mean.get)
    want = ["ellipsoid_patch", "trigonometric", "quadratic"]
    status = Status.AGREES if order == want else Status.PARTLY if order[0] == "ellipsoid_patch" else Status.DISAGREES
    return Verdict(status, "mean over all plain variants and settings: "
                   + ", ".join(f"{f} {_f(mean[f])}" for f in order))


# ---------------------------------------------------------------------------------------- noise
def _noise_increases(an: Analysis) -> Verdict:
    lv = an.noise_levels
    if len(lv) < 2:
        return _not("needs two or more noise levels")
    hits, bad = 0, []
    robust_hits = 0
    for v in an.plain:
        seq = [an.err(v, noise=n) for n in lv]
        ok = all(b > a for a, b in zip(seq, seq[1:]))
        hits += ok
        rseq = [an.err(v, noise=n, measure="median_erel") for n in lv]
        robust_hits += all(b > a for a, b in zip(rseq, rseq[1:]))
        if not ok:
            bad.append(f"{v.label} " + "→".join(_f(x) for x in seq))
    total = len(an.plain)
    text = f"{hits}/{total} variants rise with every noise step (robust companion, median e_rel: {robust_hits}/{total})"
    if bad:
        text += "; not monotone: " + "; ".join(bad[:8]) + (" …" if len(bad) > 8 else "")
    return Verdict(_share_verdict(hits, total, agree=0.9, partly=0.5), text)


def _noise_linear(an: Analysis) -> Verdict:
    lv = an.noise_levels
    mids = [n for n in lv if 0 < n < max(lv)]
    if len(lv) < 3 or not mids or min(x for x in lv if x > 0) == max(lv):
        return _not("needs three non-zero noise levels")
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
    return Verdict(_share_verdict(hits, total),
                   f"{hits}/{total} variants within 15% of the straight line from {lo:g} to {hi:g}; "
                   "largest deviations: " + ", ".join(f"{lab} {d:.0%}" for d, lab in worst[:4]))


# ---------------------------------------------------------------------------------------- density × range
def _best_range(an: Analysis, method: str, **where) -> int | None:
    errs = {k: an.err(Variant(method, k), **where) for k in an.ranges(method)}
    errs = {k: e for k, e in errs.items() if np.isfinite(e)}
    return min(errs, key=errs.get) if errs else None


def _multi_range_methods(an: Analysis) -> list[str]:
    return [m for m in an.methods() if len(an.ranges(m)) >= 3]


def _coarse_small_ranges(an: Analysis) -> Verdict:
    d = min(an.levels("density"), default=None)
    if d != 217 or 0.0 not in an.noise_levels:
        return _not("needs noise-free meshes with 217 vertices")
    cells, hits = [], 0
    for m in _multi_range_methods(an):
        b = _best_range(an, m, density=d, noise=0.0)
        ok = b is not None and b <= 2
        hits += ok
        cells.append(f"{short_name(m)} best R{b}" + ("" if ok else " ✗"))
    return Verdict(_share_verdict(hits, len(cells), agree=0.99, partly=0.5), "217 vertices, no noise: " + ", ".join(cells))


def _dense_r4(an: Analysis) -> Verdict:
    if 12481 not in an.levels("density") or 0.0 not in an.noise_levels:
        return _not("needs noise-free meshes with 12481 vertices (not in this grid)")
    cells, hits = [], 0
    for m in _multi_range_methods(an):
        if 4 not in an.ranges(m):
            continue
        b = _best_range(an, m, density=12481, noise=0.0)
        r2, r4 = an.err(Variant(m, 2), density=12481, noise=0.0), an.err(Variant(m, 4), density=12481, noise=0.0)
        ok = b == 4
        hits += ok
        cells.append(f"{short_name(m)} best R{b} (R4/R2 = {_pct(r4 / r2)})" + ("" if ok else " ✗"))
    return Verdict(_share_verdict(hits, len(cells), agree=0.99, partly=0.5), "12481 vertices, no noise: " + ", ".join(cells))


def _range_follows_density(an: Analysis) -> Verdict:
    dens = an.levels("density")
    if 817 not in dens or len(dens) < 2 or 0.0 not in an.noise_levels:
        return _not("needs noise-free meshes with 817 vertices and another density")
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
def _an_beats_r1(an: Analysis) -> Verdict:
    need = [an.find("an", 2), an.find("qs", 1), an.find("nc", 1)]
    if None in need or 0.0 not in an.noise_levels:
        return _not("needs AN (R2), QS (R1), NC (R1) on noise-free meshes")
    cells, hits = [], 0
    dens = an.levels("density")
    for d in dens:
        a, q, n = (an.err(v, density=d, noise=0.0) for v in need)
        ok = a < q and a < n
        hits += ok
        cells.append(f"{d}: AN {_f(a)}, QS {_f(q)}, NC {_f(n)}" + ("" if ok else " ✗"))
    return Verdict(_share_verdict(hits, len(dens), agree=0.99, partly=0.5), "; ".join(cells))


def _nc_equal_range(an: Analysis) -> Verdict:
    if 0.0 not in an.noise_levels:
        return _not("needs noise-free meshes")
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
    return Verdict(_share_verdict(hits, total, agree=0.5, partly=0.25),
                   "NC vs QS and AN at the same range, no noise: " + "; ".join(cells))


def _ru_dense_irregular(an: Analysis) -> Verdict:
    ru = an.find("ru", 2)
    r1 = [v for v in an.plain if v.range == 1]
    dens, irr = an.levels("density"), an.levels("irregularity")
    if ru is None or not r1 or len(dens) < 2 or len(irr) < 2 or 0.0 not in an.noise_levels:
        return _not("needs RU, R1 estimators, two densities and two irregularities")
    hi_d, lo_d, hi_i = max(dens), min(dens), max(irr)
    best_r1_dense = min(r1, key=lambda v: an.err(v, density=hi_d, irregularity=hi_i, noise=0.0))
    e_ru_dense = an.err(ru, density=hi_d, irregularity=hi_i, noise=0.0)
    e_r1_dense = an.err(best_r1_dense, density=hi_d, irregularity=hi_i, noise=0.0)
    best_r1_reg = min(r1, key=lambda v: an.err(v, density=lo_d, irregularity=0.0, noise=0.0))
    e_ru_reg = an.err(ru, density=lo_d, irregularity=0.0, noise=0.0)
    e_r1_reg = an.err(best_r1_reg, density=lo_d, irregularity=0.0, noise=0.0)
    a, b = e_ru_dense < e_r1_dense, e_r1_reg < e_ru_reg
    status = Status.AGREES if a and b else Status.PARTLY if a or b else Status.DISAGREES
    return Verdict(status, f"{hi_d} vertices at {hi_i:g}°: RU {_f(e_ru_dense)} vs best R1 "
                   f"{best_r1_dense.label} {_f(e_r1_dense)}{'' if a else ' ✗'}; {lo_d} vertices at 0°: "
                   f"best R1 {best_r1_reg.label} {_f(e_r1_reg)} vs RU {_f(e_ru_reg)}{'' if b else ' ✗'}")


@_at_highest_noise
def _noise_csm_then_mru(an: Analysis, hi: float) -> Verdict:
    cells, csm_hits, mru_hits, total, mtotal = [], 0, 0, 0, 0
    for k in (2, 3, 4):
        group = [v for v in an.plain if v.range == k]
        if an.find("csm", k) is None or len(group) < 2:
            continue
        ranked = sorted(group, key=lambda v: an.err(v, noise=hi))
        total += 1
        csm_hits += ranked[0].method == "csm"
        text = f"R{k}: " + " < ".join(f"{short_name(v.method)} {_f(an.err(v, noise=hi))}" for v in ranked[:3])
        if k >= 3 and an.find("mru", k) is not None:
            mtotal += 1
            mru_hits += ranked[1].method == "mru"
        cells.append(text)
    if not total:
        return _not("needs CSM at R2–R4")
    status = (Status.AGREES if csm_hits == total and mru_hits == mtotal else
              Status.PARTLY if csm_hits or mru_hits else Status.DISAGREES)
    return Verdict(status, f"noise {hi:.0%}, three lowest per range: " + "; ".join(cells)
                   + f" (CSM first in {csm_hits}/{total}, MRU second in {mru_hits}/{mtotal} of R3/R4)")


# ---------------------------------------------------------------------------------------- smoothing (Fig. 10)
def _fig10_rows(an: Analysis):
    d = an.settings.fig10_density
    out = []
    for m in an.methods():
        r2, r3 = an.find(m, 2), an.find(m, 3)
        sm, sv = an.find(m, 2, Smoothing.MESH), an.find(m, 2, Smoothing.VALUES)
        if r3 is not None and sm is not None and sv is not None:
            out.append((m, r2, r3, sm, sv))
    return d, out


@_at_highest_noise
def _r3_vs_smoothing(an: Analysis, hi: float) -> Verdict:
    d, rows = _fig10_rows(an)
    if not rows or 0.0 not in an.noise_levels:
        return _not("needs R3 and R2SM/R2SV variants at noise 0 and a noisy level")
    quiet = noisy = 0
    cells = []
    for m, _, r3, sm, sv in rows:
        e = {n: (an.err(r3, density=d, noise=n), min(an.err(sm, density=d, noise=n), an.err(sv, density=d, noise=n)))
             for n in (0.0, hi)}
        quiet += e[0.0][0] < e[0.0][1]
        noisy += e[hi][1] < e[hi][0]
        cells.append(f"{short_name(m)}: R3 {_f(e[0.0][0])} vs smoothed {_f(e[0.0][1])} (no noise), "
                     f"{_f(e[hi][0])} vs {_f(e[hi][1])} (noise)")
    n = len(rows)
    status = _share_verdict(min(quiet, noisy), n)
    return Verdict(status, f"{d} vertices; R3 better without noise for {quiet}/{n}, smoothing better "
                   f"with noise for {noisy}/{n}: " + "; ".join(cells))


@_at_highest_noise
def _mesh_beats_values(an: Analysis, hi: float) -> Verdict:
    d, rows = _fig10_rows(an)
    if not rows:
        return _not("needs R2SM and R2SV variants on noisy meshes")
    hits, cells = 0, []
    for m, _, _, sm, sv in rows:
        a, b = an.err(sm, density=d, noise=hi), an.err(sv, density=d, noise=hi)
        hits += a < b
        cells.append(f"{short_name(m)} R2SM {_f(a)} vs R2SV {_f(b)}" + ("" if a < b else " ✗"))
    return Verdict(_share_verdict(hits, len(rows)), f"{d} vertices, noise {hi:.0%}: " + "; ".join(cells))


def _range_differs_from_smoothing(an: Analysis) -> Verdict:
    d, rows = _fig10_rows(an)
    if not rows:
        return _not("needs R3 and R2SM/R2SV variants")
    hits, total, cells = 0, 0, []
    for m, _, r3, sm, sv in rows:
        for n in an.noise_levels:
            e3 = an.err(r3, density=d, noise=n)
            for s in (sm, sv):
                rel = abs(an.err(s, density=d, noise=n) - e3) / e3
                total += 1
                hits += rel > 0.10
        cells.append(f"{short_name(m)}")
    return Verdict(_share_verdict(hits, total),
                   f"{hits}/{total} (estimator, noise, smoothing) cases where the R3 error and the smoothed R2 "
                   f"error differ by more than 10% ({d} vertices)")


# ---------------------------------------------------------------------------------------- §6
@_at_highest_noise
def _larger_range_noise(an: Analysis, hi: float) -> Verdict:
    hits, cells = 0, []
    methods = [m for m in an.methods() if len(an.ranges(m)) >= 2]
    for m in methods:
        seq = [an.err(Variant(m, k), noise=hi) for k in an.ranges(m)]
        ok = all(b < a for a, b in zip(seq, seq[1:]))
        hits += ok
        cells.append(f"{short_name(m)} " + "→".join(_f(x) for x in seq) + ("" if ok else " ✗"))
    return Verdict(_share_verdict(hits, len(methods), agree=0.99, partly=0.5),
                   f"noise {hi:.0%}, error by increasing range: " + "; ".join(cells))


def _ru_mru_best_irregular(an: Analysis) -> Verdict:
    irr = an.levels("irregularity")
    if len(irr) < 2 or 0.0 not in an.noise_levels:
        return _not("needs noise-free meshes at two irregularities")
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
    return Verdict(_share_verdict(hits, total, agree=0.99, partly=0.5) if total else Status.NOT_TESTED,
                   "no noise, same range: " + "; ".join(cells))


@_at_highest_noise
def _mru_vs_csm(an: Analysis, hi: float) -> Verdict:
    if 0.0 not in an.noise_levels:
        return _not("needs noise-free and noisy meshes")
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
        cells.append(f"R{k}: no noise MRU {_f(an.err(m, noise=0.0))} vs CSM {_f(an.err(c, noise=0.0))}"
                     f"{'' if q else ' ✗'}; noise MRU {_f(an.err(m, noise=hi))} vs CSM {_f(an.err(c, noise=hi))}"
                     f"{'' if z else ' ✗'}")
    return Verdict(_share_verdict(quiet + noisy, 2 * total, agree=0.99, partly=0.5) if total else Status.NOT_TESTED,
                   "; ".join(cells))


def _mru_larger_range(an: Analysis) -> Verdict:
    ru = an.find("ru", 2)
    big = [v for v in (an.find("mru", 3), an.find("mru", 4)) if v is not None]
    if ru is None or not big or 0.0 not in an.noise_levels:
        return _not("needs RU (R2) and MRU at R3/R4 on noise-free meshes")
    e_ru = an.err(ru, noise=0.0)
    hits = sum(an.err(v, noise=0.0) < e_ru for v in big)
    return Verdict(_share_verdict(hits, len(big), agree=0.99, partly=0.5),
                   f"no noise: RU (R2) {_f(e_ru)}; " + ", ".join(f"{v.label} {_f(an.err(v, noise=0.0))}" for v in big))


def _runtime(an: Analysis) -> Verdict:
    d = max(an.levels("density"), default=None)
    if d is None:
        return _not("no data")
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
    return Verdict(_share_verdict(hits, total, agree=0.99, partly=0.5) if total else Status.NOT_TESTED,
                   f"mean seconds per estimate at {d} vertices (normals precomputed): " + "; ".join(cells))


CLAIMS: tuple[Claim, ...] = (
    Claim("irregularity", "§5.3, Tab. 1", "The error of most estimators increases with irregularity.",
          "every R1–R3 variant, no noise: error at 0° < 14° < 25°; agrees if ≥ 2/3 of the variants", _irregularity_rises),
    Claim("csm-robust", "§5.3, Tab. 1", "CSM is significantly more robust against irregular triangulations than the other estimators.",
          "in each range group R1–R3, CSM has the smallest error increase at the highest irregularity", _csm_most_robust),
    Claim("range-robust", "§5.3, Tab. 1", "With a larger range the degradation with irregularity is reduced.",
          "median (over estimators) increase at the highest irregularity falls from R1 to R2 to R3 (to R4)", _range_reduces_degradation),
    Claim("csm-r1-dip", "§5.3, Tab. 1", "CSM (R1) is more accurate on slightly irregular (14°) than on regular meshes.",
          "CSM (R1) error at 14° below its 0° error", _csm_r1_dips),
    Claim("functions", "§5.3", "Averaged over all estimators, the elliptic function gives the best results, followed by the trigonometric one.",
          "mean error over all plain variants and settings: ellipsoid_patch < trigonometric < quadratic", _function_order),
    Claim("noise-up", "§5.3", "The error increases with noise.",
          "each plain variant's error rises at each noise step; agrees if ≥ 90% of variants", _noise_increases),
    Claim("noise-linear", "§5.3", "Between 33% and 100% noise the error grows linearly.",
          "the 66% error lies within 15% (of the 33→100% rise) of the straight line, for ≥ 2/3 of variants", _noise_linear),
    Claim("coarse-small-range", "§5.3, Fig. 8", "On the coarsest mesh (217 vertices), ranges R1 and R2 are the most accurate.",
          "for every estimator with three or more ranges, its best range at 217 vertices (no noise) is R1 or R2", _coarse_small_ranges),
    Claim("dense-r4", "§5.3, Fig. 8", "On the densest mesh (12481 vertices), R4 greatly reduces the error.",
          "for every estimator with R4, R4 is its best range at 12481 vertices (no noise)", _dense_r4),
    Claim("range-density", "§5.3, Fig. 8", "817 vertices are best processed with R2; denser meshes get better results with larger ranges.",
          "best range at 817 vertices is R2, and the best range does not decrease with density (no noise)", _range_follows_density),
    Claim("an-vs-r1", "§5.3, Fig. 8", "AN (R2) outperforms QS (R1) and NC (R1) at every density.",
          "no noise, per density: AN (R2) < QS (R1) and AN (R2) < NC (R1)", _an_beats_r1),
    Claim("nc-equal-range", "§5.3, Fig. 8", "At equal ranges, NC often performs better (than QS and AN).",
          "no noise, per range R2–R4 and density: NC below both QS and AN in at least half the cases", _nc_equal_range),
    Claim("ru-dense-irregular", "§5.3, Fig. 8", "RU's advantage is reproduced on dense irregular meshes; on regular coarse meshes an R1 estimator is better.",
          "densest mesh at the highest irregularity: RU < best R1; coarsest mesh at 0°: best R1 < RU (no noise)", _ru_dense_irregular),
    Claim("noise-csm-mru", "§5.3, Fig. 9", "With noise, CSM (R2–R4) handles noise best, MRU (R3, R4) second.",
          "at the highest noise, CSM has the lowest error in each of R2–R4 and MRU the second lowest at R3 and R4", _noise_csm_then_mru),
    Claim("r3-vs-smoothing", "§5.3, Fig. 10", "R3 estimators are useful mainly without noise; with noise, smoothing looks better.",
          "at the Fig. 10 density: R3 < min(R2SM, R2SV) without noise and min(R2SM, R2SV) < R3 with noise, for ≥ 2/3 of the estimators", _r3_vs_smoothing),
    Claim("smooth-mesh-first", "§6", "Smoothing the noisy mesh gives better results than smoothing the curvature values afterwards.",
          "at the Fig. 10 density and highest noise: R2SM < R2SV for ≥ 2/3 of the estimators", _mesh_beats_values),
    Claim("range-not-smoothing", "§6", "Increasing the estimation range produces different results than smoothing.",
          "the R3 error and the R2SM/R2SV errors differ by more than 10% in ≥ 2/3 of the cases", _range_differs_from_smoothing),
    Claim("range-noise", "§6", "A larger range improves robustness against noise.",
          "at the highest noise, every estimator's error falls with each range step", _larger_range_noise),
    Claim("ru-mru-irregular", "§6", "Without noise, RU and MRU perform best also on irregular meshes; on regular meshes the Goldfeather–Interrante estimators do very well too.",
          "no noise, highest irregularity: the best variant of each range R2–R4 is RU or MRU (the 0° ratio of the best G&I variant is shown)", _ru_mru_best_irregular),
    Claim("mru-vs-csm", "§6", "MRU gives better results than CSM, but only for meshes without noise.",
          "per range R2–R4: MRU < CSM without noise and CSM < MRU at the highest noise", _mru_vs_csm),
    Claim("mru-range", "§6", "MRU has a higher accuracy on larger estimation ranges (than the original RU).",
          "no noise: MRU (R3) and MRU (R4) below RU (R2)", _mru_larger_range),
    Claim("mru-fast", "§6", "MRU is faster than all other estimators with a comparable range.",
          "at the densest mesh, MRU has the lowest mean time in each range group it belongs to (our implementations, not the paper's)", _runtime),
)
"""The checked statements, in the order of the paper."""


def check(claim: Claim, an: Analysis) -> Verdict:
    """One claim on the paper's estimators of ``an``; a check that fails on odd data is reported,
    not raised."""
    try:
        return claim.check(an.paper())
    except (ValueError, KeyError, ZeroDivisionError) as exc:
        return Verdict(Status.NOT_TESTED, f"could not be evaluated: {exc}")


def check_all(an: Analysis) -> list[tuple[Claim, Verdict]]:
    """Check every claim. The claims are the paper's statements about its own estimators, so
    estimators beyond the paper (``in_paper=False``) are left out of every comparison."""
    return [(claim, check(claim, an)) for claim in CLAIMS]
