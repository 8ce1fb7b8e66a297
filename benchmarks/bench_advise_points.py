"""The advisor on point clouds against MeshLab's APSS, on the paper's protocol.

Run by hand (not part of the test suite)::

    python benchmarks/bench_advise_points.py 2                 # 2 surfaces per function: 24 clouds
    python benchmarks/bench_advise_points.py 2 --first 3       # surfaces 3 and 4 (held out)
    python benchmarks/bench_advise_points.py 1 --first 3 --functions quadratic --noises 1 --samplings blue

The clouds are those of ``bench_accuracy.py --points`` and ``points_wide_ranges.py`` (the study's
random Monge patches of 3169 vertices, seed 0; about 3169 points, uniform random or blue noise;
noise 0 or 100 % of the paper's level, 3-D Gaussian of 10 % of the matching mesh's mean edge), **no
normals given**. On each cloud ``curv.advise(cloud, vertices=evaluated)`` chooses a call (its self-
check measures every point-cloud candidate on noisy copies of the cloud's smooth twin, its
centres drawn from the evaluated points), and the call runs on the cloud. The evaluated points
follow ``points_wide_ranges.py``'s same-footing rule (no border point of the clean cloud within 13
spacings, the reach of every call compared), so APSS's widest scales qualify too. APSS gets the
library's default normals of the noisy cloud (jet R2, oriented up), at the scales of
``points_wide_ranges.py`` (6-16; the best per cell, chosen against the truth, is kept, which favours
APSS). Every candidate of :data:`curv.advice.clouds.CLOUD_CALLS` is run too, for the advisor's regret
on clouds.

Reported per cell (sampling, noise): the pooled median e_rel over the cell's evaluated points of
the advised calls, of APSS's best scale, their ratio (the target: at most 0.8 in every cell), the
best single candidate and the advisor's regret per cloud.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import points_accuracy as pa  # noqa: E402
import points_wide_ranges as pw  # noqa: E402


def run_cloud(job) -> dict:
    """The advice on one cloud, its error, every candidate's and APSS's at every scale."""
    import curv
    from curv.advice.clouds import cloud_candidates, cloud_features, usable_points
    from curv.point_normals import point_normals

    function, noise, sample, s_index = job
    sampling = pa.SAMPLINGS[s_index]
    cloud, _, ev, t1, t2 = pw.protocol_cloud(function, noise, sample, s_index)
    points = cloud.points
    t0 = time.perf_counter()
    adv = curv.advise(cloud, vertices=np.flatnonzero(ev))
    seconds = time.perf_counter() - t0
    errors = {}
    for cand in cloud_candidates(cloud, cloud_features(cloud, usable_points(cloud)), 1.0):
        res = curv.estimate(cloud, **cand.kwargs)
        errors[cand.key] = pa._errors(t1, t2, res.k1[ev], res.k2[ev])
    advised = errors[adv.best.key]
    normals = point_normals(cloud).normals
    for scale in pw.APSS_SCALES:
        k1, k2, _, _ = pa.apss_curvature(points, normals, scale)
        errors[f"APSS scale {scale:g}"] = pa._errors(t1, t2, k1[ev], k2[ev])
    return {"cell": (sampling, noise), "function": function, "sample": sample, "errors": errors,
            "advised": adv.best.key, "advised_errors": advised, "measured": adv.best.measured_erel,
            "noise_measured": adv.features.noise, "evaluated": int(ev.sum()), "advise_seconds": seconds,
            "ties": [c.key for c in adv.ranking if c.within_noise]}


def call_name(key: str) -> str:
    """A candidate's key with its absolute radius (a multiple of each cloud's own spacing, so a
    different number on every cloud) written ``radius=*``: the same call on every cloud."""
    import re

    return re.sub(r"radius=[^;]+", "radius=*", key)


def _same_calls(rows: list) -> list:
    """The rows with their candidates' keys by :func:`call_name`."""
    return [{**r, "advised": call_name(r["advised"]), "errors": {call_name(k): v for k, v in r["errors"].items()}}
            for r in rows]


def _median(pooled: list) -> float:
    e = np.concatenate([p["e_rel"] for p in pooled])
    e = e[np.isfinite(e)]
    return float(np.median(e)) if e.size else float("nan")


def report(rows: list) -> str:
    lines = ["| cell | clouds | advised (pooled median e_rel) | APSS best scale | APSS median | advised / APSS | "
             "20 % ahead? | best single candidate | its median | advisor regret per cloud: median / max |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    rows = _same_calls(rows)
    for cell in sorted({r["cell"] for r in rows}):
        rs = [r for r in rows if r["cell"] == cell]
        ours = _median([r["advised_errors"] for r in rs])
        apss = {k: _median([r["errors"][k] for r in rs]) for k in rs[0]["errors"] if k.startswith("APSS")}
        best_apss = min(apss, key=apss.get)
        cands = {k: _median([r["errors"][k] for r in rs]) for k in rs[0]["errors"] if not k.startswith("APSS")}
        best_cand = min(cands, key=cands.get)
        regrets = []
        for r in rs:
            own = {k: np.nanmedian(v["e_rel"]) for k, v in r["errors"].items() if not k.startswith("APSS")}
            regrets.append(own[r["advised"]] / min(own.values()))
        ratio = ours / apss[best_apss]
        lines.append(f"| {pa.cell_name(cell)} | {len(rs)} | {ours:.4g} | {best_apss} | {apss[best_apss]:.4g} | "
                     f"{ratio:.2f} | {'yes' if ratio <= 0.8 else 'no'} | {best_cand} | {cands[best_cand]:.4g} | "
                     f"{np.median(regrets):.2f} / {np.max(regrets):.2f} |")
    lines += ["", "Advised calls per cell (radius=*: the call's multiple of each cloud's spacing): "]
    for cell in sorted({r["cell"] for r in rows}):
        picks = [r["advised"] for r in rows if r["cell"] == cell]
        counts = {p: picks.count(p) for p in dict.fromkeys(picks)}
        lines.append(f"- {pa.cell_name(cell)}: " + ", ".join(f"{k} ({v})" for k, v in counts.items()))
    return "\n".join(lines)


def _init_worker():
    os.environ["CURV_THREADS"] = "1"


def main(argv=None) -> int:
    import json
    from concurrent.futures import ProcessPoolExecutor

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("samples", type=int, help="random surfaces per function")
    parser.add_argument("--first", type=int, default=0, help="first surface (0: the tables' ones)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--runs", help="also write every cloud's numbers here (JSON)")
    parser.add_argument("--report", help="only the report, from a --runs file")
    parser.add_argument("--functions", nargs="+", choices=pa.FUNCTIONS, default=pa.FUNCTIONS,
                        help="only these surfaces' clouds")
    parser.add_argument("--noises", nargs="+", type=float, choices=pa.NOISES, default=pa.NOISES,
                        help="only these noise levels")
    parser.add_argument("--samplings", nargs="+", choices=pa.SAMPLINGS, default=pa.SAMPLINGS,
                        help="only these samplings")
    args = parser.parse_args(argv)
    if args.report:
        rows = json.loads(Path(args.report).read_text())
        for r in rows:
            r["cell"] = tuple(r["cell"])
            r["errors"] = {k: {m: np.asarray(v, float) for m, v in e.items()} for k, e in r["errors"].items()}
            r["advised_errors"] = {m: np.asarray(v, float) for m, v in r["advised_errors"].items()}
        print(report(rows) + f"\n\nFrom `{args.report}`; advice {np.median([r['advise_seconds'] for r in rows]):.1f} s "
              "per cloud (median).")
        return 0
    t0 = time.perf_counter()
    jobs = [(fn, noise, s, pa.SAMPLINGS.index(sampling)) for noise in args.noises for fn in args.functions
            for s in range(args.first, args.first + args.samples) for sampling in args.samplings]
    rows = []
    with ProcessPoolExecutor(args.workers, initializer=_init_worker) as ex:
        for row in ex.map(run_cloud, jobs):
            rows.append(row)
            print(f"\r{len(rows)}/{len(jobs)} clouds", end="", flush=True)
    print()
    if args.runs:
        Path(args.runs).write_text(json.dumps(
            [{**r, "errors": {k: {m: np.asarray(v).tolist() for m, v in e.items()} for k, e in r["errors"].items()},
              "advised_errors": {m: np.asarray(v).tolist() for m, v in r["advised_errors"].items()}} for r in rows],
            default=float))
    text = report(rows)
    cmd = "benchmarks/bench_advise_points.py " + " ".join(sys.argv[1:] if argv is None else argv)
    print(text + f"\n\nCommand: `{cmd}`; {len(jobs)} clouds in {time.perf_counter() - t0:.0f} s wall, "
          f"{args.workers} workers; advice {np.median([r['advise_seconds'] for r in rows]):.1f} s per cloud (median).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
