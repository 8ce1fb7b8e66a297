"""The base table: a study over the grid, closed surfaces beside it, the advisor's measures on every
mesh, the calibration and the kernel (``python -m tools.advice_table``; see the package's docstring)."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from curv.advice.features import FIT_METHOD, FIT_RANGE, raw_measures
from curv.study.protocol import StudySettings, Task, study_variants
from curv.variants import NOISE_FRACTION

from .kernel import fit_kernel, key_text

DEFAULT_OUT = Path(__file__).resolve().parents[2] / "curv" / "data" / "advisor_table.json"
"""The packaged table (this tool runs from a checkout of the repository)."""

DEFAULT_SAMPLES = 3
DEFAULT_DENSITIES = (817, 1801, 3169, 7057, 12481)
"""Hexagon subdivisions s = 16, 24, 32, 48, 64: about even steps of log density (217 is left out:
on its hexagon no vertex is farther than R4 from the border, so the study evaluates none)."""
DEFAULT_NOISE = (0.0, 0.05, 0.1, 0.2, 0.33, 0.6, 1.0)
"""Noise levels (fractions of the paper's 100 %): about even steps of their square root, the
kernel's noise axis."""
DEFAULT_IRREGULARITY = (0.0, 8.0, 16.0, 25.0)
DEFAULT_CLOSED = ("sphere", "ellipsoid", "torus")
DEFAULT_CLOSED_VERTICES = (642, 2562, 10242)
EREL_DIGITS = 3
"""Significant digits of the stored median e_rel (a relative rounding of at most 0.5 %)."""
POINT_DIGITS = 4
"""Significant digits of the stored point coordinates."""


def table_settings(*, samples: int = DEFAULT_SAMPLES, densities=DEFAULT_DENSITIES, noise=DEFAULT_NOISE,
                   irregularity=DEFAULT_IRREGULARITY, seed: int = 0) -> StudySettings:
    """The study grid of the table: every registry variant at its named ranges, no smoothing variants."""
    selectors = tuple(v.id for v in study_variants(smoothing=False))
    return StudySettings(samples=samples, densities=tuple(densities), noise=tuple(float(x) for x in noise),
                         irregularity=tuple(float(x) for x in irregularity), estimators=selectors, seed=seed)


def mesh_features(task: Task) -> dict:
    """The advisor's raw measures on the mesh of ``task``, with the truth beside them."""
    from curv.study.testmesh import build_test_mesh

    tm = build_test_mesh(task)
    raw = raw_measures(tm.mesh)
    truth = tm.truth
    scale = np.abs(truth.k1[tm.evaluated]) + np.abs(truth.k2[tm.evaluated])
    return {
        "key": list(task.key), "noise_true": task.noise * NOISE_FRACTION,
        "irregularity_planar": tm.irregularity, "density_true": raw["mean_edge"] * float(np.median(scale)),
        "noise_raw": raw["noise_raw"], "irregularity_raw": raw["irregularity_raw_deg"], "density": raw["density"],
    }


def random_closed_params(name: str, rng: np.random.Generator) -> dict:
    """Random shape parameters of a closed surface: a sphere's radius in [0.5, 3] (the measures are
    scale-free, so it only checks that), an ellipsoid's three semi-axes in [0.5, 1.5], a torus's
    tube radius in [0.2, 0.6] of its centre radius 1; other surfaces keep their defaults."""
    if name == "sphere":
        return {"radius": float(rng.uniform(0.5, 3.0))}
    if name == "ellipsoid":
        return dict(zip("abc", rng.uniform(0.5, 1.5, 3).tolist()))
    if name == "torus":
        return {"major": 1.0, "minor": float(rng.uniform(0.2, 0.6))}
    return {}


def closed_mesh_point(args: tuple) -> tuple[dict, dict]:
    """Raw measures and every variant's median e_rel on one noisy closed analytic surface.

    ``args = (seed, name, n_vertices, noise_level, sample, variant_ids)``; every vertex is
    evaluated (no border). The shape (:func:`random_closed_params`) depends on (seed, name, sample)
    and the noise directions on (seed, name, n_vertices, sample) only, so the sizes and noise levels
    of one sample are paired like the study's.

    Returns
    -------
    (dict, dict)
        The row of raw measures (``key`` = ``[seed, name, n_vertices, 0.0, noise_level, sample]``)
        and ``{variant id: median e_rel}`` (NaN where the variant raised).
    """
    import zlib

    from curv.api import estimate
    from curv.geometry.normals import vertex_normals
    from curv.study.metrics import summarize
    from curv.variants import Variant
    from curv.surfaces import make_surface

    seed, name, n, level, sample, variant_ids = args
    params = random_closed_params(name, np.random.default_rng([seed, 8, zlib.crc32(name.encode()), sample]))
    rng = np.random.default_rng([seed, 7, zlib.crc32(name.encode()), n, sample])
    s = make_surface(name, n_vertices=n, noise=level * NOISE_FRACTION, seed=rng, **params)
    raw = raw_measures(s.mesh)
    scale = np.abs(s.truth.k1) + np.abs(s.truth.k2)
    row = {"key": [seed, name, n, 0.0, float(level), sample], "noise_true": level * NOISE_FRACTION,
           "irregularity_planar": float("nan"), "density_true": raw["mean_edge"] * float(np.median(scale)),
           "noise_raw": raw["noise_raw"], "irregularity_raw": raw["irregularity_raw_deg"], "density": raw["density"],
           "params": params}
    normals, every = vertex_normals(s.mesh), np.ones(s.mesh.n_vertices, bool)
    erel = {}
    for vid in variant_ids:
        v = Variant.from_id(vid)
        try:
            erel[vid] = summarize(s.truth, estimate(s.mesh, method=v.method, range=v.range, normals=normals),
                                  every)["median_erel"]
        except Exception:  # recorded as missing, like a failing variant of the study
            erel[vid] = float("nan")
    return row, erel



ROWS_NAME = "advisor_rows.json"
"""The cache of measured rows in the study directory: ``{"measures": MEASURES, "features": {key:
row}, "closed": {key: [row, erel]}}`` (keys are the JSON of the row's key), so a rebuild only
measures what is new."""

MEASURES = f"{FIT_METHOD} R{FIT_RANGE}, closed shapes v1"
"""What the cached rows were measured with; a cache of other measures is discarded. Change it
with :func:`curv.advice.features.raw_measures` or :func:`random_closed_params`."""


def _load_rows(work_dir: Path) -> dict:
    path = work_dir / ROWS_NAME
    cache = json.loads(path.read_text()) if path.exists() else {}
    if cache.get("measures") != MEASURES:
        cache = {"measures": MEASURES, "features": {}, "closed": {}}
    return cache


def _save_rows(work_dir: Path, cache: dict) -> None:
    path = work_dir / ROWS_NAME
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(cache))
    tmp.replace(path)


def study_feature_rows(tasks: list[Task], executor, cache: dict) -> list[dict]:
    """:func:`mesh_features` of every task, from ``cache["features"]`` or computed on ``executor``."""
    have = cache["features"]
    todo = [t for t in tasks if key_text(t.key) not in have]
    for task, row in zip(todo, executor.map(mesh_features, todo)):
        have[key_text(task.key)] = row
    return [have[key_text(t.key)] for t in tasks]


def closed_points(names, sizes, levels, samples: int, seed: int, variant_ids, executor, cache: dict):
    """:func:`closed_mesh_point` over every (name, size, level, sample): rows and (p, v) median e_rel.

    Points already in ``cache["closed"]`` with a value for every variant are not recomputed; the
    largest meshes are submitted first (load balance).
    """
    jobs = [(seed, nm, int(n), float(lv), s, tuple(variant_ids))
            for s in range(samples) for nm in names for n in sorted(sizes, reverse=True) for lv in levels]
    have = cache["closed"]
    key = lambda job: key_text([job[0], job[1], job[2], 0.0, job[3], job[4]])  # noqa: E731
    todo = [j for j in jobs if key(j) not in have or set(variant_ids) - set(have[key(j)][1])]
    for job, (row, erel) in zip(todo, executor.map(closed_mesh_point, todo)):
        have[key(job)] = [row, erel]
    rows = [have[key(j)][0] for j in jobs]
    erel = np.array([[have[key(j)][1][v] for v in variant_ids] for j in jobs], float)
    return rows, erel.reshape(len(jobs), len(variant_ids))


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



def measure_rows(settings: StudySettings, work_dir, *, workers: int | None = None, closed=(),
                 closed_vertices=DEFAULT_CLOSED_VERTICES, progress=None) -> tuple[list[dict], np.ndarray, dict]:
    """Run (or resume) the study of ``settings`` in ``work_dir`` and measure every mesh of the table.

    Parameters
    ----------
    settings : StudySettings
    work_dir : path-like
        The study directory; it also keeps the measured rows (:data:`ROWS_NAME`), so a rerun
        measures only what is new.
    workers : int, optional
        Local processes (``0``: this process); default the study's.
    closed : sequence of str
        Closed analytic surfaces (``"sphere"``, ``"ellipsoid"``, ``"torus"``) added at each of
        ``closed_vertices`` and each noise level of ``settings``, ``settings.samples`` random
        shapes and noise draws each: the study's Monge patches cover a narrow band of densities and
        none of the regular closed tessellations real meshes resemble.
    closed_vertices : sequence of int
    progress : callable, optional
        Called with a short text after each phase.

    Returns
    -------
    rows : list of dict
        Per mesh: key, true noise, planar irregularity, raw measures (:func:`mesh_features`).
    erel : (p, v) float64
        Median e_rel of every variant on every mesh (NaN where missing or not positive).
    seconds : dict
        Wall seconds of the phases run now (``study``, ``features``, ``closed``).
    """
    from curv.study.executors import open_executor
    from curv.study.runner import run

    work_dir = Path(work_dir)
    say = progress or (lambda text: None)
    variants = [v.id for v in settings.variants()]
    tasks = list(settings.tasks())
    seconds = {}
    with open_executor(workers=workers) as ex:
        t0 = time.perf_counter()
        results = run(settings, work_dir, executor=ex)
        seconds["study"] = time.perf_counter() - t0
        say(f"study: {len(tasks)} meshes, {seconds['study']:.0f} s")
        cache = _load_rows(work_dir)
        t0 = time.perf_counter()
        rows = study_feature_rows(tasks, ex, cache)
        seconds["features"] = time.perf_counter() - t0
        _save_rows(work_dir, cache)
        say(f"features: {seconds['features']:.0f} s")
        t0 = time.perf_counter()
        c_rows, c_erel = closed_points(closed, closed_vertices, settings.noise, settings.samples, settings.seed,
                                       variants, ex, cache)
        seconds["closed"] = time.perf_counter() - t0
        _save_rows(work_dir, cache)
        say(f"closed surfaces: {len(c_rows)} meshes, {seconds['closed']:.0f} s")
    erel = _study_erel(results, rows, variants)
    if c_rows:
        rows = rows + c_rows
        erel = np.concatenate([erel, c_erel])
    return rows, np.where(erel > 0, erel, np.nan), seconds


def _study_erel(results, rows: list[dict], variants: list[str]) -> np.ndarray:
    """(p, v) median e_rel of the study's results table, in the order of ``rows`` and ``variants``."""
    index = {tuple(r["key"]): i for i, r in enumerate(rows)}
    col = {v: j for j, v in enumerate(variants)}
    erel = np.full((len(rows), len(variants)), np.nan)
    keys = zip(*(results[c] for c in ("seed", "function", "density", "irregularity", "noise", "sample")))
    for key, vid, value in zip(keys, results["variant"], results["median_erel"]):  # one row per (mesh, variant)
        i = index.get((int(key[0]), str(key[1]), int(key[2]), float(key[3]), float(key[4]), int(key[5])))
        j = col.get(vid)
        if i is not None and j is not None:
            erel[i, j] = value
    return erel


def table_points(rows: list[dict], cal: dict) -> np.ndarray:
    """(p, 3) measured ``(density, noise level, irregularity)`` of the rows under calibration ``cal``."""
    from curv.advice.features import calibrate_irregularity, calibrate_noise

    noise = np.array([calibrate_noise(r["noise_raw"], cal, r["density"]) for r in rows])
    irr = np.array([calibrate_irregularity(r["irregularity_raw"], n, cal) for r, n in zip(rows, noise)])
    return np.stack([[r["density"] for r in rows], noise / NOISE_FRACTION, irr], axis=1)



def _round(x: float, digits: int):
    """``x`` to ``digits`` significant digits for the JSON (None for NaN)."""
    return None if not np.isfinite(x) else float(f"{x:.{digits}g}")


def _percentile(values: np.ndarray, q: float):
    """The ``q`` th percentile to 4 significant digits, None for no values."""
    return _round(float(np.percentile(values, q)), 4) if values.size else None


def table_command(argv, sub: str = "") -> str:
    """The command line stored in a table's metadata: ``python -m tools.advice_table [sub] argv``
    with every path argument reduced to its file name (the directories it ran in are the machine's,
    not the table's)."""
    words = ["python", "-m", "tools.advice_table", *([sub] if sub else []),
             *(Path(a).name if "/" in a and not a.startswith("-") else a for a in argv)]
    return " ".join(words)


def make_table(settings: StudySettings, rows: list[dict], erel: np.ndarray, *, command: str = "",
               closed=(), closed_vertices=(), seconds: dict | None = None) -> dict:
    """The advisor's table from measured ``rows`` and their ``erel`` (see :func:`measure_rows`)."""
    variants = [v.id for v in settings.variants()]
    cal = fit_calibration(rows)
    points = table_points(rows, cal)
    kernel = fit_kernel(points, erel)
    rel = lambda est, true: np.abs(est[true > 0] / true[true > 0] - 1)  # noqa: E731
    true_noise = np.array([r["noise_true"] for r in rows])
    noise = points[:, 1] * NOISE_FRACTION
    big = true_noise >= NOISE_FRACTION / 3 - 1e-12
    seconds = seconds or {}
    return {
        "kernel": kernel,
        "metadata": {
            "command": command, "settings": settings.as_dict(), "variants_note": "named ranges, no smoothing",
            "created": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "n_meshes": len(rows),
            "fit": f"{FIT_METHOD} R{FIT_RANGE}",
            **{f"{k}_seconds": round(v, 1) for k, v in seconds.items()},
            "seconds_note": "wall seconds of this run's phases; a resumed run counts only what it computed",
            "closed": {"surfaces": list(closed), "vertices": list(closed_vertices) if closed else []},
            "noise_relative_error_at_or_above_a_third": {
                "median": _percentile(rel(noise[big], true_noise[big]), 50),
                "p90": _percentile(rel(noise[big], true_noise[big]), 90)},
            "noise_abs_error_clean_median": _percentile(noise[~(true_noise > 0)], 50),
        },
        "calibration": cal,
        "variants": variants,
        "columns": ["density", "noise_level", "irregularity_deg"],
        "points": [[_round(x, POINT_DIGITS) for x in p] for p in points],
        "truth": {"key": [r["key"] for r in rows],
                  "noise_true": [_round(r["noise_true"], 4) for r in rows],
                  "irregularity_planar": [_round(r["irregularity_planar"], 4) for r in rows],
                  "density_true": [_round(r["density_true"], 4) for r in rows]},
        "median_erel": [[_round(x, EREL_DIGITS) for x in row] for row in erel],
    }


def build_table(settings: StudySettings, work_dir, *, workers: int | None = None, command: str = "",
                closed=(), closed_vertices=DEFAULT_CLOSED_VERTICES, progress=None) -> dict:
    """Run (or resume) the study of ``settings`` in ``work_dir`` and turn it into the advisor's table
    (:func:`measure_rows`, then :func:`make_table`)."""
    rows, erel, seconds = measure_rows(settings, work_dir, workers=workers, closed=closed,
                                       closed_vertices=closed_vertices, progress=progress)
    return make_table(settings, rows, erel, command=command, closed=closed, closed_vertices=closed_vertices,
                      seconds=seconds)


