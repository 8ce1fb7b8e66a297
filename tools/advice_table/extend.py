"""The table's extension: the option candidates as columns, the coarse meshes, the closed sizes and
the noise twins as rows (``extend`` and ``fill``), and the meshes of a table key rebuilt and scored."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from curv.advice.features import raw_measures
from curv.variants import NOISE_FRACTION

from .base import (DEFAULT_CLOSED, DEFAULT_CLOSED_VERTICES, DEFAULT_DENSITIES, EREL_DIGITS, POINT_DIGITS, _round,
                   random_closed_params)
from .kernel import fit_kernel, key_text

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
    from curv.estimators import ESTIMATORS
    from curv.variants import Variant

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
    from curv.study.testmesh import evaluated_vertices

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
    from curv.api import estimate
    from curv.fitted_normals import fitted_normals
    from curv.geometry.normals import vertex_normals
    from curv.study.metrics import summarize
    from curv.variants import Variant

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

    from curv.study.protocol import Task
    from curv.study.testmesh import build_test_mesh
    from curv.surfaces import make_surface

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
    from curv.study.executors import open_executor

    work_dir = Path(work_dir)
    work_dir.mkdir(parents=True, exist_ok=True)
    path = work_dir / "extension.json"
    done = json.loads(path.read_text()) if path.exists() else {}
    todo = [j for j in jobs if not set(j[1]) <= set(done.get(key_text(j[0]), [None, {}])[1])]
    say = progress or (lambda text: None)
    say(f"{len(jobs)} jobs, {len(todo)} to run")
    t0 = time.perf_counter()
    batch = 16
    with open_executor(workers=workers) as ex:
        for b in range(0, len(todo), batch):
            part = todo[b:b + batch]
            for job, (row, erel) in zip(part, ex.map(candidate_point, part)):
                old = done.get(key_text(job[0]), [row, {}])
                done[key_text(job[0])] = [row, {**old[1], **erel}]
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
    cal = base["calibration"]
    variants = list(base["variants"]) + [v for v in option_variants() if v not in base["variants"]]
    col = {v: j for j, v in enumerate(variants)}
    keys = [list(k) for k in base["truth"]["key"]]
    erel = np.full((len(keys), len(variants)), np.nan)
    erel[:, : len(base["variants"])] = np.array(base["median_erel"], float)
    points = [list(p) for p in base["points"]]
    truth = {k: list(v) for k, v in base["truth"].items()}
    truth.setdefault("n_evaluated", [None] * len(keys))
    index = {key_text(k): i for i, k in enumerate(keys)}
    if jobs is not None:  # exactly the planned meshes (a work directory may hold more)
        planned = {key_text(j[0]) for j in jobs}
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
    from curv.advice.features import calibrate_irregularity, calibrate_noise

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



def load_base(path) -> dict:
    """The base table to extend (what ``python -m tools.advice_table --out base.json`` writes); an
    already extended table is refused (its option columns would be taken for base ones)."""
    with open(path) as fh:
        table = json.load(fh)
    if set(option_variants()) & set(table["variants"]):
        raise SystemExit(f"{path}: already extended; give the base table (python -m tools.advice_table --out base.json)")
    return table


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
    have = {key_text(k) for k in table["truth"]["key"]}
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
    return [j for j in jobs if key_text(j[0]) not in have]


def noise_jobs(table: dict, levels, sizes=None) -> list[tuple]:
    """Jobs (:func:`candidate_point`, every variant of ``table``) for the noise twins at ``levels``
    (fractions of the paper's level) of every noise-free mesh of ``table`` (of ``sizes`` if given:
    a key's density or vertex count) that ``table`` does not hold yet: the same surface,
    tessellation and noise directions (:func:`table_mesh`), a noise level between the grid's. Largest
    meshes first (load balance)."""
    have = {key_text(k) for k in table["truth"]["key"]}
    every = tuple(table["variants"])
    jobs = []
    for key in table["truth"]["key"]:
        if key[4] != 0 or (sizes is not None and key[2] not in sizes):
            continue
        for lv in levels:
            twin = [*key[:4], float(lv), key[5]]
            if key_text(twin) not in have:
                have.add(key_text(twin))
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
        got = done.get(key_text(key))
        if got is None:
            continue
        for vid, x in got[1].items():
            j = col.get(vid)
            if j is not None and erel[i][j] is None and x is not None and np.isfinite(x) and x > 0:
                erel[i][j] = _round(x, EREL_DIGITS)
                filled += 1
    new_rows = [done[key_text(k)] for k in new_keys if key_text(k) in done]
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


