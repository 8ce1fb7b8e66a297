"""Held-out validation of the advisor (:func:`curv.advise`): regret against the best candidate.

Run by hand (not part of the test suite)::

    .venv/bin/python benchmarks/bench_advisor.py --quick            # 48 meshes of at most ~3700 vertices
    .venv/bin/python benchmarks/bench_advisor.py --meshes 80 --seed 11000 --workers 1 --runs runs11000.json   # docs/ADVISOR.md
    .venv/bin/python benchmarks/bench_advisor.py --meshes 60 --seed 2000 --workers 2 --runs runs2000.json
    .venv/bin/python benchmarks/bench_advisor.py --rescore runs.json --table other.json  # another table, same meshes
    .venv/bin/python benchmarks/bench_advisor.py --refeature old.json --runs new.json  # add the residual measures to old runs
    .venv/bin/python benchmarks/bench_advisor.py --twin-bound [--table other.json]    # the table's own bound, no runs
    .venv/bin/python benchmarks/bench_advisor.py --twin-bound --noise-draws 90 --workers 1 --runs draws.json

Held-out meshes, drawn from seeds the table never used (``--seed``, default 1000; the table's study
uses seed 0) and at settings between and beyond the table's grid points: noise level 0 for
:data:`NOISE_FREE_SHARE` of the meshes, else uniform in 0 to 1.3 of the paper's 100 %, continuous
irregularity (0 to 30 degrees), hexagon densities 3 s (s + 1) + 1 with the vertex count
log-uniform over s = 8..81 (217 to 19,927 vertices), three quarters Monge patches of eq. 5.1 (the
study's meshes, :func:`curv.study.testmesh.build_test_mesh`, evaluated away from the border by
:func:`tools.advice_table.extend.evaluated_for_table`, the study's R4 rule where it leaves 30 vertices),
one quarter closed analytic surfaces of random shape
(:func:`tools.advice_table.base.random_closed_params`: sphere radius, ellipsoid semi-axes, torus tube
radius) at the same vertex counts (a geodesic sphere or ellipsoid snaps to the nearest
10 f^2 + 2, so sizes between the table's 642, 2562 and 10242 too; every vertex evaluated; no
irregularity option). Truth is exact (:mod:`curv.surfaces`). Per mesh every candidate call (the
table's and :func:`tools.advice_table.extend.option_variants`) is run and scored by the median e_rel over
the evaluated vertices it gives a value for (the study's ``median_erel``), and each call's valid
share on the mesh is stored (:func:`curv.advice.shares.valid_shares`).

Reported: regret = median e_rel of the advised call / the best median e_rel over the calls the
ranking admits first (within :data:`curv.advice.shares.VALID_SHARE_SLACK` of the best valid share;
errors below the table's ``erel_floor``, 1e-6, count as the floor: rounding, as in the advisor)
(median, 90th percentile, share within 1.05), overall and for subsets (patches, closed surfaces,
settings inside or beyond the table's grid, nearly noise-free); the advisor's mean error against
that of every fixed choice (the best fixed choices named); the regret of a few fixed choices for
scale; how close the noise estimate is to the true noise (share within +-25 % at and above a third
of the paper's level) and the irregularity estimate to the 3D irregularity of the same mesh without
noise (what the noise correction should recover) and to the planar irregularity the patch was made
with. ``--rescore`` re-advises the meshes of a ``--runs`` file from their stored raw measures with
another table (the estimators' errors do not depend on the table): it compares tables on the
same held-out meshes in a second, and must not be used to tune a table on them. ``--twin-bound``
runs nothing: on the table's own meshes it scores each mesh with the best call of the other random
surfaces made at its setting (:func:`twin_regrets`), what a rule that knew the setting exactly
could reach, beside the advisor's leave-one-out; with ``--noise-draws`` it also runs every candidate
on fresh noise draws of table meshes (:func:`noise_draw_report`).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FIXED_SHOWN = ("jet:R4", "jet:R4;degree=4", "icc:R4;fit_range=4;normals=fit", "mru:R2", "mru:R4", "qs:R3")
CLOSED = ("sphere", "ellipsoid", "torus")
NOISE_FREE_SHARE = 0.15
"""Share of the held-out meshes drawn without noise (the advisor's weak spot gets its own sample)."""
MONGE = ("quadratic", "ellipsoid_patch", "trigonometric")


def draw_settings(n: int, seed: int, *, s_range=(8, 81)) -> list[dict]:
    """``n`` held-out mesh settings from one random stream (the shapes of closed surfaces too); the
    vertex count log-uniform over the hexagons of ``s_range`` (s = 8, 81: 217 to 19,927 vertices)."""
    from tools.advice_table.base import random_closed_params

    rng = np.random.default_rng([seed, 42])
    lo, hi = (np.log(3 * s * (s + 1) + 1) for s in s_range)
    out = []
    for i in range(n):
        closed = rng.random() < 0.25
        target = np.exp(rng.uniform(lo, hi))
        s = int(np.clip(round((-3 + np.sqrt(9 + 12 * (target - 1))) / 6), *s_range))
        function = str(rng.choice(CLOSED if closed else MONGE))
        out.append({
            "index": i, "seed": seed + i, "function": function, "closed": bool(closed),
            "n_vertices": 3 * s * (s + 1) + 1,
            "noise_level": 0.0 if rng.random() < NOISE_FREE_SHARE else float(rng.uniform(0.0, 1.3)),
            "irregularity": 0.0 if closed else float(rng.uniform(0.0, 30.0)),
            "params": random_closed_params(function, rng) if closed else {},
        })
    return out


def _mesh(setting: dict, noise_level: float):
    """(mesh, truth, evaluated, planar irregularity) of a setting at ``noise_level`` (the same mesh
    and noise directions at every level)."""
    from curv.study.protocol import NOISE_FRACTION, Task
    from curv.study.testmesh import build_test_mesh
    from curv.surfaces import make_surface

    from tools.advice_table.extend import evaluated_for_table

    if setting["closed"]:
        s = make_surface(setting["function"], n_vertices=setting["n_vertices"],
                         noise=noise_level * NOISE_FRACTION, seed=setting["seed"], **setting["params"])
        return s.mesh, s.truth, np.ones(s.mesh.n_vertices, bool), float("nan")
    tm = build_test_mesh(Task(setting["seed"], setting["function"], setting["n_vertices"],
                              setting["irregularity"], noise_level, 0))
    return tm.mesh, tm.truth, evaluated_for_table(tm.mesh), tm.irregularity


def evaluate(setting: dict) -> dict:
    """Every candidate's median e_rel on one held-out mesh, the advisor's answer (self-checked) and the
    table's first choice alone (``check=False``)."""
    from curv import advise
    from curv.advice.features import RESIDUAL_MEASURES, SHAPE_MEASURES, angle_deviation_deg, fan_triangles
    from curv.advice.prediction import load_table
    from curv.advice.shares import valid_shares
    from tools.advice_table.extend import option_variants, variant_errors

    mesh, truth, evaluated, irr_true = _mesh(setting, setting["noise_level"])
    clean = _mesh(setting, 0.0)[0]
    table = load_table(setting.get("table"))
    variants = list(dict.fromkeys([*table["variants"], *option_variants()]))
    t0 = time.perf_counter()
    adv = advise(mesh, table=table)
    t_adv = time.perf_counter() - t0
    table_only = advise(mesh, table=table, check=False).best.variant.id
    erel = variant_errors(mesh, truth, evaluated, variants)  # a failing candidate (NaN) cannot be the best one
    raw = {k: getattr(adv.features, k) for k in ("noise_raw", "irregularity_raw_deg", "density", "border_share",
                                                 *SHAPE_MEASURES, *RESIDUAL_MEASURES)}
    return {**setting, "erel": erel, "advised": adv.best.variant.id, "advised_table": table_only,
            "expected": adv.expected_erel, "raw": raw,
            "shares": valid_shares(mesh, variants), "n_evaluated": int(evaluated.sum()),
            "noise_est": adv.features.noise, "irr_est": adv.features.irregularity_deg,
            "density_est": adv.features.density, "irr_true": irr_true,
            "ranking": [c.as_dict() for c in adv.ranking],  # the checks, for bench_advise_rules.py's replays
            "irr_clean_3d": angle_deviation_deg(clean.vertices, fan_triangles(clean)), "advise_seconds": t_adv}


def _regret_row(label: str, regret: np.ndarray, erel: np.ndarray) -> str:
    """One markdown row: median and p90 regret, share within 1.05, mean median e_rel."""
    return (f"| {label} | {np.nanmedian(regret):.3f} | {np.nanpercentile(regret, 90):.3f} | "
            f"{100 * np.mean(regret <= 1.05):.0f} % | {np.nanmean(erel):.4f} |")


def beyond_grid(runs: list[dict], table: dict) -> np.ndarray:
    """(m,) bool: meshes whose setting lies outside the table's grid (noise, irregularity or density)."""
    grid = table["metadata"]["settings"]
    densities = list(grid["densities"]) + list(table["metadata"].get("coarse", {}).get("densities", []))
    noise = np.array([r["noise_level"] for r in runs])
    irr = np.array([r["irregularity"] for r in runs])
    n = np.array([r["n_vertices"] for r in runs])
    return (noise > max(grid["noise"])) | (irr > max(grid["irregularity"])) | (n < min(densities)) | (
        n > max(densities))


def admissible(runs: list[dict], variants: list[str]) -> np.ndarray:
    """(m, v) bool: the candidates the ranking puts first on each mesh, those within
    :data:`curv.advice.shares.VALID_SHARE_SLACK` of the best valid share (what regret compares against)."""
    from curv.advice.shares import VALID_SHARE_SLACK

    S = np.array([[r.get("shares", {}).get(v, 1.0) for v in variants] for r in runs], float)
    return S >= S.max(axis=1, keepdims=True) - VALID_SHARE_SLACK


def summarize_runs(runs: list[dict], table: dict | None = None) -> tuple[str, dict]:
    """The markdown report and its numbers.

    Parameters
    ----------
    runs : list of dict
        :func:`evaluate` of every held-out mesh.
    table : dict, optional
        The advisor table validated (for the grid's bounds); default the packaged one.
    """
    from curv.advice.prediction import load_table
    from curv.study.protocol import NOISE_FRACTION

    table = load_table() if table is None else table
    variants = list(runs[0]["erel"])
    E = np.array([[r["erel"][v] for v in variants] for r in runs], float)
    # below the table's floor an error is rounding (nc R1 and mru R4 on a noise-free sphere: 1e-14 and
    # 4e-16), and every such call is as good as the others: the advisor says so, the regret too
    floor = table["kernel"].get("erel_floor", 0.0)
    E = np.where(E > 0, np.maximum(E, floor), np.nan)
    best = np.nanmin(np.where(admissible(runs, variants), E, np.nan), axis=1)
    adv = np.array([r["erel"].get(r["advised"], np.nan) for r in runs], float)
    adv = np.where(adv > 0, np.maximum(adv, floor), np.nan)
    regret = adv / best
    fixed_mean = {v: float(np.nanmean(E[:, j])) for j, v in enumerate(variants) if np.isfinite(E[:, j]).all()}
    ranked_fixed = sorted(fixed_mean, key=fixed_mean.get)
    best_fixed = ranked_fixed[0]
    adv_mean = float(np.nanmean(adv))

    noise_true = np.array([r["noise_level"] * NOISE_FRACTION for r in runs])
    noise_est = np.array([r["noise_est"] for r in runs])
    big = noise_true >= NOISE_FRACTION / 3
    rel = np.abs(noise_est[big] / noise_true[big] - 1)
    closed = np.array([r["closed"] for r in runs])
    irr_est = np.array([r["irr_est"] for r in runs])
    irr_clean = np.array([r["irr_clean_3d"] for r in runs])
    irr_planar = np.array([r["irr_true"] for r in runs])
    d_clean = np.abs(irr_est - irr_clean)
    d_planar = np.abs(irr_est - irr_planar)[~closed]
    outside = beyond_grid(runs, table)
    small_noise_error = (np.median(np.abs(noise_est[~big] - noise_true[~big])) / NOISE_FRACTION if (~big).any()
                         else float("nan"))
    numbers = {
        "meshes": len(runs), "median_regret": float(np.nanmedian(regret)),
        "worst_index": int(runs[int(np.nanargmax(regret))]["index"]),
        "p90_regret": float(np.nanpercentile(regret, 90)), "max_regret": float(np.nanmax(regret)),
        "advisor_failed": int(np.sum(~np.isfinite(adv))), "advisor_mean_erel": adv_mean,
        "best_fixed": best_fixed, "best_fixed_mean_erel": fixed_mean[best_fixed],
        "gain_vs_best_fixed": 1 - adv_mean / fixed_mean[best_fixed],
        "noise_within_25pct": float(np.mean(rel <= 0.25)), "noise_median_rel_error": float(np.median(rel)),
        "noise_p90_rel_error": float(np.percentile(rel, 90)),
        "noise_clean_max": float(noise_est[noise_true == 0].max()) if (noise_true == 0).any() else float("nan"),
        "irr_median_abs_diff_clean": float(np.median(d_clean)),
        "irr_p90_abs_diff_clean": float(np.percentile(d_clean, 90)),
        "irr_median_abs_diff": float(np.median(d_planar)) if d_planar.size else float("nan"),
    }
    lines = [
        f"Held-out meshes: {len(runs)} ({int(closed.sum())} closed, {int(outside.sum())} with a setting beyond "
        f"the table's grid), candidates: {len(variants)}.",
        "",
        "| choice | median regret | p90 regret | regret <= 1.05 | mean median e_rel |",
        "|---|---|---|---|---|",
        _regret_row("**advisor**", regret, adv),
    ]
    if all("advised_table" in r for r in runs):  # the table's first choice, before the self-check
        tab = np.array([r["erel"].get(r["advised_table"], np.nan) for r in runs], float)
        tab = np.where(tab > 0, np.maximum(tab, floor), np.nan)
        numbers.update(table_median_regret=float(np.nanmedian(tab / best)),
                       table_p90_regret=float(np.nanpercentile(tab / best, 90)),
                       table_max_regret=float(np.nanmax(tab / best)))
        lines.append(_regret_row("the table alone (check=False)", tab / best, tab))
    for v in dict.fromkeys([*ranked_fixed[:3], *FIXED_SHOWN]):
        if v in variants:
            j = variants.index(v)
            tag = " (best fixed)" if v == best_fixed else (" (2nd best fixed)" if v == ranked_fixed[1] else "")
            lines.append(_regret_row(f"always {v}{tag}", E[:, j] / best, E[:, j]))
    n_vertices = np.array([r["n_vertices"] for r in runs])
    subsets = (("Monge patches", ~closed), ("closed surfaces", closed), ("inside the grid", ~outside),
               ("beyond the grid", outside), ("217-816 vertices", n_vertices < 817),
               ("817-12481 vertices", (n_vertices >= 817) & (n_vertices <= 12481)),
               ("above 12481 vertices", n_vertices > 12481), ("noise-free", noise_true == 0),
               ("noise < 0.1 of the paper's", noise_true < 0.1 * NOISE_FRACTION))
    for label, mask in subsets:
        if mask.any():
            lines.append(_regret_row(f"advisor, {label} ({int(mask.sum())})", regret[mask], adv[mask]))
    lines += [
        "",
        f"Advisor mean error {100 * numbers['gain_vs_best_fixed']:.1f} % below the best fixed choice ({best_fixed}, "
        f"best of {len(fixed_mean)} candidates as fixed choices); largest regret {numbers['max_regret']:.2f}; "
        f"the advised variant gave no value on {numbers['advisor_failed']} meshes.",
        f"Noise estimate at and above a third of the paper's level ({int(big.sum())} meshes): "
        f"{100 * numbers['noise_within_25pct']:.1f} % within +-25 %, relative error median "
        f"{100 * numbers['noise_median_rel_error']:.1f} %, p90 {100 * numbers['noise_p90_rel_error']:.1f} %; "
        f"below a third ({int((~big).sum())}): median |estimate - truth| "
        f"{small_noise_error:.3f} of the paper's level.",
        "Irregularity: median |estimate - 3D irregularity of the noise-free mesh| "
        f"{numbers['irr_median_abs_diff_clean']:.1f} degrees (p90 {numbers['irr_p90_abs_diff_clean']:.1f}); Monge patches against the planar target the mesh "
        f"was made with: median {numbers['irr_median_abs_diff']:.1f} degrees (the 3D measure includes the lift's "
        "distortion, see curv.advice.features.MeshFeatures).",
    ]
    return "\n".join(lines), numbers


def setting_twins(keys) -> list[np.ndarray]:
    """The table's meshes grouped by setting: one index array per (surface kind, vertex count,
    irregularity, noise level), its meshes the different random surfaces (a key's seed and sample)
    made at that setting (keys as in :func:`tools.advice_table.extend.table_mesh`)."""
    groups: dict = {}
    for i, k in enumerate(keys):
        groups.setdefault((k[1], int(k[2]), float(k[3]), float(k[4])), []).append(i)
    return [np.array(g) for g in groups.values()]


def twin_regrets(groups, log_values: np.ndarray) -> dict:
    """What a rule that knew a mesh's setting exactly, and nothing else, could reach on the table.

    Each mesh is given the best call of another random surface at its setting (its twin) and, in a
    second reading, the call with the lowest mean log e_rel over all its twins (the best single call
    for the setting, the mesh itself left out), and in a third over the setting's meshes including
    itself (the best setting-level rule fitted on these very meshes: optimistic). The calls admitted
    are those every mesh of the setting has a value for (every candidate runs on every held-out
    mesh; in the table some option columns are empty on samples 1 and 2), both for the choice and
    for the best call the regret divides by.

    Parameters
    ----------
    groups : list of (k,) int arrays
        The meshes of one setting each (:func:`setting_twins`; or the noise draws of one mesh,
        :func:`noise_draw_report`).
    log_values : (p, v) float64
        log median e_rel, floored as the advisor floors it (NaN where missing).

    Returns
    -------
    dict
        ``pair_mesh`` (q,) int64 and ``pair_regret`` (q,) float64: one entry per (mesh, twin) pair;
        ``pooled`` and ``in_sample`` (p,) float64: per mesh (NaN where the setting's meshes share
        no call).
    """
    pair_mesh, pair_regret = [], []
    pooled = np.full(len(log_values), np.nan)
    in_sample = np.full(len(log_values), np.nan)
    for group in groups:
        common = np.isfinite(log_values[group]).all(axis=0)
        if not common.any():
            continue
        values = np.where(common, log_values, np.inf)
        for i in group:
            twins = group[group != i]

            def regret(score):  # the mesh's error with the call of the lowest score, over its best
                return np.exp(values[i, np.argmin(np.where(common, score, np.inf))] - values[i].min())

            for j in twins:
                pair_mesh.append(i)
                pair_regret.append(regret(values[j]))
            pooled[i] = regret(values[twins].mean(axis=0))
            in_sample[i] = regret(values[group].mean(axis=0))
    return {"pair_mesh": np.array(pair_mesh, np.int64), "pair_regret": np.array(pair_regret),
            "pooled": pooled, "in_sample": in_sample}


def twin_bound_report(table: dict) -> str:
    """Markdown: the regret of :func:`twin_regrets` on ``table``, overall and per cell family, beside
    the advisor's own leave-one-out regret with each mesh's random surface left out (its kernel and
    features, :func:`tools.advice_table.kernel.loo_regret` by :func:`tools.advice_table.kernel.surface_groups`)."""
    from curv.advice.prediction import log_erel, table_coordinates
    from tools.advice_table.kernel import loo_regret, surface_groups

    keys = table["truth"]["key"]
    log_values = log_erel(table)
    tw = twin_regrets(setting_twins(keys), log_values)
    points = np.array([[np.nan if x is None else x for x in p] for p in table["points"]], float)
    loo = loo_regret(table_coordinates(table, *points.T), log_values, table["kernel"]["bandwidth"],
                     surface_groups(keys))
    closed = np.array([k[1] in CLOSED for k in keys])
    n = np.array([k[2] for k in keys])
    noise = np.array([k[4] for k in keys], float)
    families = [("all", np.ones(len(keys), bool)), ("Monge patches", ~closed), ("closed surfaces", closed)]
    for kind, km in (("patches", ~closed), ("closed", closed)):
        for size, sm in (("< 817 vertices", n < 817), (">= 817 vertices", n >= 817)):
            for nl, nm in (("noise-free", noise == 0), ("noise 0.015-0.1", (noise > 0) & (noise <= 0.1)),
                           ("noise 0.2-1", noise > 0.1)):
                families.append((f"{kind}, {size}, {nl}", km & sm & nm))

    def cells(r):  # p90 / worst / share within 1.3
        r = r[np.isfinite(r)]
        return f" {np.percentile(r, 90):.2f} / {r.max():.2f} / {100 * np.mean(r <= 1.3):.0f} % |" if r.size else " |"

    lines = ["Regret p90 / worst / share <= 1.3 (medians in the text):", "",
             "| table meshes | n | one twin's best call | the twins' pooled best call "
             "| pooled with the mesh itself | the advisor, its surface left out |",
             "|---|---|---|---|---|---|"]
    for label, mask in families:
        if mask.any():
            pair = tw["pair_regret"][mask[tw["pair_mesh"]]]
            lines.append(f"| {label} | {int(mask.sum())} |{cells(pair)}{cells(tw['pooled'][mask])}"
                         f"{cells(tw['in_sample'][mask])}{cells(loo[mask])}")
    missing = int(np.sum(~np.isfinite(tw["pooled"])))
    medians = ", ".join(f"{name} {np.nanmedian(r):.3f}" for name, r in (
        ("one twin", tw["pair_regret"]), ("pooled twins", tw["pooled"]), ("pooled with itself", tw["in_sample"]),
        ("advisor", loo)))
    lines += ["", f"{len(keys)} table meshes in {len(setting_twins(keys))} settings (surface kind, vertex count, "
              f"irregularity, noise level); regret over the best admitted call, errors floored "
              f"at {table['kernel'].get('erel_floor', 0.0):g}; the calls admitted: those every mesh of the setting has "
              f"a value for (the advisor's column: every call the mesh has); {missing} meshes left out (no call "
              f"shared). Median regret overall: {medians}."]
    return "\n".join(lines)

def noise_draw_errors(args: tuple) -> dict:
    """Every candidate's median e_rel on a table mesh with a fresh noise draw.

    Parameters
    ----------
    args : (key, draw, variants)
        A table key (:func:`tools.advice_table.extend.table_mesh`), the draw's seed and the candidates: the
        same surface, tessellation and noise level as the table mesh, the noise drawn from
        ``[key's seed, 91, draw]`` (evaluated as the held-out meshes are).
    """
    from tools.advice_table.extend import evaluated_for_table, table_mesh, variant_errors
    from curv.study.protocol import NOISE_FRACTION

    key, draw, variants = args
    seed, name, n, irr, level, sample = key
    mesh, truth, _ = table_mesh([seed, name, n, irr, 0.0, sample])
    rng = np.random.default_rng([int(seed), 91, int(draw)])
    mesh = mesh.with_vertices(mesh.vertices + rng.normal(scale=level * NOISE_FRACTION * mesh.mean_edge_length,
                                                         size=mesh.vertices.shape))
    return variant_errors(mesh, truth, evaluated_for_table(mesh), variants)


def noise_draw_report(table: dict, n_meshes: int, draws: int, pool, *, seed: int = 5) -> tuple[str, list]:
    """Markdown: :func:`twin_regrets` over noise draws (:func:`noise_draw_errors`) of ``n_meshes`` noisy
    table meshes drawn at random (a third of them below 817 vertices, the rest 817-3169; patches and
    closed surfaces as the table holds them). Two draws differ in nothing a feature of the setting or
    the surface can see, so their regret is what no advice from such features avoids; and the rows."""
    from tools.advice_table.extend import option_variants

    variants = list(dict.fromkeys([*table["variants"], *option_variants()]))
    keys = [k for k in table["truth"]["key"] if k[4] > 0 and k[2] <= 3169]
    rng = np.random.default_rng(seed)
    coarse = [k for k in keys if k[2] < 817]
    dense = [k for k in keys if k[2] >= 817]
    n_coarse = min(len(coarse), (2 * n_meshes) // 3)
    pick = [coarse[i] for i in rng.choice(len(coarse), n_coarse, replace=False)] + [
        dense[i] for i in rng.choice(len(dense), n_meshes - n_coarse, replace=False)]
    jobs = [(k, d, variants) for k in pick for d in range(draws)]
    errors = list(pool.map(noise_draw_errors, jobs))
    rows = [{"key": k, "draw": d, "erel": e} for (k, d, _), e in zip(jobs, errors)]
    floor = table["kernel"].get("erel_floor", 0.0)
    E = np.array([[e.get(v, np.nan) for v in variants] for e in errors], float)
    log_values = np.log(np.where(E > 0, np.maximum(E, floor), np.nan))
    tw = twin_regrets([np.arange(i * draws, (i + 1) * draws) for i in range(len(pick))], log_values)
    n = np.repeat([k[2] for k in pick], draws)
    closed = np.repeat([k[1] in CLOSED for k in pick], draws)
    lines = [f"| noise draws of a table mesh ({draws} each) | meshes | one other draw's best call "
             f"| the other draws' pooled best call |", "|---|---|---|---|"]
    for label, mask in (("all", n > 0), ("patches < 817 vertices", (n < 817) & ~closed),
                        ("patches 817-3169 vertices", (n >= 817) & ~closed), ("closed < 817 vertices", (n < 817) & closed),
                        ("closed 817-3169 vertices", (n >= 817) & closed)):
        if mask.any():
            pair = tw["pair_regret"][mask[tw["pair_mesh"]]]
            cells = [f"{np.median(r):.3f} / {np.percentile(r, 90):.2f} / {r.max():.2f} / {100 * np.mean(r <= 1.3):.0f} %"
                     for r in (pair[np.isfinite(pair)], tw["pooled"][mask][np.isfinite(tw["pooled"][mask])])]
            lines.append(f"| {label} | {int(mask.sum()) // draws} | {cells[0]} | {cells[1]} |")
    lines += ["", "Regret median / p90 / worst / share <= 1.3 over every (mesh, draw); the same surface, "
              "tessellation and noise level, only the noise drawn again."]
    return "\n".join(lines), rows


def residual_row(setting: dict) -> dict:
    """The residual measures (:func:`curv.advice.features.residual_measures`) of a run's mesh, rebuilt
    from its setting (no estimator runs, no score is read)."""
    from curv.advice.features import residual_measures

    return residual_measures(_mesh(setting, setting["noise_level"])[0])


def refeature_runs(runs: list[dict], pool) -> list[dict]:
    """The runs with the residual measures added to their stored raw measures (``raw``), for runs
    made before those measures existed; the other raw measures and the estimators' errors are kept."""
    keep = ("index", "seed", "function", "closed", "n_vertices", "noise_level", "irregularity", "params")
    rows = list(pool.map(residual_row, [{k: r[k] for k in keep} for r in runs]))
    return [{**r, "raw": {**r["raw"], **row}} for r, row in zip(runs, rows)]


def stored_features(raw: dict, table: dict):
    """The :class:`~curv.advice.features.MeshFeatures` of a run's stored raw measures, calibrated by
    ``table`` as :func:`curv.advise` calibrates them (a triangle mesh)."""
    from curv.advice.features import (RESIDUAL_MEASURES, SHAPE_MEASURES, MeshFeatures, calibrate_irregularity,
                                      calibrate_noise)

    cal = table["calibration"]
    noise = calibrate_noise(raw["noise_raw"], cal, raw["density"])
    return MeshFeatures(irregularity_deg=calibrate_irregularity(raw["irregularity_raw_deg"], noise, cal),
                        noise=noise, density=raw["density"], border_share=raw["border_share"],
                        polygon_kinds={3: 1}, noise_raw=raw["noise_raw"],
                        **{k: raw.get(k, float("nan")) for k in (*SHAPE_MEASURES, *RESIDUAL_MEASURES)})


def readvise(runs: list[dict], table: dict) -> list[dict]:
    """The runs with the advice of another table, from their stored raw measures (no estimator runs
    again): the same calibration, prediction and candidates as :func:`curv.advise`."""
    from curv.advice.prediction import predict
    from curv.advice.shares import candidates, rank

    out = []
    for r in runs:  # one prediction per held-out mesh
        feats = stored_features(r["raw"], table)
        pred = predict(table, feats)
        ok = [v for v in candidates(table, feats) if np.isfinite(pred[v])]
        choice = rank({v: pred[v] for v in ok}, r.get("shares", {}))[0]
        out.append({**r, "advised": choice, "expected": pred[choice], "noise_est": feats.noise,
                    "irr_est": feats.irregularity_deg})
    return out


def main(argv=None) -> int:
    from curv.advice.prediction import load_table
    from curv.study.executors import open_executor

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="48 meshes of at most ~3700 vertices")
    parser.add_argument("--meshes", type=int, help="held-out meshes; default 200 (48 with --quick)")
    parser.add_argument("--seed", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--out", help="also write the markdown report here")
    parser.add_argument("--table", help="advisor table JSON to validate; default the packaged one")
    parser.add_argument("--runs", help="also write every mesh's numbers here (JSON)")
    parser.add_argument("--rescore", metavar="RUNS", help="re-advise the meshes of a --runs file with --table "
                        "instead of running anything (triangle meshes; the estimators' errors are the file's)")
    parser.add_argument("--refeature", metavar="RUNS", help="add the residual measures to the raw measures of a "
                        "--runs file made before they existed (meshes rebuilt, nothing scored) and write it to --runs")
    parser.add_argument("--twin-bound", action="store_true", help="print what a rule knowing each table mesh's "
                        "setting could reach: each mesh given its twins' best calls (--table or the packaged one)")
    parser.add_argument("--noise-draws", type=int, metavar="N", help="with --twin-bound: also run every candidate "
                        "on 4 fresh noise draws of N noisy table meshes (--runs: where to keep their errors)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    if args.twin_bound:
        text = twin_bound_report(load_table(args.table))
        if args.noise_draws:
            with open_executor(workers=args.workers) as pool:
                more, rows = noise_draw_report(load_table(args.table), args.noise_draws, 4, pool)
            if args.runs:
                Path(args.runs).write_text(json.dumps(rows, default=float))
            cmd = "benchmarks/bench_advisor.py " + " ".join(sys.argv[1:] if argv is None else argv)
            text += f"\n\n{more}\n\nCommand: `{cmd}`; {time.perf_counter() - t0:.0f} s wall with {args.workers} workers."
        print(text)
        return 0
    if args.refeature:
        if not args.runs:
            parser.error("--refeature needs --runs (where to write)")
        with open_executor(workers=args.workers) as pool:
            runs = refeature_runs(json.loads(Path(args.refeature).read_text()), pool)
        Path(args.runs).write_text(json.dumps(runs, default=float))
        print(f"wrote {args.runs}: {len(runs)} runs, {time.perf_counter() - t0:.0f} s wall")
        return 0
    table = load_table(args.table)
    if args.rescore:
        runs = readvise(json.loads(Path(args.rescore).read_text()), table)
    else:
        n, s_range = (48, (8, 34)) if args.quick else (200, (8, 81))
        n = args.meshes or n
        settings = [{**s, "table": args.table} for s in draw_settings(n, args.seed, s_range=s_range)]
        runs = []
        with open_executor(workers=args.workers) as pool:  # one kernel thread per worker
            for run in pool.map(evaluate, settings):
                runs.append(run)
                if args.runs:  # as they come, so that a long run can be read (--rescore) before it ends
                    Path(args.runs).write_text(json.dumps(runs, default=float))
    text, _ = summarize_runs(runs, table)
    if args.runs:
        Path(args.runs).write_text(json.dumps(runs, default=float))
    cmd = "benchmarks/bench_advisor.py " + " ".join(sys.argv[1:] if argv is None else argv)
    text += f"\n\nCommand: `{cmd}`; {time.perf_counter() - t0:.0f} s wall with {args.workers} workers."
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
