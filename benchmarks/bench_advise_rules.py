"""Which call of the checked short list to advise? Ranking rules replayed on stored checks.

Run by hand (not part of the test suite) on the runs files of ``bench_advisor.py`` (every
candidate's true error on every held-out mesh) and the checks ``bench_advise_judge.py`` stored for
them (every mesh advised once, the measured errors of its short list)::

    python benchmarks/bench_advise_judge.py runs23000.json --checks checks23000.json      # once per runs file
    python benchmarks/bench_advise_rules.py runs23000.json runs24000.json --checks checks23000.json checks24000.json
    python benchmarks/bench_advise_rules.py RUNS... --checks CHECKS... --losses           # where the table loses
    python benchmarks/bench_advise_rules.py RUNS... --checks CHECKS... --realized REAL... # also the input's own score
    python benchmarks/bench_advise_rules.py runs35000.json --checks runs35000.json        # the checks bench_advisor.py stored

A check made by the library since the realized score (``bench_advisor.py``'s runs keep each mesh's
ranking; ``bench_advise_judge.py``'s checks too) carries each call's realized medians: the realized
rules then read those (no ``--realized``), and the library's own ranking is one more row, to be the
same as the realized rule at :data:`curv.advice.ranking.REALIZED_WEIGHT`.

Every rule picks one call of the short list (the calls the check measured, in the table's order)
from what the advice knows at run time: the table's predicted errors, the kernel's neighbours in
the table (their errors of the short-listed calls), the check's measured errors per copy and, with
``--realized``, each call's error *on the input itself* against its smooth twin's curvature
(:func:`realized_scores`: the input's own noise draw, which the copies draw afresh). Regret is
against the best call on that mesh (the calls within the valid-share slack), as in
``bench_advisor.py``; each rule's median / 90th percentile / worst regret pooled over the files and
per file, and its mean regret.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

FLOOR = 1e-6
JUDGE_SPREAD = 0.34
"""The smooth twin's bias between two calls of one short list as a log standard deviation: its 90th
percentile on seeds 23000 + 24000 was 1.76x-2.30x (docs/ADVISOR.md, "The judge's bias against the
table"), 1.645 sigma of a normal at log(1.76)."""


def mesh_records(runs: list[dict], checks: list[dict], realized: list[dict] | None = None) -> list[dict]:
    """One record per mesh: its true errors and best, the short list in the table's order with each
    call's prediction, measured error and copies (and realized score), the mesh's setting and features."""
    from bench_advise_judge import _candidates

    from curv.advice.shares import VALID_SHARE_SLACK

    by_index = {c["index"]: c["ranking"] for c in checks}
    # the realized scores of a --realized file, else those the library stored with its checks
    real = {r["index"]: r["scores"] for r in realized or []} or {
        c["index"]: {s["key"]: s["measured"].get("realized", []) for s in c["ranking"] if s["measured"] is not None}
        for c in checks}
    out = []
    for r in runs:
        e = {v: max(x, FLOOR) for v, x in r["erel"].items() if x is not None and x > 0}
        top = max(r["shares"].values())
        best = min(e[v] for v in e if r["shares"].get(v, 1.0) >= top - VALID_SHARE_SLACK)
        cands, measured = _candidates(by_index[r["index"]])
        cover = max(c.valid_share for c in cands) - VALID_SHARE_SLACK
        short = [{"key": c.key, "pred": max(c.expected_erel, FLOOR), "cover": c.valid_share >= cover,
                  "meas": max(measured[c.key].erel, FLOOR) if measured[c.key].ok else None,
                  "copies": np.maximum(np.asarray(measured[c.key].copies, float), FLOOR),
                  "real": _geometric_mean(real.get(r["index"], {}).get(c.key, []))}
                 for c in cands if c.key in measured]
        out.append({"run": r, "e": e, "best": best, "first": cands[0].key, "cands": cands, "measured": measured,
                    "short": [c for c in short if c["cover"]] or [{"key": cands[0].key}]})
    return out


def _geometric_mean(values) -> float | None:
    v = np.asarray([x for x in values if x is not None and x > 0], float)
    return float(np.exp(np.mean(np.log(np.maximum(v, FLOOR))))) if v.size else None


def _neighbours(rec: dict, table: dict) -> tuple[np.ndarray, np.ndarray]:
    """The table's kernel weights (normalised) over the table meshes that have every short-listed
    call, and those meshes' log errors of them: (k,), (k, s)."""
    from bench_advisor import stored_features

    from curv.advice.prediction import BASE_COLUMNS, feature_values, log_erel, table_coordinates

    if "neighbours" not in rec:
        points = table_coordinates(table, *np.asarray(table["points"], float).T)
        query = table_coordinates(table, *feature_values(stored_features(rec["run"]["raw"], table),
                                                         table.get("columns", BASE_COLUMNS)))
        d2 = np.sum((points - query) ** 2, axis=1) / table["kernel"]["bandwidth"] ** 2
        cols = [table["variants"].index(c["key"]) for c in rec["short"]]
        logs = log_erel(table)[:, cols]
        have = np.all(np.isfinite(logs), axis=1)
        w = np.exp(-0.5 * (d2[have] - d2[have].min()))
        rec["neighbours"] = (w / w.sum(), logs[have])
    return rec["neighbours"]


def _measured(rec: dict, judge: str = "meas") -> list[dict]:
    return [c for c in rec["short"] if c.get(judge) is not None]


def pick_weighted(rec: dict, weight: float, judge: str = "meas") -> str:
    """The call of least ``(1 - weight) log predicted + weight log judged`` error."""
    calls = _measured(rec, judge)
    if not calls:
        return rec["first"]
    return min(calls, key=lambda c: (1 - weight) * math.log(c["pred"]) + weight * math.log(c[judge]))["key"]


def pick_weighted_veto(rec: dict, weight: float, band: float) -> str:
    """:func:`pick_weighted` on the realized score, then the table-first rule's veto: the check's measured
    best instead where the copies measured the pick more than ``band`` times its error on every copy."""
    from curv.advice.ranking import _separated

    pick = pick_weighted(rec, weight, "real")
    calls = _measured(rec)
    if not calls or rec["measured"].get(pick) is None or not rec["measured"][pick].ok:
        return pick
    best = min(calls, key=lambda c: c["meas"])["key"]
    return best if _separated(rec["measured"][best], rec["measured"][pick], band) else pick


def pick_within_ties(rec: dict, table: dict, k: float) -> str:
    """The measured best among the calls the table cannot tell from its first: the neighbours' mean
    log ratio to the first within ``k`` standard errors of that mean."""
    calls = _measured(rec)
    if not calls or calls[0]["key"] != rec["first"]:
        return rec["first"]
    w, logs = _neighbours(rec, table)
    neff = 1 / np.sum(w**2)
    tied = []
    for j, c in enumerate(rec["short"]):
        d = logs[:, j] - logs[:, 0]
        mu = w @ d
        if c.get("meas") is not None and mu <= k * math.sqrt(w @ (d - mu) ** 2 / neff):
            tied.append(c)
    return min(tied, key=lambda c: c["meas"])["key"]


def pick_posterior(rec: dict, table: dict, spread: float = JUDGE_SPREAD) -> str:
    """The call of least posterior log ratio to the table's first: the table's (its neighbours' mean
    and spread of that ratio) and the check's (the measured ratio, :data:`JUDGE_SPREAD`) combined by
    their precisions."""
    calls = _measured(rec)
    if not calls or calls[0]["key"] != rec["first"]:
        return rec["first"]
    w, logs = _neighbours(rec, table)
    best, pick = 0.0, rec["first"]
    for j, c in enumerate(rec["short"]):
        if j == 0 or c.get("meas") is None:
            continue
        d = logs[:, j] - logs[:, 0]
        mu, var = w @ d, max(w @ (d - w @ d) ** 2, 1e-12)
        delta = math.log(c["meas"] / calls[0]["meas"])
        post = (mu / var + delta / spread**2) / (1 / var + 1 / spread**2)
        if post < best:
            best, pick = post, c["key"]
    return pick


def pick_vote(rec: dict, table: dict) -> str:
    """The short-listed call best on the largest kernel weight of the table's neighbours."""
    w, logs = _neighbours(rec, table)
    votes = np.bincount(np.argmin(logs, axis=1), weights=w, minlength=len(rec["short"]))
    return rec["short"][int(np.argmax(votes))]["key"]


def pick_band(rec: dict, band: float) -> str:
    """:func:`curv.advice.ranking.rank_candidates`'s table-first rule at ``band`` (``realized_weight=None``,
    shipped before the realized score): the table's first unless the check measured it more than
    ``band`` times the best on every copy."""
    from curv.advice.ranking import rank_candidates
    from curv.advice.shares import VALID_SHARE_SLACK

    return rank_candidates(rec["cands"], rec["measured"], VALID_SHARE_SLACK, judge_bias=band,
                           realized_weight=None)[0].key


def pick_library(rec: dict) -> str:
    """:func:`curv.advice.ranking.rank_candidates` as shipped, on the realized scores the library stored
    with its checks (the same figures as ``pick_weighted(rec, REALIZED_WEIGHT, "real")``, from the library)."""
    from curv.advice.ranking import rank_candidates
    from curv.advice.shares import VALID_SHARE_SLACK

    return rank_candidates(rec["cands"], rec["measured"], VALID_SHARE_SLACK)[0].key


def rules(table: dict, with_realized: bool, library: bool = False) -> list:
    """(label, pick) of every rule compared."""
    from curv.advice.ranking import JUDGE_BIAS

    out = [(f"the table's first, the check's veto at {JUDGE_BIAS:g}x (table-first)", lambda r: pick_band(r, JUDGE_BIAS)),
           ("the check's measured best (band 1)", lambda r: pick_band(r, 1.0))]
    out += [(f"weighted geometric mean, check's weight {w:g}", lambda r, w=w: pick_weighted(r, w)) for w in (0.2, 0.5)]
    out += [(f"the check among the table's ties ({k:g} standard error)", lambda r, k=k: pick_within_ties(r, table, k))
            for k in (1.0, 2.0)]
    out += [("posterior of the table's neighbours and the check", lambda r: pick_posterior(r, table)),
            ("the table's neighbours' vote", lambda r: pick_vote(r, table))]
    if with_realized:
        out += [(f"realized score, weight {w:g} (the rest the table's)", lambda r, w=w: pick_weighted(r, w, "real"))
                for w in (0.5, 0.7, 1.0)]
        out.append((f"realized score, weight 0.5, the check's veto at {JUDGE_BIAS:g}x",
                    lambda r: pick_weighted_veto(r, 0.5, JUDGE_BIAS)))
    if library:
        out.append(("the library's ranking (rank_candidates, its stored realized scores)", pick_library))
    out.append(("bound: the truly best of the short list", lambda r: min(r["short"], key=lambda c: r["e"][c["key"]])["key"]))
    return out


def _cells(x) -> str:
    x = np.asarray(x, float)
    return f"{np.median(x):.3f} / {np.percentile(x, 90):.3f} / {x.max():.2f}"


def rules_report(sets: dict, table: dict, with_realized: bool, library: bool = False) -> str:
    """Markdown: every rule's regret pooled and per set."""
    names = list(sets)
    lines = [f"| rule | pooled ({sum(len(v) for v in sets.values())}) | " + " | ".join(names) + " | mean regret |",
             "|---" * (len(names) + 3) + "|"]
    for label, pick in rules(table, with_realized, library):
        per = {n: [rec["e"][pick(rec)] / rec["best"] for rec in recs] for n, recs in sets.items()}
        pooled = sum(per.values(), [])
        lines.append(f"| {label} | {_cells(pooled)} | " + " | ".join(_cells(per[n]) for n in names)
                     + f" | {np.mean(pooled):.3f} |")
    return "\n".join(lines)


def agreement_report(sets: dict, split: int = 500) -> str:
    """Markdown: how well each judge orders a short list, the correlation of its log errors with the
    true ones over every (mesh, measured call), each mesh's logs centred (only the order within a
    mesh matters), on meshes of at most and of more than ``split`` vertices."""
    judges = [("pred", "the table's prediction"), ("meas", "the check's measure"), ("real", "the realized score")]
    rows = {False: [], True: []}
    for recs in sets.values():
        for rec in recs:
            calls = [c for c in rec["short"] if all(c.get(j) is not None for j, _ in judges)]
            if len(calls) > 1:
                logs = np.log([[c[j] for j, _ in judges] + [rec["e"][c["key"]]] for c in calls])
                rows[rec["run"]["n_vertices"] > split].append(logs - logs.mean(axis=0))
    lines = ["| meshes | calls | " + " | ".join(label for _, label in judges) + " |", "|---" * (len(judges) + 2) + "|"]
    for big, label in ((False, f"at most {split} vertices"), (True, f"more than {split} vertices")):
        if rows[big]:
            x = np.concatenate(rows[big])
            lines.append(f"| {label} | {len(x)} | " + " | ".join(f"{np.corrcoef(x[:, i], x[:, -1])[0, 1]:.2f}"
                                                              for i in range(len(judges))) + " |")
    return "\n".join(lines)


def losses_report(sets: dict, above: float = 1.2) -> str:
    """Markdown: the meshes where the table's first choice has regret above ``above``."""
    def short(key):
        return key.replace(";fit_range=", " fit R").replace(";normals=fit", "").replace(";degree=", " deg ").replace(":", " ")

    def num(x):
        return "-" if x is None else f"{x:.3g}"

    lines = ["| mesh | surface | vertices | noise | irregularity | the table's first (regret): predicted / measured "
             "| the short list's best (regret, table's place): predicted / measured | the check's best (regret) |",
             "|---|---|---|---|---|---|---|---|"]
    for name, recs in sets.items():
        for rec in recs:
            r, e, first = rec["run"], rec["e"], rec["short"][0]
            if e[rec["first"]] / rec["best"] <= above:
                continue
            best = min(rec["short"], key=lambda c: e[c["key"]])
            place = [c["key"] for c in rec["short"]].index(best["key"]) + 1
            calls = _measured(rec)
            checked = min(calls, key=lambda c: c["meas"]) if calls else None
            lines.append(
                f"| {name}/{r['index']} | {r['function']}{' (closed)' if r['closed'] else ''} | {r['n_vertices']} | "
                f"{r['noise_level']:.2f} | {r['irregularity']:.0f}° | {short(rec['first'])} ({e[rec['first']] / rec['best']:.2f}): "
                f"{num(first.get('pred'))} / {num(first.get('meas'))} | {short(best['key'])} ({e[best['key']] / rec['best']:.2f}, "
                f"#{place}): {num(best.get('pred'))} / {num(best.get('meas'))} | "
                + (f"{short(checked['key'])} ({e[checked['key']] / rec['best']:.2f}) |" if checked else "none measured |"))
    return "\n".join(lines)


def realized_scores(runs: list[dict], checks: list[dict], *, copies: int = 3, centres: int = 64) -> list[dict]:
    """Each short-listed call's error on the input itself at the check's centres, against the smooth
    twin's curvature there (per centre set: its median e_rel), with the check's centres and twins
    (seed 0). Unlike the check's copies, the input keeps its own noise draw."""
    from bench_advisor import _mesh

    import curv
    from curv.advice.advising import _mesh_pool
    from curv.advice.answer import Candidate
    from curv.advice.check import _centre_sets, call_reach
    from curv.advice.twin import build_twin, range_units
    from curv.core.errors import CurvError
    from curv.metrics import relative_error

    by_index = {c["index"]: c["ranking"] for c in checks}
    out = []
    for r in runs:
        mesh = _mesh(r, r["noise_level"])[0]
        proposed = [Candidate(c["method"], c["range"], c["options"], c["expected_erel"], c["valid_share"])
                    for c in by_index[r["index"]] if c["measured"] is not None]
        pool = _mesh_pool(mesh, proposed, None) if proposed else np.zeros(0, np.int64)
        scores = {c.key: [] for c in proposed}
        for chosen in _centre_sets(pool, copies, centres, np.random.default_rng([0, 35])) if pool.size else []:
            units = range_units(mesh, chosen)
            twin = build_twin(mesh, chosen, np.max([call_reach(mesh, c.kwargs, units, chosen) for c in proposed], axis=0))
            for c in proposed:
                try:
                    res = curv.estimate(mesh, vertices=twin.source, **c.kwargs)
                except CurvError:
                    continue
                err = relative_error(twin.k1, twin.k2, res.k1[twin.source], res.k2[twin.source])
                if np.isfinite(err).any():
                    scores[c.key].append(float(np.nanmedian(err)))
        out.append({"index": r["index"], "scores": scores})
        print(f"  mesh {r['index']}: realized", flush=True)
    return out


def main(argv=None) -> int:
    from curv.advice.prediction import load_table

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="runs files of bench_advisor.py")
    parser.add_argument("--checks", nargs="+", required=True, help="the stored checks of bench_advise_judge.py, one per runs file")
    parser.add_argument("--realized", nargs="+", help="realized scores, one file per runs file (made where missing)")
    parser.add_argument("--losses", action="store_true", help="list the meshes the table's first choice loses on")
    args = parser.parse_args(argv)
    if len(args.checks) != len(args.runs) or (args.realized and len(args.realized) != len(args.runs)):
        parser.error("give one --checks (and --realized) file per runs file")
    sets = {}
    for i, path in enumerate(args.runs):
        runs, checks = json.loads(Path(path).read_text()), json.loads(Path(args.checks[i]).read_text())
        real = None
        if args.realized:
            real_path = Path(args.realized[i])
            if not real_path.exists():
                real_path.write_text(json.dumps(realized_scores(runs, checks)))
            real = json.loads(real_path.read_text())
        sets[Path(path).stem] = mesh_records(runs, checks, real)
    if args.losses:
        print(losses_report(sets))
        return 0
    stored = any(bool(c["measured"].get("realized")) for path in args.checks
                 for m in json.loads(Path(path).read_text()) for c in m["ranking"] if c["measured"] is not None)
    print(rules_report(sets, load_table(), bool(args.realized) or stored, library=stored))
    if args.realized or stored:
        print("\nThe judges' order of a short list against the truth (correlation of centred log errors):\n")
        print(agreement_report(sets))
    return 0


if __name__ == "__main__":
    sys.exit(main())
