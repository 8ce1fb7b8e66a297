"""Build the advisor's table (``curv/data/advisor_table.json``) from a study run.

The table behind :func:`curv.advise`: a study over a grid of densities, noise levels and
irregularities (the study's own tasks, meshes, runner and metrics), then, on every mesh of that
grid, the advisor's own feature measures. It stores

- ``calibration``: the noise measure's floor, density term and gain
  (``raw² = a² + c density⁴ + (b noise)²``, least squares over all the table's meshes of known noise) and the angle jitter per noise level of the irregularity
  measure (``raw² = clean² + (c level)²``, least squares over each mesh and its noise-free twin);
- ``points``: per mesh, the measured ``(density, noise level, irregularity)``;
- ``median_erel``: per mesh and variant, the median e_rel against the exact curvature;
- ``kernel``: the noise axis transform (linear or square root), the axis scales (standard
  deviation of each coordinate over the points) and the bandwidth, the pair with the lowest
  leave-one-out mean regret (each mesh advised from all the others);
- ``metadata``: the exact command, the settings, the date, timings.

Regenerate (this session's table: 270 study meshes and 90 closed ones, about 3.5 minutes on 2
busy cores from scratch)::

    python -m curv.advisor_table --work /tmp/advisor-study --samples 3 --densities 817 3169 \\
        --noise 0 0.1 0.25 0.5 1 --irregularity 0 12.5 25 --workers 2 \\
        --closed sphere ellipsoid torus --closed-vertices 642 2562

(these are the defaults, so ``python -m curv.advisor_table --work DIR`` is the same run.)
(217 is left out: on its hexagon no vertex is farther than R4 from the border, so the study
evaluates none.) A finer table later: more samples, ``--densities 817 3169 12481``, more noise
and irregularity levels. The study directory resumes, so a long run may be split.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from .advisor import FIT_METHOD, FIT_RANGE, kernel_predict, raw_measures, table_coordinates
from .study.protocol import NOISE_FRACTION, StudySettings, Task, study_variants

__all__ = ["DEFAULT_OUT", "table_settings", "mesh_features", "fit_calibration", "choose_bandwidth",
           "build_table", "main"]

DEFAULT_OUT = Path(__file__).parent / "data" / "advisor_table.json"
BANDWIDTHS = (0.15, 0.25, 0.35, 0.5, 0.7, 1.0, 1.5)
"""Candidate kernel widths in scaled units, tried by leave-one-out."""
NOISE_AXES = ("linear", "sqrt")
"""Candidate transforms of the noise axis, tried by leave-one-out with every bandwidth."""


def table_settings(*, samples: int = 3, densities=(817, 3169), noise=(0.0, 0.1, 0.25, 0.5, 1.0),
                   irregularity=(0.0, 12.5, 25.0), seed: int = 0) -> StudySettings:
    """The study grid of the table: every registry variant at its named ranges, no smoothing variants."""
    selectors = tuple(v.id for v in study_variants(smoothing=False))
    return StudySettings(samples=samples, densities=tuple(densities), noise=tuple(float(x) for x in noise),
                         irregularity=tuple(float(x) for x in irregularity), estimators=selectors, seed=seed)


def mesh_features(task: Task) -> dict:
    """The advisor's raw measures on the mesh of ``task``, with the truth beside them."""
    from .study.testmesh import build_test_mesh

    tm = build_test_mesh(task)
    raw = raw_measures(tm.mesh)
    truth = tm.truth
    scale = np.abs(truth.k1[tm.evaluated]) + np.abs(truth.k2[tm.evaluated])
    return {
        "key": list(task.key), "noise_true": task.noise * NOISE_FRACTION,
        "irregularity_planar": tm.irregularity, "density_true": raw["mean_edge"] * float(np.median(scale)),
        "noise_raw": raw["noise_raw"], "irregularity_raw": raw["irregularity_raw_deg"], "density": raw["density"],
    }


def closed_mesh_point(args: tuple) -> tuple[dict, list[float]]:
    """Raw measures and every variant's median e_rel on one noisy closed analytic surface.

    ``args = (seed, name, n_vertices, noise_level, sample, variant_ids)``; every vertex is
    evaluated (no border). The noise directions depend on (seed, name, n_vertices, sample) only.
    """
    import zlib

    from .api import estimate
    from .normals import vertex_normals
    from .study.metrics import summarize
    from .study.protocol import Variant
    from .surfaces import make_surface

    seed, name, n, level, sample, variant_ids = args
    rng = np.random.default_rng([seed, 7, zlib.crc32(name.encode()), n, sample])
    s = make_surface(name, n_vertices=n, noise=level * NOISE_FRACTION, seed=rng)
    raw = raw_measures(s.mesh)
    scale = np.abs(s.truth.k1) + np.abs(s.truth.k2)
    row = {"key": [seed, name, n, 0.0, float(level), sample], "noise_true": level * NOISE_FRACTION,
           "irregularity_planar": float("nan"), "density_true": raw["mean_edge"] * float(np.median(scale)),
           "noise_raw": raw["noise_raw"], "irregularity_raw": raw["irregularity_raw_deg"], "density": raw["density"]}
    normals, every = vertex_normals(s.mesh), np.ones(s.mesh.n_vertices, bool)
    erel = []
    for vid in variant_ids:
        v = Variant.from_id(vid)
        try:
            erel.append(summarize(s.truth, estimate(s.mesh, method=v.method, range=v.range, normals=normals),
                                  every)["median_erel"])
        except Exception:  # recorded as missing, like a failing variant of the study
            erel.append(float("nan"))
    return row, erel


def closed_points(names, sizes, levels, samples: int, seed: int, variant_ids, workers: int | None):
    """:func:`closed_mesh_point` over every (name, size, level, sample), in a process pool."""
    from concurrent.futures import ProcessPoolExecutor

    jobs = [(seed, nm, int(n), float(lv), s, tuple(variant_ids))
            for s in range(samples) for nm in names for n in sizes for lv in levels]
    if not jobs:
        return [], []
    if workers == 0:
        out = [closed_mesh_point(j) for j in jobs]
    else:
        with ProcessPoolExecutor(workers or None) as pool:
            out = list(pool.map(closed_mesh_point, jobs))
    return [r for r, _ in out], [e for _, e in out]


def fit_calibration(rows: list[dict]) -> dict:
    """Least-squares calibration of the noise and irregularity measures (see the module docstring)."""
    raw = np.array([r["noise_raw"] for r in rows])
    true = np.array([r["noise_true"] for r in rows])
    density = np.array([r["density"] for r in rows])
    design = np.stack([np.ones_like(true), density**4, true**2], axis=1)
    (a2, c4, b2), *_ = np.linalg.lstsq(design, raw**2, rcond=None)
    clean = {tuple(r["key"][:4] + r["key"][5:]): r["irregularity_raw"] for r in rows if r["noise_true"] == 0}
    dl, dy = [], []
    for r in rows:
        base = clean.get(tuple(r["key"][:4] + r["key"][5:]))
        if base is not None and r["noise_true"] > 0:
            dl.append((r["noise_true"] / NOISE_FRACTION) ** 2)
            dy.append(r["irregularity_raw"] ** 2 - base**2)
    dl, dy = np.array(dl), np.array(dy)
    c2 = float(dl @ dy / (dl @ dl)) if dl.size else 0.0
    return {"noise_floor": float(np.sqrt(max(a2, 0.0))), "noise_gain": float(np.sqrt(max(b2, 1e-12))),
            "noise_density4": float(max(c4, 0.0)),
            "irregularity_noise_deg": float(np.sqrt(max(c2, 0.0)))}


def _regret(log_values: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """Median e_rel of the chosen variant over the best one, per mesh."""
    best = np.nanmin(log_values, axis=1)
    return np.exp(log_values[np.arange(len(chosen)), chosen] - best)


def loo_regret(coords: np.ndarray, log_values: np.ndarray, bandwidth: float) -> np.ndarray:
    """(p,) regret of advising each mesh from all the other meshes of the table."""
    chosen = np.empty(len(coords), np.int64)
    for i in range(len(coords)):  # p is a few hundred table meshes, not vertices
        rest = np.arange(len(coords)) != i
        pred = kernel_predict(coords[rest], log_values[rest], coords[i], bandwidth)
        pred = np.where(np.isfinite(pred) & np.isfinite(log_values[i]), pred, np.inf)
        chosen[i] = int(np.argmin(pred))
    return _regret(log_values, chosen)


def choose_bandwidth(coords: np.ndarray, log_values: np.ndarray) -> tuple[float, dict]:
    """The candidate of :data:`BANDWIDTHS` with the lowest leave-one-out mean regret, and all scores."""
    scores = {h: float(np.mean(loo_regret(coords, log_values, h))) for h in BANDWIDTHS}
    return min(scores, key=scores.get), scores


def build_table(settings: StudySettings, work_dir, *, workers: int | None = None, command: str = "",
                closed=(), closed_vertices=(642, 2562)) -> dict:
    """Run (or resume) the study of ``settings`` in ``work_dir`` and turn it into the advisor's table.

    ``closed`` adds closed analytic surfaces (registry names such as ``"sphere"``, ``"torus"``) at
    each of ``closed_vertices`` and each noise level of ``settings``, ``settings.samples`` noise
    draws each: the study's Monge patches cover only a narrow band of densities and none of the
    regular closed tessellations real meshes resemble.
    """
    from .study.runner import run

    t0 = time.perf_counter()
    results = run(settings, work_dir, workers=workers)
    t_study = time.perf_counter() - t0
    variants = [v.id for v in settings.variants()]
    tasks = list(settings.tasks())
    t1 = time.perf_counter()
    rows = [mesh_features(t) for t in tasks]
    t_features = time.perf_counter() - t1

    index = {tuple(r["key"]): i for i, r in enumerate(rows)}
    erel = np.full((len(rows), len(variants)), np.nan)
    col = {v: j for j, v in enumerate(variants)}
    keys = zip(*(results[c] for c in ("seed", "function", "density", "irregularity", "noise", "sample")))
    for key, vid, value in zip(keys, results["variant"], results["median_erel"]):
        i, j = index.get((int(key[0]), str(key[1]), int(key[2]), float(key[3]), float(key[4]), int(key[5]))), col.get(vid)
        if i is not None and j is not None:
            erel[i, j] = value
    t2 = time.perf_counter()
    c_rows, c_erel = closed_points(closed, closed_vertices, settings.noise, settings.samples, settings.seed,
                                   variants, workers)
    t_closed = time.perf_counter() - t2
    if c_rows:
        rows += c_rows
        erel = np.concatenate([erel, np.array(c_erel, float)])
    erel = np.where(erel > 0, erel, np.nan)
    cal = fit_calibration(rows)

    from .advisor import calibrate_irregularity, calibrate_noise

    noise = np.array([calibrate_noise(r["noise_raw"], cal, r["density"]) for r in rows])
    irr = np.array([calibrate_irregularity(r["irregularity_raw"], n, cal) for r, n in zip(rows, noise)])
    points = np.stack([[r["density"] for r in rows], noise / NOISE_FRACTION, irr], axis=1)
    best = None
    for axis in NOISE_AXES:
        noise_coord = np.sqrt(points[:, 1]) if axis == "sqrt" else points[:, 1]
        scales = np.std(np.stack([np.log(points[:, 0]), noise_coord, points[:, 2]], axis=1), axis=0)
        kernel = {"noise_axis": axis, "scales": np.where(scales > 0, scales, 1.0).tolist()}
        coords = table_coordinates({"kernel": kernel}, *points.T)
        bandwidth, scores = choose_bandwidth(coords, np.log(erel))
        kernel.update(bandwidth=bandwidth, loo_mean_regret={str(h): round(s, 4) for h, s in scores.items()})
        if best is None or scores[bandwidth] < best["loo_mean_regret"][str(best["bandwidth"])]:
            best = kernel
    table = {"kernel": best}

    rel = lambda est, true: np.abs(est[true > 0] / true[true > 0] - 1)  # noqa: E731
    true_noise = np.array([r["noise_true"] for r in rows])
    big = true_noise >= NOISE_FRACTION / 3 - 1e-12
    table.update({
        "metadata": {
            "command": command, "settings": settings.as_dict(), "variants_note": "named ranges, no smoothing",
            "created": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "n_meshes": len(rows),
            "fit": f"{FIT_METHOD} R{FIT_RANGE}", "study_seconds": round(t_study, 1),
            "features_seconds": round(t_features, 1), "closed_seconds": round(t_closed, 1),
            "closed": {"surfaces": list(closed), "vertices": list(closed_vertices) if closed else []},
            "noise_relative_error_at_or_above_a_third": {
                "median": float(np.median(rel(noise[big], true_noise[big]))),
                "p90": float(np.percentile(rel(noise[big], true_noise[big]), 90))},
            "noise_abs_error_clean_median": float(np.median(noise[~(true_noise > 0)])),
        },
        "calibration": cal,
        "variants": variants,
        "columns": ["density", "noise_level", "irregularity_deg"],
        "points": np.round(points, 5).tolist(),
        "truth": [{"key": r["key"], "noise_true": r["noise_true"], "irregularity_planar": (round(r["irregularity_planar"], 3) if np.isfinite(r["irregularity_planar"]) else None),
                   "density_true": round(r["density_true"], 5)} for r in rows],
        "median_erel": [[None if not np.isfinite(x) else float(f"{x:.4g}") for x in row] for row in erel],
    })
    return table


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m curv.advisor_table", description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(DEFAULT_OUT), help="table to write; default the packaged one")
    parser.add_argument("--work", default="advisor-study", help="study directory (resumes); default ./advisor-study")
    parser.add_argument("--samples", type=int, default=3)
    parser.add_argument("--densities", type=int, nargs="+", default=[817, 3169])
    parser.add_argument("--noise", type=float, nargs="+", default=[0.0, 0.1, 0.25, 0.5, 1.0])
    parser.add_argument("--irregularity", type=float, nargs="+", default=[0.0, 12.5, 25.0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=None, help="local processes; default the study's")
    parser.add_argument("--closed", nargs="*", default=["sphere", "ellipsoid", "torus"], help="closed surfaces to add (sphere ellipsoid torus)")
    parser.add_argument("--closed-vertices", type=int, nargs="+", default=[642, 2562])
    args = parser.parse_args(argv)
    settings = table_settings(samples=args.samples, densities=args.densities, noise=args.noise,
                              irregularity=args.irregularity, seed=args.seed)
    command = "python -m curv.advisor_table " + " ".join(sys.argv[1:] if argv is None else argv)
    table = build_table(settings, args.work, workers=args.workers, command=command,
                        closed=tuple(args.closed), closed_vertices=tuple(args.closed_vertices))
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w") as fh:
        json.dump(table, fh, separators=(",", ":"))
    meta = table["metadata"]
    print(f"wrote {args.out}: {meta['n_meshes']} meshes x {len(table['variants'])} variants; "
          f"calibration {table['calibration']}; bandwidth {table['kernel']['bandwidth']} "
          f"(LOO mean regret {table['kernel']['loo_mean_regret']}); study {meta['study_seconds']} s, "
          f"features {meta['features_seconds']} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
