"""How far can the check's judge be trusted against the table? Its bias per call, and the regret of
the override rule at each band.

Run by hand (not part of the test suite) on the runs files of ``bench_advisor.py`` (every
candidate's true error on every held-out mesh)::

    python benchmarks/bench_advisor.py --quick --meshes 24 --seed 23000 --workers 1 --runs runs23000.json
    python benchmarks/bench_advise_judge.py runs23000.json --checks checks23000.json   # advise every mesh
    python benchmarks/bench_advise_judge.py runs23000.json --checks checks23000.json --report   # again from them
    python benchmarks/bench_advise_judge.py runs23000.json --checks narrow.json --reach-margin 0.5   # another twin

Every mesh of the runs is advised once (self-checked) and its ranking stored (``--checks``); the
report needs only the stored rankings and the runs' true errors:

- the judge's bias: per mesh, each measured call's log(measured / true), and the difference of
  that between every two calls of one short list (how far the check sets two calls apart from their
  true ratio): median, 90th percentile, largest, as factors;
- the meshes where the check's measured best is not the table's first choice, and which of the two
  was truly better;
- the regret (against the best call on that mesh, the calls within the valid-share slack) of the
  table-first rule of :func:`curv.advice.ranking.rank_candidates` (``realized_weight=None``) at each
  ``--bands`` value: the table's first
  choice kept unless the check measured it more than that many times the best's error on every copy
  (1: the check's best unless the copies cannot tell them apart; ``inf``: the table alone).
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


def advise_all(runs: list[dict], reach_margin: float | None = None, weight_width: float | None = None) -> list[dict]:
    """Each run's mesh advised (self-checked): its index and ranking (``Candidate.as_dict``).

    ``reach_margin`` and ``weight_width`` change the twin for this process (what-if runs of a
    different judge: :data:`curv.advice.check.REACH_MARGIN`, :data:`curv.advice.twin.WEIGHT_WIDTH`).
    """
    import functools

    from bench_advisor import _mesh

    import curv.advice.check as check
    import curv.advice.twin as twin
    from curv.advice.advising import iter_advise
    from curv.core.jit import run_to_end

    if reach_margin is not None:
        check.REACH_MARGIN = reach_margin
    if weight_width is not None:
        twin.build_twin = functools.partial(twin.build_twin, weight_width=weight_width)
    out = []
    for r in runs:
        adv = run_to_end(iter_advise(_mesh(r, r["noise_level"])[0]))
        out.append({"index": r["index"], "ranking": [c.as_dict() for c in adv.ranking]})
        print(f"  mesh {r['index']}: {adv.best.key}", flush=True)
    return out


def _candidates(stored: list[dict]) -> tuple[list, dict]:
    """The stored ranking as :class:`Candidate` objects in the table's order, and their measures."""
    from curv.advice.answer import Candidate
    from curv.advice.check import Measured
    from curv.advice.shares import VALID_SHARE_SLACK

    top = max(c["valid_share"] for c in stored)
    # the table's order: by coverage, then by prediction (what rank_candidates gets from the table)
    order = sorted(stored, key=lambda c: (c["valid_share"] < top - VALID_SHARE_SLACK, c["expected_erel"]))
    cands = [Candidate(c["method"], c["range"], c["options"], c["expected_erel"], c["valid_share"]) for c in order]
    measured = {c["key"]: Measured(m["erel"], tuple(m["copies"]), m["spread"], m["measured"], m["seconds"],
                                   tuple(m.get("realized", ())))
                for c in order if (m := c["measured"]) is not None}
    return cands, measured


def report(runs: list[dict], checks: list[dict], bands: list[float]) -> str:
    """The markdown report of one runs file and its stored checks."""
    from curv.advice.ranking import rank_candidates
    from curv.advice.shares import VALID_SHARE_SLACK

    lines, pairs, regrets = [], [], {b: [] for b in bands}
    wins = losses = 0
    by_index = {c["index"]: c for c in checks}
    for r in runs:
        stored = by_index[r["index"]]["ranking"]
        e = {v: max(x, FLOOR) for v, x in r["erel"].items() if x is not None and x > 0}
        top = max(r["shares"].values())
        best = min(e[v] for v in e if r["shares"].get(v, 1.0) >= top - VALID_SHARE_SLACK)
        cands, measured = _candidates(stored)
        ok = [c.key for c in cands if c.key in measured and measured[c.key].ok and c.key in e]
        logs = np.array([math.log(max(measured[k].erel, FLOOR) / e[k]) for k in ok])
        if logs.size > 1:
            pairs.extend(np.abs(logs[:, None] - logs[None, :])[np.triu_indices(logs.size, 1)])
        for b in bands:
            regrets[b].append(e[rank_candidates(cands, measured, VALID_SHARE_SLACK, judge_bias=b,
                                                realized_weight=None)[0].key] / best)
        table_pick = rank_candidates(cands, measured, VALID_SHARE_SLACK, judge_bias=math.inf, realized_weight=None)[0].key
        check_pick = rank_candidates(cands, measured, VALID_SHARE_SLACK, judge_bias=0.0, realized_weight=None)[0].key
        if table_pick != check_pick:
            t, c = e[table_pick] / best, e[check_pick] / best
            wins, losses = wins + (c * 1.02 < t), losses + (t * 1.02 < c)
            lines.append(f"| {r['index']} | {r['function']} | {r['n_vertices']} | {r['noise_level']:.2f} | "
                         f"{table_pick} ({t:.2f}) | {check_pick} ({c:.2f}) | "
                         f"{measured[table_pick].erel / max(measured[check_pick].erel, FLOOR):.2f} |")
    pairs = np.exp(np.array(pairs))
    out = [f"judge's bias between two calls of one short list: median {np.median(pairs):.2f}x, "
           f"p90 {np.percentile(pairs, 90):.2f}x, largest {pairs.max():.2f}x ({pairs.size} pairs)",
           f"the check's best against the table's first choice: {len(lines)} meshes differ, the check "
           f"truly better on {wins}, worse on {losses}", "",
           "| mesh | surface | vertices | noise | table's first (regret) | check's best (regret) | measured ratio |",
           "|---|---|---|---|---|---|---|", *lines, "", "| band | regret median | p90 | worst |", "|---|---|---|---|"]
    for b in bands:
        x = np.array(regrets[b])
        out.append(f"| {b:g} | {np.median(x):.3f} | {np.percentile(x, 90):.3f} | {x.max():.2f} |")
    return "\n".join(out)


def main(argv=None) -> int:
    from curv.advice.ranking import JUDGE_BIAS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="runs files of bench_advisor.py")
    parser.add_argument("--checks", nargs="+", required=True, help="one stored-checks file per runs file")
    parser.add_argument("--report", action="store_true", help="report from the stored checks (no advising)")
    parser.add_argument("--bands", type=float, nargs="+", default=[1.0, 1.5, 2.0, 2.5, JUDGE_BIAS, math.inf])
    parser.add_argument("--reach-margin", type=float, help="the twin's patch margin in range units (what-if)")
    parser.add_argument("--weight-width", type=float, help="the twin's weights' width, share of the radius (what-if)")
    args = parser.parse_args(argv)
    if len(args.checks) != len(args.runs):
        parser.error("give one --checks file per runs file")
    for path, checks_path in zip(args.runs, args.checks):
        runs = json.loads(Path(path).read_text())
        if not args.report:
            Path(checks_path).write_text(json.dumps(advise_all(runs, args.reach_margin, args.weight_width)))
        print(f"\n{path} ({len(runs)} meshes), checks {checks_path}:\n")
        print(report(runs, json.loads(Path(checks_path).read_text()), args.bands))
    return 0


if __name__ == "__main__":
    sys.exit(main())
