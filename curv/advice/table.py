"""Build the advisor's table (``curv/data/advisor_table.json``) from a study run.

The table behind :func:`curv.advise`: a study over a grid of densities, noise levels and
irregularities (the study's own tasks, meshes, runner and metrics), noisy closed analytic
surfaces of random shape beside it, then, on every mesh, the advisor's own feature measures. It
stores

- ``calibration``: the noise measure's floor, density term and gain
  (``raw² = a² + c density⁴ + (b noise)²``, least squares over all the table's meshes of known
  noise) and the angle jitter per noise level of the irregularity measure
  (``raw² = clean² + (c level)²``, least squares over each mesh and its noise-free twin);
- ``points``: per mesh, the measured ``(density, noise level, irregularity)``;
- ``median_erel``: per mesh and variant, the median e_rel against the exact curvature (3
  significant digits);
- ``kernel``: the noise axis transform (linear or square root), the axis scales (standard
  deviation of each coordinate over the points) and the bandwidth, the pair with the lowest
  leave-one-out mean regret (each mesh advised from all the others);
- ``truth``: per mesh, its key, true noise, planar irregularity and density from the exact
  curvature (for checks; the advisor does not read it);
- ``metadata``: the exact command, the settings, the date, timings.

Regenerate the shipped table (1260 study meshes: hexagon densities 817, 1801, 3169, 7057 and
12481 x noise levels 0, 0.05, 0.1, 0.2, 0.33, 0.6, 1 x irregularities 0, 8, 16, 25 x the three
Monge patches x 3 samples; plus sphere, ellipsoid and torus at 642, 2562 and 10242 vertices x the
same noise levels x 3 random shapes: 1449 meshes; 28.5 CPU-minutes, 32 minutes wall with 2 workers
on 2 cores shared with another study run, from scratch)::

    python -m curv.advice.table --work advisor-study-3 --workers 2

Every grid setting is a default (``--samples``, ``--densities``, ``--noise``,
``--irregularity``, ``--closed``, ``--closed-vertices`` change them).

The shipped table is that base table extended (``extend``) with the option candidates (jet degree
3 and 4 at R2-R4; ``normals="fit"`` at ``fit_range`` 2 and 4 for nc, qs, an, mru, ru, icc) as new
columns, run on every sample-0 mesh of the base table (patches and closed surfaces), and with
coarse meshes as new rows (every candidate): patches
of 217, 331 and 469 vertices, evaluated away from the border at the largest of R4..R1 that leaves
at least 30 vertices, and sphere, ellipsoid and torus at 162, 252 and 362 vertices, one sample
each::

    python -m curv.advice.table extend --base base.json --work advisor-ext --workers 2

Then the option candidates are run on the closed surfaces of the other two samples too (the closed
surfaces are few beside the patches; their option columns were empty there), two more random
surfaces of every coarse setting are added as rows (every candidate: the best call changes fastest
with the surface on coarse meshes), and every mesh is measured again for the shape, tessellation
and raw noise columns (:data:`EXTRA_COLUMNS`: border share, edge length spread, valence spread,
anisotropy, curvature spread, saddle share, uncalibrated noise measure; the meshes are rebuilt from
their keys, only the measuring fit runs), which a forward selection by grouped leave-one-out regret
turns into further kernel axes (:func:`select_axes`)::

    python -m curv.advice.table fill --table extended.json --out filled.json --work advisor-fill --workers 2
    python -m curv.advice.table fill --table filled.json --out coarse.json --kinds --coarse-samples 3 --work advisor-coarse --workers 2
    python -m curv.advice.table refeature --table coarse.json --work advisor-refeature --workers 1

(``base.json``: the base table the first command writes, ``--out base.json``; ``extended.json``
the second's ``--out``). The fill ran 150 meshes (5036 estimates) in 151 s wall with 2 workers,
the coarse fill 630 meshes (42,840 estimates) in about 2 minutes wall with 2 workers, the refeature
measures every mesh (1764 of them took 192 s wall, 102 CPU-s, with 1 worker) and chose the axes in
about 7 minutes more on the loaded machine (two leave-one-outs per trial; a rerun over the same
``--work`` only chooses).

Then the option candidates are run on the patches of samples 1 and 2 at 817, 1801 and 3169
vertices (their option columns were empty: an option call was weighed on other meshes than a named
call), closed surfaces of about 480 vertices (between the coarse 362 and the grid's 642; three
random shapes, every candidate) are added as rows, and the extra columns and axes are measured and
chosen again (the rows of the meshes measured before come from the same ``--work``)::

    python -m curv.advice.table fill --table shipped.json --out options.json --kinds quadratic ellipsoid_patch trigonometric --sizes 817 1801 3169 --work advisor-options --workers 1
    python -m curv.advice.table fill --table options.json --out closed.json --kinds --coarse-samples 3 --coarse-closed-vertices 162 252 362 482 --work advisor-closed --workers 1
    python -m curv.advice.table refeature --table closed.json --work advisor-refeature --workers 1

(504 meshes, 20,160 estimates, 356 CPU-s; 63 meshes, 105 CPU-s; with 1 worker each.) Then the
option candidates are run on the 7057-vertex patches of samples 1 and 2, a noise level between the
grid's 0 and 0.05 of the paper's is added where the noise measure resolves it: the noise twins at
0.015 of every noise-free mesh of 2562-10242 vertices (the same surface, tessellation and noise
directions, :func:`noise_jobs`), every candidate, as rows; and the measures and axes again::

    python -m curv.advice.table fill --out options7057.json --kinds quadratic ellipsoid_patch trigonometric --sizes 7057 --work advisor-twins --workers 1
    python -m curv.advice.table fill --table options7057.json --out twins.json --kinds --noise-levels 0.015 --sizes 2562 3169 7057 10242 --work advisor-twins --workers 1
    python -m curv.advice.table refeature --table twins.json --work advisor-refeature --workers 1

(168 meshes, 6720 estimates, 331 CPU-s; 90 meshes, 6120 estimates.) Then closed surfaces between
the grid's sizes are added as rows, where the winners of the noise-free ellipsoids change (nc R1 up
to 642 vertices, jet R2 degree 4 from 2562): 1000, 1600 and 5000 vertices, three random shapes at
every noise level, every candidate; and the measures and axes again::

    python -m curv.advice.table fill --table twins.json --out closed2.json --kinds --coarse-samples 3 --coarse-closed-vertices 162 252 362 482 1000 1600 5000 --work advisor-closed2 --workers 1
    python -m curv.advice.table refeature --table closed2.json --work advisor-refeature --workers 1

(189 meshes, 12,852 estimates, 502 s wall with 1 worker at niceness 10 on the loaded machine.) Then every
mesh is measured again for the residual measures (``noise_raw4``, ``residual_ratio``:
:mod:`curv.advice.residuals`, which tell a quadric's model error from noise) and the axes chosen
again, over the packaged table (no estimator runs)::

    python -m curv.advice.table refeature --table closed2.json --work advisor-refeature2 --workers 1

(2736 meshes measured in 1114 s wall with 1 worker at niceness 10 on the loaded machine.) The coarse rows are
measured with the base table's calibration; the kernel is refitted by leave-one-out over all rows. 217 vertices is left out: on
its hexagon no vertex is farther than R4 from the border, so the study evaluates none. The study
directory resumes and keeps the measured rows (``advisor_rows.json``), so a long run may be split
and a rerun over a finished directory only refits the calibration and the kernel (seconds).

Last, the anisotropy axis became logarithmic (:data:`EXTRA_TRANSFORMS`) and the axes were chosen
again over the packaged table's stored points (nothing measured or run; 579 s wall at niceness 10)::

    python -m curv.advice.table reselect
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from .advisor import FIT_METHOD, FIT_RANGE, kernel_predict, raw_measures, table_coordinates
from ..study.protocol import StudySettings, Task, study_variants
from ..variants import NOISE_FRACTION

__all__ = ["DEFAULT_OUT", "table_settings", "mesh_features", "random_closed_params", "closed_mesh_point",
           "measure_rows", "fit_calibration", "table_points", "choose_bandwidth", "fit_kernel", "make_table",
           "build_table", "main", "table_mesh", "fill_jobs", "fill_table", "feature_row", "noise_groups",
           "select_axes", "refeature_table", "loo_regret", "EXTRA_COLUMNS", "EREL_FLOOR", "surface_groups",
           "coarse_jobs", "noise_jobs", "FEATURE_MEASURES"]

DEFAULT_OUT = Path(__file__).parents[1] / "data" / "advisor_table.json"
BANDWIDTHS = (0.15, 0.25, 0.35, 0.5, 0.7, 1.0, 1.5)
"""Candidate kernel widths in scaled units, tried by leave-one-out."""
NOISE_AXES = ("linear", "sqrt")
"""Candidate transforms of the noise axis, tried by leave-one-out with every bandwidth."""

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
    from ..study.testmesh import build_test_mesh

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

    from ..api import estimate
    from ..geometry.normals import vertex_normals
    from ..study.metrics import summarize
    from ..variants import Variant
    from ..surfaces import make_surface

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
with :func:`curv.advice.advisor.raw_measures` or :func:`random_closed_params`."""


def _key_text(key) -> str:
    return json.dumps(list(key))


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
    todo = [t for t in tasks if _key_text(t.key) not in have]
    for task, row in zip(todo, executor.map(mesh_features, todo)):
        have[_key_text(task.key)] = row
    return [have[_key_text(t.key)] for t in tasks]


def closed_points(names, sizes, levels, samples: int, seed: int, variant_ids, executor, cache: dict):
    """:func:`closed_mesh_point` over every (name, size, level, sample): rows and (p, v) median e_rel.

    Points already in ``cache["closed"]`` with a value for every variant are not recomputed; the
    largest meshes are submitted first (load balance).
    """
    jobs = [(seed, nm, int(n), float(lv), s, tuple(variant_ids))
            for s in range(samples) for nm in names for n in sorted(sizes, reverse=True) for lv in levels]
    have = cache["closed"]
    key = lambda job: _key_text([job[0], job[1], job[2], 0.0, job[3], job[4]])  # noqa: E731
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


def _regret(log_values: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """Median e_rel of the chosen variant over the best one, per mesh."""
    best = np.nanmin(log_values, axis=1)
    return np.exp(log_values[np.arange(len(chosen)), chosen] - best)


def loo_regret(coords: np.ndarray, log_values: np.ndarray, bandwidth: float, groups=None) -> np.ndarray:
    """(p,) regret of advising each mesh from the other meshes of the table.

    Parameters
    ----------
    coords : (p, a) float64
        Scaled kernel coordinates of the table's meshes.
    log_values : (p, v) float64
        log median e_rel (NaN where missing).
    bandwidth : float
    groups : (p,) array_like, optional
        Meshes of one group are left out together (e.g. one surface at every noise level: its
        twins would otherwise stand next to it on every axis but noise); default each mesh alone.

    Returns
    -------
    (p,) float64
        The chosen variant's median e_rel over the best one's, per mesh: the same prediction as
        :func:`curv.advice.advisor.kernel_predict` (weights shifted per row by the nearest other mesh, and
        exactly per variant where that leaves a variant no weight).
    """
    p = len(coords)
    d2 = np.sum((coords[:, None, :] - coords[None, :, :]) ** 2, axis=2) / bandwidth**2
    np.fill_diagonal(d2, np.inf)
    if groups is not None:
        g = np.asarray(groups)
        d2[g[:, None] == g[None, :]] = np.inf
    have = np.isfinite(log_values)
    values = np.where(have, log_values, 0.0)
    w = np.exp(-0.5 * (d2 - d2.min(axis=1, keepdims=True)))
    total = w @ have.astype(np.float64)
    pred = (w @ values) / np.where(total > 0, total, 1.0)
    for i, j in zip(*np.nonzero(~(total > 1e-200) & have.any(axis=0)[None, :])):  # a few (row, variant) pairs
        dist = np.where(have[:, j], d2[i], np.inf)
        if np.isfinite(dist.min()):
            wij = np.exp(-0.5 * (dist - dist.min()))
            pred[i, j] = wij @ values[:, j] / wij.sum()
        else:
            pred[i, j] = np.inf
    pred = np.where(have & np.isfinite(pred), pred, np.inf)  # a mesh is advised among the variants it has
    chosen = np.argmin(pred, axis=1)
    return _regret(log_values, chosen)


def choose_bandwidth(coords: np.ndarray, log_values: np.ndarray) -> tuple[float, dict]:
    """The candidate of :data:`BANDWIDTHS` with the lowest leave-one-out mean regret, and all scores."""
    scores = {h: float(np.mean(loo_regret(coords, log_values, h))) for h in BANDWIDTHS}
    return min(scores, key=scores.get), scores


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
    from ..study.executors import open_executor
    from ..study.runner import run

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
    from .advisor import calibrate_irregularity, calibrate_noise

    noise = np.array([calibrate_noise(r["noise_raw"], cal, r["density"]) for r in rows])
    irr = np.array([calibrate_irregularity(r["irregularity_raw"], n, cal) for r, n in zip(rows, noise)])
    return np.stack([[r["density"] for r in rows], noise / NOISE_FRACTION, irr], axis=1)


def fit_kernel(points: np.ndarray, erel: np.ndarray) -> dict:
    """The kernel (noise axis, scales, bandwidth) with the lowest leave-one-out mean regret.

    Parameters
    ----------
    points : (p, 3) float64
        ``(density, noise level, irregularity)`` of the table's meshes.
    erel : (p, v) float64
        Median e_rel (NaN where missing).

    Returns
    -------
    dict
        ``noise_axis``, ``scales`` (standard deviation of each transformed coordinate),
        ``bandwidth`` and ``loo_mean_regret`` (every bandwidth of the chosen axis).
    """
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
    return best


def _round(x: float, digits: int):
    """``x`` to ``digits`` significant digits for the JSON (None for NaN)."""
    return None if not np.isfinite(x) else float(f"{x:.{digits}g}")


def _percentile(values: np.ndarray, q: float):
    """The ``q`` th percentile to 4 significant digits, None for no values."""
    return _round(float(np.percentile(values, q)), 4) if values.size else None


def table_command(argv, sub: str = "") -> str:
    """The command line stored in a table's metadata: ``python -m curv.advice.table [sub] argv``
    with every path argument reduced to its file name (the directories it ran in are the machine's,
    not the table's)."""
    words = ["python", "-m", "curv.advice.table", *([sub] if sub else []),
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


# ---------------------------------------------------------------------------- extension: options and coarse meshes
FIT_NORMAL_ESTIMATORS = ("nc", "qs", "an", "mru", "ru", "icc")
"""Estimators whose result depends on the vertex normals (a frame, neighbour normals or the
interpolated normal field), so fitted normals are a different candidate; ``jet`` only orients its
own fit with them, ``meyer`` computes its own, ``csm`` uses none."""
FIT_RANGES = (2, 4)
"""``fit_range`` of the ``normals="fit"`` candidates: the default and the widest named range (the
winner on dense noisy meshes)."""
JET_DEGREES = (3, 4)
"""The jet degrees beyond the default 2 offered as candidates (at R2-R4: a triangle 1-ring has too
few points for them)."""
COARSE_DENSITIES = (217, 331, 469)
"""Hexagon subdivisions s = 8, 10, 12 below the study's grid: the paper's coarsest mesh and between."""
COARSE_CLOSED_VERTICES = (162, 252, 362)
"""Closed surfaces below the grid's 642 (geodesic sizes 10 f² + 2)."""
OPTION_DENSITIES = DEFAULT_DENSITIES
"""The base table's patch densities the option candidates run on (sample 0, every noise level,
irregularity and function)."""
OPTION_CLOSED_VERTICES = DEFAULT_CLOSED_VERTICES
"""The base table's closed-surface sizes the option candidates run on (sample 0)."""
MIN_EVALUATED = 30
"""A patch evaluates its vertices away from the border at the largest of R4..R1 that leaves at least
this many (the study's R4 leaves none on a 217-vertex hexagon)."""


def option_variants() -> list[str]:
    """Variant ids of the documented options that change the result: jet degrees 3 and 4 at R2-R4,
    ``normals="fit"`` at each of :data:`FIT_RANGES` for :data:`FIT_NORMAL_ESTIMATORS` at their
    named ranges (R2-R4 for the fits; icc also R1)."""
    from ..estimators import ESTIMATORS
    from ..variants import Variant

    out = [Variant("jet", k, options={"degree": d}).id for d in JET_DEGREES for k in (2, 3, 4)]
    for fr in FIT_RANGES:
        for name in FIT_NORMAL_ESTIMATORS:
            spec = ESTIMATORS[name]
            ks = [k for k in spec.ranges if k >= 2 or name == "icc"]
            out += [Variant(name, k, options={"normals": "fit", "fit_range": fr}).id for k in ks]
    return out


def evaluated_for_table(mesh) -> np.ndarray:
    """(n,) bool: vertices with no border vertex within the largest range of R4..R1 that leaves at
    least :data:`MIN_EVALUATED` of them (R4 is the study's rule), all vertices on a closed mesh."""
    from ..study.testmesh import evaluated_vertices

    if not mesh.border_vertices.any():
        return np.ones(mesh.n_vertices, bool)
    for k in (4, 3, 2, 1):
        out = evaluated_vertices(mesh, range_factor=k)
        if out.sum() >= MIN_EVALUATED:
            return out
    return out


def variant_errors(mesh, truth, evaluated, variant_ids) -> dict:
    """``{variant id: median e_rel}`` of every variant on one mesh (NaN where it raised or gave no
    value): Max normals, fitted normals computed once per fit range."""
    from ..api import estimate
    from ..fitted_normals import fitted_normals
    from ..geometry.normals import vertex_normals
    from ..study.metrics import summarize
    from ..variants import Variant

    normals = {None: vertex_normals(mesh)}
    erel = {}
    for vid in variant_ids:
        v = Variant.from_id(vid)
        kw = v.kwargs
        try:
            if kw.pop("normals", None) == "fit":
                fr = kw.pop("fit_range", 2)
                if fr not in normals:
                    normals[fr] = fitted_normals(mesh, range=fr)
                kw["normals"] = normals[fr]
            else:
                kw["normals"] = normals[None]
            erel[vid] = summarize(truth, estimate(mesh, **kw), evaluated)["median_erel"]
        except Exception:  # recorded as missing, like a failing variant of the study
            erel[vid] = float("nan")
    return erel


def table_mesh(key) -> tuple:
    """(mesh, truth, planar irregularity) of a table key: a study key ``[seed, function, density,
    irregularity, noise, sample]`` (a Monge patch) or a closed-surface key ``[seed, name,
    n_vertices, 0.0, noise, sample]`` (:func:`closed_mesh_point`'s shapes and noise draws)."""
    import zlib

    from ..study.protocol import Task
    from ..study.testmesh import build_test_mesh
    from ..surfaces import make_surface

    seed, name, n, irr, level, sample = key
    if name in DEFAULT_CLOSED:
        params = random_closed_params(name, np.random.default_rng([seed, 8, zlib.crc32(name.encode()), sample]))
        rng = np.random.default_rng([seed, 7, zlib.crc32(name.encode()), n, sample])
        s = make_surface(name, n_vertices=n, noise=level * NOISE_FRACTION, seed=rng, **params)
        return s.mesh, s.truth, float("nan")
    tm = build_test_mesh(Task(int(seed), name, int(n), float(irr), float(level), int(sample)))
    return tm.mesh, tm.truth, tm.irregularity


def candidate_point(args: tuple) -> tuple[dict, dict]:
    """Raw measures and the median e_rel of ``variant_ids`` on one table mesh.

    ``args = (key, variant_ids)``; ``key`` is a study key ``[seed, function, density,
    irregularity, noise, sample]`` (a Monge patch, evaluated by :func:`evaluated_for_table`) or a
    closed-surface key ``[seed, name, n_vertices, 0.0, noise, sample]`` (as
    :func:`closed_mesh_point`, every vertex evaluated).
    """
    key, variant_ids = args
    level = key[4]
    mesh, truth, planar = table_mesh(key)
    evaluated = evaluated_for_table(mesh)
    raw = raw_measures(mesh)
    scale = np.abs(truth.k1[evaluated]) + np.abs(truth.k2[evaluated])
    row = {"key": list(key), "noise_true": level * NOISE_FRACTION, "irregularity_planar": planar,
           "density_true": raw["mean_edge"] * float(np.median(scale)), "noise_raw": raw["noise_raw"],
           "irregularity_raw": raw["irregularity_raw_deg"], "density": raw["density"],
           "n_evaluated": int(evaluated.sum())}
    return row, variant_errors(mesh, truth, evaluated, variant_ids)


def extension_jobs(base: dict, *, samples: int = 1, option_samples: int = 1, seed: int = 0) -> list[tuple]:
    """The jobs that extend ``base`` (a table): every variant on the coarse patches and closed
    surfaces (``samples`` each), the option variants on the base table's meshes of sample below
    ``option_samples`` at :data:`OPTION_DENSITIES` and :data:`OPTION_CLOSED_VERTICES`. Largest
    meshes first (load balance)."""
    settings = base["metadata"]["settings"]
    every = list(base["variants"]) + [v for v in option_variants() if v not in base["variants"]]
    options = [v for v in every if v not in base["variants"]]
    jobs = []
    for key in base["truth"]["key"]:
        sizes = OPTION_CLOSED_VERTICES if key[1] in DEFAULT_CLOSED else OPTION_DENSITIES
        if key[5] < option_samples and key[2] in sizes:
            jobs.append((list(key), tuple(options)))
    for s in range(samples):
        for fn in settings["functions"]:
            for d in COARSE_DENSITIES:
                for irr in settings["irregularity"]:
                    for lv in settings["noise"]:
                        jobs.append(([seed, fn, d, float(irr), float(lv), s], tuple(every)))
        for nm in DEFAULT_CLOSED:
            for n in COARSE_CLOSED_VERTICES:
                for lv in settings["noise"]:
                    jobs.append(([seed, nm, n, 0.0, float(lv), s], tuple(every)))
    jobs.sort(key=lambda j: -j[0][2] * len(j[1]))
    return jobs


def run_extension(jobs: list[tuple], work_dir, *, workers: int | None = None, progress=None) -> dict:
    """Run (or resume) ``jobs`` (:func:`candidate_point`) into ``work_dir/extension.json``:
    ``{key text: [row, {variant id: e_rel}]}``; saved after every batch, so a run may be split."""
    from ..study.executors import open_executor

    work_dir = Path(work_dir)
    work_dir.mkdir(parents=True, exist_ok=True)
    path = work_dir / "extension.json"
    done = json.loads(path.read_text()) if path.exists() else {}
    todo = [j for j in jobs if not set(j[1]) <= set(done.get(_key_text(j[0]), [None, {}])[1])]
    say = progress or (lambda text: None)
    say(f"{len(jobs)} jobs, {len(todo)} to run")
    t0 = time.perf_counter()
    batch = 16
    with open_executor(workers=workers) as ex:
        for b in range(0, len(todo), batch):
            part = todo[b:b + batch]
            for job, (row, erel) in zip(part, ex.map(candidate_point, part)):
                old = done.get(_key_text(job[0]), [row, {}])
                done[_key_text(job[0])] = [row, {**old[1], **erel}]
            tmp = path.with_suffix(".tmp")
            tmp.write_text(json.dumps(done))
            tmp.replace(path)
            say(f"{min(b + batch, len(todo))}/{len(todo)} jobs, {time.perf_counter() - t0:.0f} s")
    return done


def extend_table(base: dict, done: dict, *, command: str = "", jobs=None) -> dict:
    """``base`` with the option variants as new columns and the coarse meshes as new rows (their
    points measured with the base table's calibration), the kernel refitted by leave-one-out.
    Option columns are NaN on the base meshes they were not run on (the prediction leaves NaN
    entries out per column)."""
    from .advisor import calibrate_irregularity, calibrate_noise

    cal = base["calibration"]
    variants = list(base["variants"]) + [v for v in option_variants() if v not in base["variants"]]
    col = {v: j for j, v in enumerate(variants)}
    keys = [list(k) for k in base["truth"]["key"]]
    erel = np.full((len(keys), len(variants)), np.nan)
    erel[:, : len(base["variants"])] = np.array(base["median_erel"], float)
    points = [list(p) for p in base["points"]]
    truth = {k: list(v) for k, v in base["truth"].items()}
    truth.setdefault("n_evaluated", [None] * len(keys))
    index = {_key_text(k): i for i, k in enumerate(keys)}
    if jobs is not None:  # exactly the planned meshes (a work directory may hold more)
        planned = {_key_text(j[0]) for j in jobs}
        done = {k: v for k, v in done.items() if k in planned}
    new_rows = []
    for ktext, (row, values) in done.items():
        i = index.get(ktext)
        if i is None:
            new_rows.append((row, values))
            continue
        for vid, x in values.items():
            if vid in col and x is not None and np.isfinite(x) and x > 0:
                erel[i, col[vid]] = x
    extra = _append_rows(new_rows, cal, col, points, truth)
    erel = np.concatenate([erel, extra])
    pts = np.array(points, float)
    keep = np.all(np.isfinite(pts), axis=1) & np.isfinite(erel).any(axis=1)
    pts, erel = pts[keep], erel[keep]
    truth = {k: [v for v, ok in zip(vals, keep) if ok] for k, vals in truth.items()}
    kernel = fit_kernel(pts, erel)
    meta = dict(base["metadata"])
    meta.update(extension_command=command, created=time.strftime("%Y-%m-%d %H:%M:%S %Z"), n_meshes=int(len(pts)),
                coarse={"densities": list(COARSE_DENSITIES), "closed_vertices": list(COARSE_CLOSED_VERTICES),
                        "min_evaluated": MIN_EVALUATED},
                options={"jet_degrees": list(JET_DEGREES), "fit_ranges": list(FIT_RANGES),
                         "fit_normal_estimators": list(FIT_NORMAL_ESTIMATORS)})
    return {**base, "kernel": kernel, "metadata": meta, "variants": variants,
            "points": [[_round(x, POINT_DIGITS) for x in p] for p in pts],
            "truth": {k: [(_round(x, 4) if isinstance(x, float) else x) for x in vals] for k, vals in truth.items()},
            "median_erel": [[_round(x, EREL_DIGITS) for x in row] for row in erel]}


def _append_rows(new_rows, cal: dict, col: dict, points: list, truth: dict) -> np.ndarray:
    """Append new meshes (:func:`candidate_point`'s ``(row, errors)``) to ``points`` (the three base
    columns, measured with the calibration ``cal``) and ``truth``; return their (r, v) median e_rel
    in the columns ``col`` (variant id -> column), NaN where missing."""
    from .advisor import calibrate_irregularity, calibrate_noise

    extra = np.full((len(new_rows), len(col)), np.nan)
    for r, (row, values) in enumerate(new_rows):
        noise = calibrate_noise(row["noise_raw"], cal, row["density"])
        points.append([row["density"], noise / NOISE_FRACTION,
                       calibrate_irregularity(row["irregularity_raw"], noise, cal)])
        for name, value in (("key", row["key"]), ("noise_true", row["noise_true"]),
                            ("irregularity_planar", row["irregularity_planar"]),
                            ("density_true", row["density_true"]), ("n_evaluated", row["n_evaluated"])):
            truth[name].append(value)
        for vid, x in values.items():
            if vid in col and x is not None and np.isfinite(x) and x > 0:
                extra[r, col[vid]] = x
    return extra


def extend_main(argv) -> int:
    """``python -m curv.advice.table extend``: add the options and the coarse meshes to a table."""
    parser = argparse.ArgumentParser(prog="python -m curv.advice.table extend", description=extend_main.__doc__)
    parser.add_argument("--base", default=str(DEFAULT_OUT), help="table to extend; default the packaged one")
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    parser.add_argument("--work", default="advisor-extension", help="keeps the computed meshes (resumes)")
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--samples", type=int, default=1, help="samples of each coarse setting")
    parser.add_argument("--option-samples", type=int, default=1, help="base samples the options run on")
    parser.add_argument("--dry-run", action="store_true", help="count the jobs and stop")
    args = parser.parse_args(argv)
    base = load_base(args.base)
    jobs = extension_jobs(base, samples=args.samples, option_samples=args.option_samples)
    if args.dry_run:
        print(f"{len(jobs)} jobs, {sum(len(j[1]) for j in jobs)} estimates")
        return 0
    t0 = time.process_time()
    done = run_extension(jobs, args.work, workers=args.workers, progress=lambda t: print(t, flush=True))
    command = table_command(argv, "extend")
    table = extend_table(base, done, command=command, jobs=jobs)
    table["metadata"]["extension_cpu_seconds_main_process"] = round(time.process_time() - t0, 1)
    with open(args.out, "w") as fh:
        json.dump(table, fh, separators=(",", ":"))
    print(f"wrote {args.out}: {len(table['points'])} meshes x {len(table['variants'])} variants; bandwidth "
          f"{table['kernel']['bandwidth']} (LOO mean regret {table['kernel']['loo_mean_regret']})", flush=True)
    return 0


def load_base(path) -> dict:
    """The base table to extend (what ``python -m curv.advice.table --out base.json`` writes); an
    already extended table is refused (its option columns would be taken for base ones)."""
    with open(path) as fh:
        table = json.load(fh)
    if set(option_variants()) & set(table["variants"]):
        raise SystemExit(f"{path}: already extended; give the base table (python -m curv.advice.table --out base.json)")
    return table


# ---------------------------------------------------------------------------- filling a table's empty cells
def fill_jobs(table: dict, *, kinds=DEFAULT_CLOSED, sizes=None) -> list[tuple]:
    """Jobs (:func:`candidate_point`) for the empty cells of ``table``'s meshes of ``kinds`` (closed
    surface names or Monge functions) and, if given, of ``sizes`` (a key's density or vertex count):
    each such mesh with the variants it has no value for. Largest meshes first (load balance)."""
    variants = table["variants"]
    jobs = []
    for key, row in zip(table["truth"]["key"], table["median_erel"]):
        missing = tuple(v for v, x in zip(variants, row) if x is None)
        if key[1] in kinds and missing and (sizes is None or key[2] in sizes):
            jobs.append((list(key), missing))
    jobs.sort(key=lambda j: -j[0][2] * len(j[1]))
    return jobs


def coarse_jobs(table: dict, samples: int, closed_vertices=None) -> list[tuple]:
    """Jobs (:func:`candidate_point`, every variant of ``table``) for the coarse meshes
    (:data:`COARSE_DENSITIES` patches, closed surfaces of ``closed_vertices``, default
    :data:`COARSE_CLOSED_VERTICES`) of the samples below ``samples`` that ``table`` does not hold
    yet: more random surfaces per coarse setting, where the best call changes fastest with the
    surface, and closed sizes between the grid's."""
    settings = table["metadata"]["settings"]
    have = {_key_text(k) for k in table["truth"]["key"]}
    every = tuple(table["variants"])
    closed_vertices = COARSE_CLOSED_VERTICES if closed_vertices is None else closed_vertices
    jobs = []
    for s in range(samples):
        for fn in settings["functions"]:
            for d in COARSE_DENSITIES:
                for irr in settings["irregularity"]:
                    for lv in settings["noise"]:
                        jobs.append(([0, fn, d, float(irr), float(lv), s], every))
        for nm in DEFAULT_CLOSED:
            for n in closed_vertices:
                for lv in settings["noise"]:
                    jobs.append(([0, nm, int(n), 0.0, float(lv), s], every))
    return [j for j in jobs if _key_text(j[0]) not in have]


def noise_jobs(table: dict, levels, sizes=None) -> list[tuple]:
    """Jobs (:func:`candidate_point`, every variant of ``table``) for the noise twins at ``levels``
    (fractions of the paper's level) of every noise-free mesh of ``table`` (of ``sizes`` if given:
    a key's density or vertex count) that ``table`` does not hold yet: the same surface,
    tessellation and noise directions (:func:`table_mesh`), a noise level between the grid's. Largest
    meshes first (load balance)."""
    have = {_key_text(k) for k in table["truth"]["key"]}
    every = tuple(table["variants"])
    jobs = []
    for key in table["truth"]["key"]:
        if key[4] != 0 or (sizes is not None and key[2] not in sizes):
            continue
        for lv in levels:
            twin = [*key[:4], float(lv), key[5]]
            if _key_text(twin) not in have:
                have.add(_key_text(twin))
                jobs.append((twin, every))
    jobs.sort(key=lambda j: -j[0][2])
    return jobs


def fill_table(table: dict, done: dict, *, command: str = "", new_keys=(), closed_vertices=None) -> dict:
    """``table`` with the values of ``done`` (:func:`run_extension`'s results) in its empty cells and
    the meshes of ``new_keys`` (keys of ``done`` the table does not hold, :func:`coarse_jobs`) as new
    rows (their base columns measured with the table's calibration); calibration and kernel unchanged
    (refit with ``refeature``). ``closed_vertices``: the coarse closed sizes now in the table (stored
    in ``metadata["coarse"]``)."""
    variants = table["variants"]
    col = {v: j for j, v in enumerate(variants)}
    erel = [list(row) for row in table["median_erel"]]
    filled = 0
    for i, key in enumerate(table["truth"]["key"]):
        got = done.get(_key_text(key))
        if got is None:
            continue
        for vid, x in got[1].items():
            j = col.get(vid)
            if j is not None and erel[i][j] is None and x is not None and np.isfinite(x) and x > 0:
                erel[i][j] = _round(x, EREL_DIGITS)
                filled += 1
    new_rows = [done[_key_text(k)] for k in new_keys if _key_text(k) in done]
    # with new rows the extra columns are measured by refeature; without, the table keeps them
    base = [p[:3] for p in table["points"]] if new_rows else table["points"]
    points, truth = [list(p) for p in base], {k: list(v) for k, v in table["truth"].items()}
    extra = _append_rows(new_rows, table["calibration"], col, points, truth)
    added = np.array(points[len(base):], float).reshape(-1, len(points[0]) if points else 3)
    keep = np.all(np.isfinite(added), axis=1) & np.isfinite(extra).any(axis=1)
    for r in np.nonzero(keep)[0]:
        erel.append([_round(x, EREL_DIGITS) if np.isfinite(x) else None for x in extra[r]])
    keep_all = np.concatenate([np.ones(len(base), bool), keep])
    points = [[_round(x, POINT_DIGITS) for x in p] for p, ok in zip(points, keep_all) if ok]
    truth = {k: [(_round(x, 4) if isinstance(x, float) else x) for x, ok in zip(vals, keep_all) if ok]
             for k, vals in truth.items()}
    meta = dict(table["metadata"])
    meta.update(fill_command=command, filled_cells=filled, n_meshes=len(points), added_meshes=int(keep.sum()),
                fill_commands=[*meta.get("fill_commands", [meta["fill_command"]] if "fill_command" in meta else []),
                               command])
    if closed_vertices is not None:
        meta["coarse"] = {**meta.get("coarse", {}), "closed_vertices": [int(n) for n in closed_vertices]}
    out = {**table, "median_erel": erel, "metadata": meta, "points": points, "truth": truth}
    if new_rows:  # the extra columns of the old rows no longer match the new rows: refeature measures them
        out["columns"] = ["density", "noise_level", "irregularity_deg"]
    return out


def fill_main(argv) -> int:
    """``python -m curv.advice.table fill``: run the variants a table's meshes of some kinds have no
    value for (by default the option candidates on the closed surfaces of samples 1 and 2)."""
    parser = argparse.ArgumentParser(prog="python -m curv.advice.table fill", description=fill_main.__doc__)
    parser.add_argument("--table", default=str(DEFAULT_OUT))
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    parser.add_argument("--work", default="advisor-fill", help="keeps the computed meshes (resumes)")
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--kinds", nargs="*", default=list(DEFAULT_CLOSED),
                        help="kinds of mesh whose empty cells are run (none: only --coarse-samples)")
    parser.add_argument("--coarse-samples", type=int, default=1,
                        help="random surfaces per coarse setting: the missing ones are added as new rows")
    parser.add_argument("--sizes", type=int, nargs="+", default=None,
                        help="fill only the meshes of these densities / vertex counts (default all)")
    parser.add_argument("--coarse-closed-vertices", type=int, nargs="+", default=None,
                        help="coarse closed-surface sizes (default the table's, else "
                             f"{' '.join(map(str, COARSE_CLOSED_VERTICES))}): sizes it lacks are added")
    parser.add_argument("--noise-levels", type=float, nargs="+", default=(),
                        help="add the noise twins at these levels (fractions of the paper's) of every noise-free "
                             "mesh (of --sizes if given) as new rows, every variant")
    parser.add_argument("--dry-run", action="store_true", help="count the jobs and stop")
    args = parser.parse_args(argv)
    with open(args.table) as fh:
        table = json.load(fh)
    sizes = args.coarse_closed_vertices or table.get("metadata", {}).get("coarse", {}).get(
        "closed_vertices", list(COARSE_CLOSED_VERTICES))
    new = coarse_jobs(table, args.coarse_samples, sizes) + noise_jobs(table, args.noise_levels, args.sizes)
    jobs = fill_jobs(table, kinds=tuple(args.kinds), sizes=args.sizes) + new
    if args.dry_run:
        print(f"{len(jobs)} jobs, {sum(len(j[1]) for j in jobs)} estimates")
        return 0
    done = run_extension(jobs, args.work, workers=args.workers, progress=lambda t: print(t, flush=True))
    out = fill_table(table, done, command=table_command(argv, "fill"),
                     new_keys=[j[0] for j in new], closed_vertices=sizes)
    if args.noise_levels:  # the levels between the grid's, as rows of every noise-free mesh's twins
        meta = out["metadata"]
        meta["twin_noise_levels"] = sorted({*meta.get("twin_noise_levels", []), *map(float, args.noise_levels)})
    with open(args.out, "w") as fh:
        json.dump(out, fh, separators=(",", ":"))
    print(f"wrote {args.out}: {out['metadata']['filled_cells']} cells filled", flush=True)
    return 0


# ---------------------------------------------------------------------------- further axes: shape and tessellation
EXTRA_COLUMNS = ("border_share", "edge_cv", "valence_sd", "anisotropy", "curvature_spread", "hyperbolic_share",
                 "noise_raw", "noise_raw4", "residual_ratio")
"""Point columns beyond the base three: the open/closed distinction, the shape and tessellation
measures of :class:`curv.advice.advisor.MeshFeatures`, the uncalibrated noise measure and the
residual measures that tell model error from noise, candidates for further kernel axes."""
EXTRA_TRANSFORMS = {"border_share": "sqrt", "noise_raw": "log", "noise_raw4": "log", "anisotropy": "log"}
"""Axis transforms of the extra columns (default linear): a border share spans 0 (closed) to a
fifth (the coarsest patch), and its square root separates the small shares of dense patches from
a closed surface; the raw noise measure spans five decades (a noise-free dense patch's quadric
misses its neighbours by a few millionths of an edge, a noisy coarse one by a tenth), and its
logarithm keeps what the calibrated noise level clips to zero: a thousandth of the paper's level
on a dense mesh, or the noise a coarse mesh's density term swallows. The anisotropy's logarithm
tells a noise-free ellipsoid (0.07 and up) from a noise-free sphere (0.001): on a linear axis the
two stood within one bandwidth and the spheres' exact calls were advised on ellipsoids."""
AXIS_WEIGHTS = (0.5, 1.0, 2.0)
"""Weights tried for an extra axis (its scale is its standard deviation over the table divided by
the weight: 2 makes it count twice as much as a base axis)."""
SELECTION_BANDWIDTHS = (0.25, 0.35, 0.5)
"""Bandwidths tried for each set of axes during the selection. Not below 0.25: the table's meshes
sit on a grid whose steps are 0.3-0.7 scaled units along the noise axis (and come in families of
one surface at every noise level), so a narrower kernel turns into the nearest grid point, which
leave-one-out over the grid rewards and a mesh between the grid's points does not."""
EREL_FLOOR = 1e-6
"""Median e_rel below this counts as this (rounding: nc R1 on a noise-free sphere reads 1e-15), in
the prediction (:func:`curv.advice.advisor.log_erel`) and in the regret the selection scores."""
MIN_GAIN = 0.02
"""A further axis is taken only when it lowers the grouped leave-one-out mean regret by more (each
axis thins the table around a mesh: an axis must pay for it)."""


FEATURE_MEASURES = MEASURES + ", shape v1, residuals v1"
"""What the cached rows of ``refeature`` were measured with; a cache of other measures is measured
again (residuals v1: :mod:`curv.advice.residuals` at R3 on 1000 sampled vertices)."""


def feature_row(key) -> dict:
    """Every raw measure (:func:`curv.advice.advisor.raw_measures`) of the table mesh of ``key``."""
    mesh, _, _ = table_mesh(key)
    raw = raw_measures(mesh)
    raw.pop("polygon_kinds")
    return {"key": list(key), **raw}


def surface_groups(keys) -> np.ndarray:
    """(p,) int64: one group per random surface (a key's seed, function or closed shape, and sample:
    the same surface at every density, irregularity and noise level), so that the selection's
    leave-one-out advises a mesh only from other surfaces, as a user's mesh is. Left out by noise
    level only (:func:`noise_groups`), the same surface at a neighbouring density or irregularity
    still stood next to it, and an axis that names the surface (its anisotropy: each Monge function
    has its own) won the selection and lost on new surfaces."""
    index: dict = {}
    return np.array([index.setdefault(_key_text([k[0], k[1], k[5]]), len(index)) for k in keys], np.int64)


def noise_groups(keys) -> np.ndarray:
    """(p,) int64: one group per table surface (its key without the noise level), so that a mesh is
    left out with its twins at the other noise levels."""
    index: dict = {}
    return np.array([index.setdefault(_key_text(list(k[:4]) + list(k[5:])), len(index)) for k in keys], np.int64)


def select_axes(points: np.ndarray, columns, erel: np.ndarray, groups, *, progress=None,
                note: str = "grouped leave-one-out") -> dict:
    """The kernel: the base axes of :func:`fit_kernel`'s noise transform and, by forward selection,
    the extra columns that lower the grouped leave-one-out mean regret by more than :data:`MIN_GAIN`.

    With several groupings the score is the mean of their leave-one-out mean regrets: the shipped
    table is scored left out by surface (:func:`surface_groups`: how a new surface is advised) and by
    noise level (:func:`noise_groups`: how a known surface is advised between the grid's settings),
    so an axis must pay on both; each alone misled the selection on the development meshes (by
    surface only it could not see that the curvature spread places a mesh between settings, by noise
    level only it took an axis that names the surface).

    Parameters
    ----------
    points : (p, c) float64
        The table's point columns (``columns`` order; the first three the base ones).
    columns : sequence of str
    erel : (p, v) float64
        Median e_rel (NaN where missing).
    groups : (p,) array_like, or a sequence of them
        Meshes left out together (:func:`surface_groups`, :func:`noise_groups`); several: one
        leave-one-out per grouping, scored by the mean.
    progress : callable, optional
    note : str
        What the groupings are (stored as ``loo_note``).

    Returns
    -------
    dict
        ``axes`` (``[column, transform, scale]``), ``bandwidth``, ``loo_mean_regret`` (per
        bandwidth of the chosen axes, the score), ``loo_p90_regret`` (per bandwidth and grouping),
        ``selection`` (each step: the axes added and the score) and ``loo_note``.
    """
    from .advisor import table_coordinates

    say = progress or (lambda text: None)
    log_values = np.log(np.maximum(erel, EREL_FLOOR))
    columns = list(columns)

    def axis(col, how, weight=1.0):
        x = points[:, columns.index(col)]
        x = np.log(np.maximum(x, 1e-12)) if how == "log" else (np.sqrt(np.maximum(x, 0)) if how == "sqrt" else x)
        sd = float(np.std(x))
        return [col, how, (sd if sd > 0 else 1.0) / weight]

    groupings = [np.asarray(groups)] if np.ndim(groups[0]) == 0 else [np.asarray(g) for g in groups]

    def score(axes):
        coords = table_coordinates({"kernel": {"axes": axes}, "columns": columns}, *points.T)
        per = {h: [loo_regret(coords, log_values, h, g) for g in groupings] for h in SELECTION_BANDWIDTHS}
        mean = {h: float(np.mean([r.mean() for r in rs])) for h, rs in per.items()}
        h = min(mean, key=mean.get)
        return mean[h], h, per

    best_axes, best = None, None
    for noise_axis in NOISE_AXES:
        axes = [axis("density", "log"), axis("noise_level", noise_axis), axis("irregularity_deg", "linear")]
        sc = score(axes)
        if best is None or sc[0] < best[0]:
            best_axes, best = axes, sc
    steps = [{"axes": [a[0] for a in best_axes], "loo_mean_regret": round(best[0], 4), "bandwidth": best[1]}]
    say(f"base axes: grouped LOO mean regret {best[0]:.4f} (bandwidth {best[1]})")
    while True:
        used = {a[0] for a in best_axes}
        trials = []
        for col in columns[3:]:
            if col in used or not np.isfinite(points[:, columns.index(col)]).all():
                continue
            for weight in AXIS_WEIGHTS:
                axes = best_axes + [axis(col, EXTRA_TRANSFORMS.get(col, "linear"), weight)]
                trials.append((score(axes), axes, weight))
        if not trials:
            break
        sc, axes, weight = min(trials, key=lambda t: t[0][0])
        say(f"+ {axes[-1][0]} (weight {weight}): {sc[0]:.4f} (bandwidth {sc[1]})")
        if sc[0] > best[0] - MIN_GAIN:
            break
        best_axes, best = axes, sc
        steps.append({"added": axes[-1][0], "weight": weight, "loo_mean_regret": round(sc[0], 4),
                      "bandwidth": sc[1]})
    _, h, per = best
    return {"axes": best_axes, "bandwidth": h, "erel_floor": EREL_FLOOR,
            "loo_mean_regret": {str(b): round(float(np.mean([r.mean() for r in rs])), 4) for b, rs in per.items()},
            "loo_mean_regret_per_grouping": {str(b): [round(float(r.mean()), 4) for r in rs] for b, rs in per.items()},
            "loo_p90_regret": {str(b): [round(float(np.percentile(r, 90)), 4) for r in rs] for b, rs in per.items()},
            "selection": steps,
            "loo_note": note}


def refeature_table(table: dict, rows: dict, *, command: str = "", progress=None) -> dict:
    """``table`` with the extra columns (:data:`EXTRA_COLUMNS`) measured on its meshes and the
    kernel chosen again (:func:`select_axes`). The base columns are recomputed from the same raw
    measures with the table's calibration (they equal the stored ones to their rounding)."""
    from .advisor import calibrate_irregularity, calibrate_noise

    cal = table["calibration"]
    keys = table["truth"]["key"]
    columns = ["density", "noise_level", "irregularity_deg", *EXTRA_COLUMNS]
    pts = []
    for k in keys:
        r = rows[_key_text(k)]
        noise = calibrate_noise(r["noise_raw"], cal, r["density"])
        pts.append([r["density"], noise / NOISE_FRACTION, calibrate_irregularity(r["irregularity_raw_deg"], noise, cal),
                    *(r[c] for c in EXTRA_COLUMNS)])
    pts = np.array(pts, float)
    meta = dict(table["metadata"])
    meta.update(refeature_command=command, created=time.strftime("%Y-%m-%d %H:%M:%S %Z"))
    return {**table, "kernel": _grouped_selection(table, pts, columns, progress), "metadata": meta,
            "columns": columns, "points": [[_round(x, POINT_DIGITS) for x in p] for p in pts]}


def _grouped_selection(table: dict, pts: np.ndarray, columns, progress) -> dict:
    """The kernel :func:`select_axes` chooses over ``table``'s meshes at ``pts`` (``(p, c)``, the
    point columns ``columns``), scored by the mean of the by-surface and by-noise-level groupings."""
    keys = table["truth"]["key"]
    return select_axes(pts, columns, np.array(table["median_erel"], float), [surface_groups(keys), noise_groups(keys)],
                       progress=progress,
                       note="the mean of two grouped leave-one-outs: each mesh advised from the other surfaces "
                            "(its random surface at every density, irregularity and noise level left out), and "
                            "from all but its twins at the other noise levels")


def reselect_table(table: dict, *, command: str = "", progress=None) -> dict:
    """``table`` with the kernel chosen again (:func:`select_axes`) over its stored point columns,
    nothing measured: for a change of the selection's rules (e.g. an axis transform,
    :data:`EXTRA_TRANSFORMS`). The points are the stored ones (:data:`POINT_DIGITS` significant digits)."""
    pts = np.array([[np.nan if x is None else x for x in p] for p in table["points"]], float)
    meta = dict(table["metadata"])
    meta.update(reselect_command=command, created=time.strftime("%Y-%m-%d %H:%M:%S %Z"))
    return {**table, "kernel": _grouped_selection(table, pts, table["columns"], progress), "metadata": meta}


def _write_selected(table: dict, path) -> int:
    """Write a table whose axes were just chosen and say which (the end of ``refeature`` and ``reselect``)."""
    with open(path, "w") as fh:
        json.dump(table, fh, separators=(",", ":"))
    k = table["kernel"]
    print(f"wrote {path}: axes {[a[0] for a in k['axes']]}, bandwidth {k['bandwidth']} "
          f"(grouped LOO mean regret {k['loo_mean_regret'][str(k['bandwidth'])]})", flush=True)
    return 0


def reselect_main(argv) -> int:
    """``python -m curv.advice.table reselect``: choose the kernel's axes again over a table's stored
    points (no mesh is built or measured)."""
    parser = argparse.ArgumentParser(prog="python -m curv.advice.table reselect", description=reselect_main.__doc__)
    parser.add_argument("--table", default=str(DEFAULT_OUT), help="table to reselect; default the packaged one")
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    args = parser.parse_args(argv)
    with open(args.table) as fh:
        table = json.load(fh)
    t0 = time.perf_counter()
    out = reselect_table(table, command=table_command(argv, "reselect"),
                         progress=lambda t: print(t, flush=True))
    out["metadata"]["reselect_seconds"] = round(time.perf_counter() - t0, 1)
    return _write_selected(out, args.out)


def refeature_main(argv) -> int:
    """``python -m curv.advice.table refeature``: measure the extra columns on a table's meshes
    (rebuilt from their keys; no estimator runs but the measuring fit) and choose the kernel's axes."""
    parser = argparse.ArgumentParser(prog="python -m curv.advice.table refeature",
                                     description=refeature_main.__doc__)
    parser.add_argument("--table", default=str(DEFAULT_OUT), help="table to refeature; default the packaged one")
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    parser.add_argument("--work", default="advisor-refeature", help="keeps the measured rows (resumes)")
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args(argv)
    from ..study.executors import open_executor

    with open(args.table) as fh:
        table = json.load(fh)
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    path = work / "features.json"
    rows = json.loads(path.read_text()) if path.exists() else {}
    if rows.get("measures") != FEATURE_MEASURES:
        rows = {"measures": FEATURE_MEASURES}
    todo = [k for k in table["truth"]["key"] if _key_text(k) not in rows]
    t0, c0 = time.perf_counter(), time.process_time()
    with open_executor(workers=args.workers) as ex:
        for b in range(0, len(todo), 64):
            part = todo[b:b + 64]
            for k, row in zip(part, ex.map(feature_row, part)):
                rows[_key_text(k)] = row
            path.write_text(json.dumps(rows))
            print(f"{min(b + 64, len(todo))}/{len(todo)} meshes measured, {time.perf_counter() - t0:.0f} s", flush=True)
    command = table_command(argv, "refeature")
    out = refeature_table(table, rows, command=command, progress=lambda t: print(t, flush=True))
    out["metadata"]["refeature_seconds"] = round(time.perf_counter() - t0, 1)
    out["metadata"]["refeature_cpu_seconds_main_process"] = round(time.process_time() - c0, 1)
    return _write_selected(out, args.out)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["extend"]:
        return extend_main(argv[1:])
    if argv[:1] == ["fill"]:
        return fill_main(argv[1:])
    if argv[:1] == ["refeature"]:
        return refeature_main(argv[1:])
    if argv[:1] == ["reselect"]:
        return reselect_main(argv[1:])
    parser = argparse.ArgumentParser(prog="python -m curv.advice.table", description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(DEFAULT_OUT), help="table to write; default the packaged one")
    parser.add_argument("--work", default="advisor-study", help="study directory (resumes); default ./advisor-study")
    parser.add_argument("--samples", type=int, default=DEFAULT_SAMPLES)
    parser.add_argument("--densities", type=int, nargs="+", default=list(DEFAULT_DENSITIES),
                        help="hexagon vertex counts 3s(s+1)+1")
    parser.add_argument("--noise", type=float, nargs="+", default=list(DEFAULT_NOISE))
    parser.add_argument("--irregularity", type=float, nargs="+", default=list(DEFAULT_IRREGULARITY))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=None, help="local processes; default the study's")
    parser.add_argument("--closed", nargs="*", default=list(DEFAULT_CLOSED), help="closed surfaces to add")
    parser.add_argument("--closed-vertices", type=int, nargs="+", default=list(DEFAULT_CLOSED_VERTICES))
    args = parser.parse_args(argv)
    settings = table_settings(samples=args.samples, densities=args.densities, noise=args.noise,
                              irregularity=args.irregularity, seed=args.seed)
    command = table_command(argv)
    table = build_table(settings, args.work, workers=args.workers, command=command,
                        closed=tuple(args.closed), closed_vertices=tuple(args.closed_vertices),
                        progress=lambda text: print(text, flush=True))
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w") as fh:
        json.dump(table, fh, separators=(",", ":"))
    meta = table["metadata"]
    print(f"wrote {args.out}: {meta['n_meshes']} meshes x {len(table['variants'])} variants; "
          f"calibration {table['calibration']}; bandwidth {table['kernel']['bandwidth']} "
          f"(LOO mean regret {table['kernel']['loo_mean_regret']}); study {meta['study_seconds']} s, "
          f"features {meta['features_seconds']} s, closed surfaces {meta['closed_seconds']} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
