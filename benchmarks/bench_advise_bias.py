"""Why the checked advice loses to the table on some held-out meshes: a short list without the winner,
a noisy ranking, or a biased judge?

Run by hand on a runs file of ``bench_advisor.py`` (every candidate's true error on every held-out
mesh, the table's and the checked advice)::

    python benchmarks/bench_advisor.py --quick --meshes 24 --seed 24000 --workers 1 --runs runs24000.json
    python benchmarks/bench_advise_bias.py runs24000.json [--max-vertices 900] [--copies 3 12]

Reported, from the runs alone: the regret of the checked advice, of the table's first choice and of
an oracle that picks the truly best of the table's first 6, 10 and 20 calls (the short list holds
the winner when the oracle's regret is 1). Then, on the meshes of at most ``--max-vertices``, the
check is run again with each number of ``--copies`` (64 centres each): if more copies pick the same
call, the ranking is not noisy; each call's measured error over its true error shows the judge's bias.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

SHORT_LISTS = (6, 10, 20)


def table_order(run: dict, table: dict) -> list[str]:
    """The table's ranking of a run's mesh from its stored raw measures (as ``bench_advisor.py
    --rescore`` re-advises), the calls within the valid-share slack only."""
    from curv.advice.features import (RESIDUAL_MEASURES, SHAPE_MEASURES, MeshFeatures, calibrate_irregularity,
                                      calibrate_noise)
    from curv.advice.prediction import predict
    from curv.advice.shares import VALID_SHARE_SLACK, candidates, rank

    cal, raw = table["calibration"], run["raw"]
    noise = calibrate_noise(raw["noise_raw"], cal, raw["density"])
    f = MeshFeatures(irregularity_deg=calibrate_irregularity(raw["irregularity_raw_deg"], noise, cal), noise=noise,
                     density=raw["density"], border_share=raw["border_share"], polygon_kinds={3: 1},
                     noise_raw=raw["noise_raw"], **{k: raw.get(k, float("nan")) for k in (*SHAPE_MEASURES,
                                                                                          *RESIDUAL_MEASURES)})
    pred = predict(table, f)
    ok = [v for v in candidates(table, f) if np.isfinite(pred[v])]
    order = rank({v: pred[v] for v in ok}, run["shares"])
    top = max(run["shares"].get(v, 1.0) for v in order)
    return [v for v in order if run["shares"].get(v, 1.0) >= top - VALID_SHARE_SLACK]


def errors(run: dict) -> dict:
    """A run's true median e_rel per call, floored at the table's floor (1e-6)."""
    return {v: max(x, 1e-6) for v, x in run["erel"].items() if x is not None and x > 0}


def main(argv=None) -> int:
    from bench_advisor import _mesh

    from curv.advice.advising import iter_advise
    from curv.advice.prediction import load_table
    from curv.core.jit import run_to_end

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+")
    parser.add_argument("--max-vertices", type=int, default=900)
    parser.add_argument("--copies", type=int, nargs="+", default=[3, 12])
    args = parser.parse_args(argv)
    table = load_table()
    for path in args.runs:
        runs = json.loads(Path(path).read_text())
        rows = []
        for r in runs:
            e, order = errors(r), table_order(r, table)
            best = min(e[v] for v in order if v in e)
            oracle = [min([e[v] / best for v in order[:k] if v in e] or [np.inf]) for k in SHORT_LISTS]
            rows.append([e.get(r["advised"], np.inf) / best, e.get(r["advised_table"], np.inf) / best, *oracle])
        a = np.array(rows)
        print(f"{path}: {len(runs)} meshes")
        names = ["checked advice", "table's first"] + [f"best of the table's first {k}" for k in SHORT_LISTS]
        for name, col in zip(names, a.T):
            print(f"  {name:30s} regret median {np.median(col):.3f}  p90 {np.percentile(col, 90):.3f}  "
                  f"worst {col.max():.2f}")
        for r in runs:
            if r["n_vertices"] > args.max_vertices:
                continue
            e = errors(r)
            mesh = _mesh(r, r["noise_level"])[0]
            advs = {c: run_to_end(iter_advise(mesh, copies=c)) for c in args.copies}
            picks = {c: adv.best.variant.id for c, adv in advs.items()}
            measured = advs[max(args.copies)].check.measured
            best = min(e[v] for v in measured if v in e)
            print(f"  {r['n_vertices']} vertices, noise {r['noise_level']:.2f} of the paper's, {r['function']}: "
                  + ", ".join(f"{c} copies -> {v} (regret {e.get(v, np.inf) / best:.2f})" for c, v in picks.items()))
            for v, m in measured.items():
                print(f"      {v:34s} measured {m.erel:.4g}  true {e.get(v, np.nan):.4g}  "
                      f"measured / true {m.erel / e.get(v, np.nan):.2f}")
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
