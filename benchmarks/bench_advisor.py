"""Held-out validation of the advisor (:func:`curv.advise`): regret against the best candidate.

Run by hand (not part of the test suite)::

    .venv/bin/python benchmarks/bench_advisor.py --quick            # 48 meshes, about 1-2 minutes on 2 cores
    .venv/bin/python benchmarks/bench_advisor.py --meshes 400 --out docs/advisor_validation.md

Held-out meshes, drawn from seeds the table never used (``--seed``, default 1000) and at settings
between and beyond the table's grid points: continuous noise level (0 to 1.3 of the paper's 100 %),
continuous irregularity (0 to 30 degrees), hexagon densities 3 s (s + 1) + 1 for a random s (the
table has 817 and 3169 only), three quarters Monge patches of eq. 5.1 (the study's meshes,
:func:`curv.study.testmesh.build_test_mesh`, evaluated away from the border as in the study), one
quarter closed analytic surfaces (sphere of random radius, ellipsoid, torus, every vertex evaluated;
no irregularity option). Truth is exact (:mod:`curv.surfaces`). Per mesh every candidate of the
table is run (Max normals) and scored by the median e_rel over the evaluated vertices it gives a
value for (the study's ``median_erel``).

Reported: regret = median e_rel of the advised variant / the best median e_rel over all candidates
(median, 90th percentile); the advisor's mean error against that of every fixed choice (the best
fixed choice named); the regret of a few fixed choices for scale; how close the noise estimate is to
the true noise (share within +-25 % at and above a third of the paper's level) and the irregularity
estimate to the planar irregularity the mesh was made with.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FIXED_SHOWN = ("mru:R2", "mru:R3", "mru:R4", "csm:R3", "qs:R3", "jet:R3")
CLOSED = ("sphere", "ellipsoid", "torus")
MONGE = ("quadratic", "ellipsoid_patch", "trigonometric")


def draw_settings(n: int, seed: int, *, s_range=(15, 40)) -> list[dict]:
    """``n`` held-out mesh settings from one random stream."""
    rng = np.random.default_rng([seed, 42])
    out = []
    for i in range(n):
        closed = rng.random() < 0.25
        s = int(rng.integers(s_range[0], s_range[1] + 1))
        out.append({
            "index": i, "seed": seed + i,
            "function": str(rng.choice(CLOSED if closed else MONGE)), "closed": bool(closed),
            "n_vertices": 3 * s * (s + 1) + 1, "noise_level": float(rng.uniform(0.0, 1.3)),
            "irregularity": 0.0 if closed else float(rng.uniform(0.0, 30.0)),
            "radius": float(rng.uniform(0.5, 3.0)),
        })
    return out


def _mesh(setting: dict):
    """(mesh, truth, evaluated, true planar irregularity)."""
    from curv.study.protocol import NOISE_FRACTION, Task
    from curv.study.testmesh import build_test_mesh
    from curv.surfaces import make_surface

    if setting["closed"]:
        params = {"radius": setting["radius"]} if setting["function"] == "sphere" else {}
        s = make_surface(setting["function"], n_vertices=setting["n_vertices"],
                         noise=setting["noise_level"] * NOISE_FRACTION, seed=setting["seed"], **params)
        return s.mesh, s.truth, np.ones(s.mesh.n_vertices, bool), float("nan")
    tm = build_test_mesh(Task(setting["seed"], setting["function"], setting["n_vertices"],
                              setting["irregularity"], setting["noise_level"], 0))
    return tm.mesh, tm.truth, tm.evaluated, tm.irregularity


def evaluate(setting: dict) -> dict:
    """Every candidate's median e_rel on one held-out mesh, and the advisor's answer."""
    from curv import advise, estimate
    from curv.advisor import load_table
    from curv.normals import vertex_normals
    from curv.study.metrics import summarize
    from curv.study.protocol import Variant

    mesh, truth, evaluated, irr_true = _mesh(setting)
    table = load_table(setting.get("table"))
    variants = table["variants"]
    t0 = time.perf_counter()
    adv = advise(mesh, table=table)
    t_adv = time.perf_counter() - t0
    normals = vertex_normals(mesh)
    erel = {}
    for vid in variants:
        v = Variant.from_id(vid)
        try:
            res = estimate(mesh, method=v.method, range=v.range, normals=normals)
            erel[vid] = summarize(truth, res, evaluated)["median_erel"]
        except Exception:  # a failing candidate cannot be the best one
            erel[vid] = float("nan")
    return {**setting, "erel": erel, "advised": f"{adv.method}:R{adv.range}", "expected": adv.expected_erel,
            "noise_est": adv.features.noise, "irr_est": adv.features.irregularity_deg,
            "density_est": adv.features.density, "irr_true": irr_true, "advise_seconds": t_adv}


def summarize_runs(runs: list[dict]) -> tuple[str, dict]:
    """The markdown report and its numbers."""
    from curv.study.protocol import NOISE_FRACTION

    variants = list(runs[0]["erel"])
    E = np.array([[r["erel"][v] for v in variants] for r in runs], float)
    E = np.where(E > 0, E, np.nan)
    best = np.nanmin(E, axis=1)
    adv = np.array([r["erel"][r["advised"]] for r in runs], float)
    regret = adv / best
    fixed_mean = {v: float(np.nanmean(E[:, j])) for j, v in enumerate(variants) if np.isfinite(E[:, j]).all()}
    best_fixed = min(fixed_mean, key=fixed_mean.get)
    adv_mean = float(np.nanmean(adv))

    noise_true = np.array([r["noise_level"] * NOISE_FRACTION for r in runs])
    noise_est = np.array([r["noise_est"] for r in runs])
    big = noise_true >= NOISE_FRACTION / 3
    rel = np.abs(noise_est[big] / noise_true[big] - 1)
    irr = np.array([(r["irr_est"], r["irr_true"]) for r in runs if not r["closed"]], float)
    numbers = {
        "meshes": len(runs), "median_regret": float(np.nanmedian(regret)),
        "p90_regret": float(np.nanpercentile(regret, 90)), "advisor_mean_erel": adv_mean,
        "best_fixed": best_fixed, "best_fixed_mean_erel": fixed_mean[best_fixed],
        "gain_vs_best_fixed": 1 - adv_mean / fixed_mean[best_fixed],
        "noise_within_25pct": float(np.mean(rel <= 0.25)), "noise_median_rel_error": float(np.median(rel)),
        "noise_clean_max": float(noise_est[noise_true == 0].max()) if (noise_true == 0).any() else float("nan"),
        "irr_median_abs_diff": float(np.median(np.abs(irr[:, 0] - irr[:, 1]))) if len(irr) else float("nan"),
    }
    lines = [
        f"Held-out meshes: {len(runs)} ({sum(r['closed'] for r in runs)} closed), candidates: {len(variants)}.",
        "",
        "| choice | median regret | p90 regret | mean median e_rel |",
        "|---|---|---|---|",
        f"| advisor | {numbers['median_regret']:.3f} | {numbers['p90_regret']:.3f} | {adv_mean:.4f} |",
    ]
    shown = dict.fromkeys([best_fixed, *FIXED_SHOWN])
    for v in shown:
        if v in variants:
            j = variants.index(v)
            rg = E[:, j] / best
            lines.append(f"| always {v}{' (best fixed)' if v == best_fixed else ''} | {np.nanmedian(rg):.3f} | "
                         f"{np.nanpercentile(rg, 90):.3f} | {np.nanmean(E[:, j]):.4f} |")
    for label, mask in (("Monge patches", [not r["closed"] for r in runs]), ("closed surfaces", [r["closed"] for r in runs])):
        mask = np.array(mask)
        if mask.any():
            lines.append(f"| advisor, {label} only ({int(mask.sum())}) | {np.nanmedian(regret[mask]):.3f} | "
                         f"{np.nanpercentile(regret[mask], 90):.3f} | {np.nanmean(adv[mask]):.4f} |")
    lines += [
        "",
        f"Advisor mean error {100 * numbers['gain_vs_best_fixed']:.1f} % below the best fixed choice ({best_fixed}).",
        f"Noise estimate at and above a third of the paper's level ({int(big.sum())} meshes): "
        f"{100 * numbers['noise_within_25pct']:.0f} % within +-25 %, median relative error "
        f"{100 * numbers['noise_median_rel_error']:.1f} %; below a third: median |estimate - truth| "
        f"{np.median(np.abs(noise_est[~big] - noise_true[~big])) if (~big).any() else float('nan'):.4f} mean edges.",
        f"Irregularity (Monge patches): median |3D estimate - planar target| {numbers['irr_median_abs_diff']:.1f} "
        "degrees (the 3D measure includes the lift's distortion, see curv.advisor.MeshFeatures).",
    ]
    return "\n".join(lines), numbers


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="48 meshes of at most ~3700 vertices")
    parser.add_argument("--meshes", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--out", help="also write the markdown report here")
    parser.add_argument("--table", help="advisor table JSON to validate; default the packaged one")
    parser.add_argument("--runs", help="also write every mesh's numbers here (JSON)")
    args = parser.parse_args(argv)
    n, s_range = (48, (15, 34)) if args.quick else (args.meshes, (15, 64))
    settings = [{**s, "table": args.table} for s in draw_settings(n, args.seed, s_range=s_range)]
    t0 = time.perf_counter()
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            runs = list(pool.map(evaluate, settings))
    else:
        runs = [evaluate(s) for s in settings]
    text, _ = summarize_runs(runs)
    if args.runs:
        Path(args.runs).write_text(json.dumps(runs, default=float))
    cmd = "benchmarks/bench_advisor.py " + " ".join(sys.argv[1:] if argv is None else argv)
    text += f"\n\nCommand: `{cmd}`; {time.perf_counter() - t0:.0f} s with {args.workers} workers."
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
