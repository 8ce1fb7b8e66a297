"""The paper's accuracy protocol (§5.1) on point clouds: ``bench_accuracy.py --points``.

Every cloud is sampled from the same random Monge patch as one of the study's test meshes
(:func:`curv.study.testmesh.build_test_mesh` at irregularity 0, the 3169-vertex hexagon, seed 0):
about :data:`DENSITY` points drawn by :func:`curv.surfaces.sample_points`, uniform random or blue
noise (the two samplings take the place of the mesh study's irregularity). Noise 100 % is 3-D
Gaussian noise of the *same absolute* standard deviation as on that mesh: ``NOISE_FRACTION`` (10 %)
of the clean mesh's mean edge length per coordinate; the truth stays that of the clean point.

Evaluated points mirror the study's evaluated vertices: on the clean cloud, the points the library
marks as the border of the scan (:func:`curv.point_normals.border_points`) are found, and a point is
evaluated if none of them lies within its R4 ball (4 spacings, :func:`curv.core.ranges.ball_radii`).

Normals: estimated from the (noisy) points, as a scan without normals would be
(:func:`curv.point_normals.point_normals`, jet fits at R2, oriented up); every curvlab estimator
and APSS get the same normals.

Variants: curvlab's point estimators (``curv.estimators.point_estimators()``) at every named range;
the peer is MeshLab's APSS (``compute_curvature_and_color_apss_per_vertex`` through pymeshlab) at
several filter scales (:data:`APSS_SCALES`, in mean point spacings, MeshLab's own unit). APSS gives
the mean curvature as ``k1 + k2`` ("Mean", 2 on a unit sphere) and the Gaussian curvature K
("Gauss"), positive on a sphere whose normals point outward, as curvlab's convention; its "K1"
and "K2" types abort the process (double free, pymeshlab 2023.12), so its principal curvatures
are made from H and K: ``k = H +- sqrt(max(H^2 - K, 0))`` (:func:`apss_curvature`, checked on
spheres and a cylinder by :func:`calibrate_apss`). The mesh reference is curvlab's mesh estimators
on the matching study mesh (same surface, same noise level), evaluated on the study's vertices.
"""

from __future__ import annotations

import os
import time

import numpy as np

DENSITY = 3169
SAMPLINGS = ("uniform", "blue")
NOISES = (0.0, 1.0)
FUNCTIONS = ("quadratic", "ellipsoid_patch", "trigonometric")
APSS_SCALES = (3.0, 4.0, 6.0, 8.0, 12.0)
"""APSS filter scales tried (MeshLab multiplies them by the mean point spacing); the best per cell is
kept, which favours APSS."""
EVALUATION_RANGE = 4
EXTRA_NORMAL_RANGE = 4
"""``extras``: every estimator again on normals fitted over R4 (degree-2 jet), on points and on the
mesh (the mesh study's choice under noise), and the jet at degree 4 (its choice on clean meshes)."""
EXTRA_JET_DEGREE = 4
MESH_NAME = "mesh"


# --- APSS ----------------------------------------------------------------------------------------

def _apss_values(points, normals, kind: str, scale: float) -> np.ndarray:
    import pymeshlab as ml

    ms = ml.MeshSet()
    ms.add_mesh(ml.Mesh(vertex_matrix=np.asarray(points, float), v_normals_matrix=np.asarray(normals, float)))
    ms.apply_filter("compute_curvature_and_color_apss_per_vertex", curvaturetype=kind, filterscale=float(scale))
    return np.array(ms.current_mesh().vertex_scalar_array(), float)


def apss_curvature(points, normals, scale: float = 2.0):
    """MeshLab APSS on a point set, converted to curvlab's quantities.

    Parameters
    ----------
    points, normals : (n, 3) float
        The points and their unit normals (APSS is signed by them); points whose normal is NaN
        are left out of APSS's input and get NaN.
    scale : float
        APSS filter scale in mean point spacings.

    Returns
    -------
    k1, k2, h, k : (n,) float
        ``h = Mean / 2`` (APSS's "Mean" is ``k1 + k2``), ``k`` = "Gauss", and the principal
        curvatures they imply, ``k1 >= k2``; NaN where APSS gives a non-finite value.
    """
    points, normals = np.asarray(points, float), np.asarray(normals, float)
    # A NaN normal (a point whose orientation the library left ambiguous) poisons every APSS fit
    # whose ball holds it (MeshLab then reports 0 there): APSS gets only the points with a normal,
    # and the others are NaN (no estimate), as curvlab's estimators leave them.
    ok = np.isfinite(normals).all(axis=1)
    h = np.full(len(points), np.nan)
    k = np.full(len(points), np.nan)
    h[ok] = 0.5 * _apss_values(points[ok], normals[ok], "Mean", scale)
    k[ok] = _apss_values(points[ok], normals[ok], "Gauss", scale)
    root = np.sqrt(np.maximum(h * h - k, 0.0))
    return h + root, h - root, h, k


def calibrate_apss(n: int = 4000, seed: int = 0) -> list[str]:
    """APSS's scale and sign on spheres (radius 1 and 2, normals out and in) and a unit cylinder.

    Returns
    -------
    list of str
        One line per case: the median converted H and K against the exact values.
    """
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    lines = []
    for r in (1.0, 2.0):
        for sign, word in ((1.0, "outward"), (-1.0, "inward")):
            _, _, h, k = apss_curvature(r * p, sign * p)
            lines.append(f"sphere r={r:g}, {word} normals: APSS H {np.median(h):+.4f} (exact {sign / r:+.4f}), "
                         f"K {np.median(k):+.4f} (exact {1 / r**2:+.4f})")
    t = rng.uniform(0.0, 2.0 * np.pi, 4 * n)
    z = rng.uniform(-4.0, 4.0, 4 * n)
    v = np.column_stack([np.cos(t), np.sin(t), z])
    nrm = np.column_stack([np.cos(t), np.sin(t), np.zeros_like(t)])
    k1, k2, h, k = apss_curvature(v, nrm)
    mid = np.abs(z) < 2.0
    lines.append(f"cylinder r=1, outward normals: APSS H {np.median(h[mid]):+.4f} (exact +0.5000), "
                 f"K {np.median(k[mid]):+.4f} (exact 0), k1 {np.median(k1[mid]):+.4f} (exact 1), "
                 f"k2 {np.median(k2[mid]):+.4f} (exact 0)")
    return lines


# --- one surface ---------------------------------------------------------------------------------

def evaluated_points(clean) -> np.ndarray:
    """(n,) bool: points with no border point of the clean cloud within their R4 ball."""
    from scipy.spatial import cKDTree

    import curv
    from curv.point_normals import border_points
    from curv.core.ranges import ball_radii, resolve

    border = border_points(clean)
    if not border.any():
        return np.ones(clean.n_points, bool)
    radii = ball_radii(clean, resolve(curv.ESTIMATORS["qs"], EVALUATION_RANGE), uses_normals=False)
    d, _ = cKDTree(clean.points[border]).query(clean.points)
    return d > radii


def _errors(t1, t2, k1, k2) -> dict:
    """Per-point errors kept for pooling: e_rel, H and K errors, and the curvature scale c."""
    from curv.metrics import relative_error

    return {"e_rel": relative_error(t1, t2, k1, k2),
            "dh": 0.5 * (k1 + k2) - 0.5 * (t1 + t2),
            "dk": k1 * k2 - t1 * t2,
            "c": 0.5 * (np.abs(t1) + np.abs(t2))}


def _variants(names, extras: bool):
    """``[(label, method, k, normal set, options)]``: each estimator at each named range, and the extras."""
    import curv

    out = [(f"{name} R{k}", name, k, "default", {}) for name in names for k in curv.ESTIMATORS[name].ranges]
    if extras:
        out += [(f"{lab} + normals R{EXTRA_NORMAL_RANGE}", name, k, "fitted", opt) for lab, name, k, _, opt in out]
        out += [(f"jet degree {EXTRA_JET_DEGREE} R{k}", "jet", k, "default", {"degree": EXTRA_JET_DEGREE})
                for k in curv.ESTIMATORS["jet"].ranges]
    return out


def run_surface(job):
    """Every variant on the clouds and the mesh of one random surface at one noise level.

    Returns
    -------
    list of (cell, {label: errors}, {label: seconds})
        Cells ``(sampling, noise)`` and ``("mesh", noise)``.
    """
    import curv
    from curv.estimators.registry import point_estimators
    from curv.geometry.normals import vertex_normals
    from curv.point_normals import point_normals
    from curv.core.pointcloud import PointCloud
    from curv.study.protocol import Task
    from curv.study.testmesh import build_test_mesh
    from curv.surfaces import sample_points

    from curv.fitted_normals import fitted_normals

    function, noise, sample, extras = job
    task = Task(seed=0, function=function, density=DENSITY, irregularity=0.0, noise=noise, sample=sample)
    tm = build_test_mesh(task)
    surface = tm.sampled.surface
    out = []

    # the mesh reference: curvlab's mesh estimators on the study's mesh of the same surface
    mesh, ev = tm.mesh, tm.evaluated
    t1, t2 = tm.truth.k1[ev], tm.truth.k2[ev]
    normals = {"default": vertex_normals(mesh)}
    if extras:
        normals["fitted"] = fitted_normals(mesh, range=EXTRA_NORMAL_RANGE, degree=2)
    errors, seconds = {}, {}
    for label, name, k, which, options in _variants(list(curv.ESTIMATORS), extras):
        t0 = time.perf_counter()
        res = curv.estimate(mesh, name, k, normals=normals[which], **options)
        seconds[label] = time.perf_counter() - t0
        errors[label] = _errors(t1, t2, res.k1[ev], res.k2[ev])
    out.append(((MESH_NAME, noise), errors, seconds, {}))

    for s_index, sampling in enumerate(SAMPLINGS):
        rng = np.random.default_rng([sample, FUNCTIONS.index(function), s_index, 16])
        sampled = sample_points(surface, DENSITY, sampling=sampling, rng=rng)
        ev = evaluated_points(sampled.cloud)
        points = sampled.cloud.points
        if noise:
            points = points + rng.normal(scale=tm.noise_sigma, size=points.shape)
        cloud = PointCloud(points)
        t1, t2 = sampled.truth.k1[ev], sampled.truth.k2[ev]
        t0 = time.perf_counter()
        est = point_normals(cloud)
        normal_seconds = time.perf_counter() - t0
        normals = {"default": est.normals}
        if extras:
            fitted = point_normals(cloud, range=EXTRA_NORMAL_RANGE).normals.copy()
            # both are oriented up from the same PCA frames; keep the R2 normals' side where they differ
            fitted[np.einsum("ij,ij->i", fitted, est.normals) < 0] *= -1.0
            normals["fitted"] = fitted
        errors, seconds = {}, {}
        for label, name, k, which, options in _variants(point_estimators(), extras):
            t0 = time.perf_counter()
            res = curv.estimate(cloud, name, k, normals=normals[which], **options)
            seconds[label] = time.perf_counter() - t0 + normal_seconds
            errors[label] = _errors(t1, t2, res.k1[ev], res.k2[ev])
        for scale in APSS_SCALES:
            label = f"APSS scale {scale:g}"
            t0 = time.perf_counter()
            k1, k2, _, _ = apss_curvature(points, est.normals, scale)
            seconds[label] = time.perf_counter() - t0 + normal_seconds
            errors[label] = _errors(t1, t2, k1[ev], k2[ev])
        facts = {"points": cloud.n_points, "evaluated": int(ev.sum()),
                 "sigma_over_spacing": tm.noise_sigma / sampled.info["spacing"],
                 "sigma_over_edge": tm.noise_sigma / tm.mesh.mean_edge_length if noise else 0.0,
                 "spacing_over_edge": sampled.info["spacing"] / tm.mesh.mean_edge_length}
        out.append(((sampling, noise), errors, seconds, facts))
    return out


# --- tables --------------------------------------------------------------------------------------

def _rms(x):
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else float("nan")


def summarise(pooled: list[dict]) -> dict:
    """Pooled measures: median e_rel, the paper's trimmed RMS, shares excluded and invalid, nRMS H and K."""
    e = np.concatenate([p["e_rel"] for p in pooled])
    dh = np.concatenate([p["dh"] for p in pooled])
    dk = np.concatenate([p["dk"] for p in pooled])
    c = np.concatenate([p["c"] for p in pooled])
    ok = np.isfinite(e)
    finite = e[ok]
    kept = finite[finite < 1.0]
    return {
        "median": float(np.median(finite)) if finite.size else np.nan,
        "trimmed_rms": _rms(kept),
        "excluded": float(1.0 - kept.size / finite.size) if finite.size else np.nan,
        "invalid": float(1.0 - finite.size / e.size) if e.size else np.nan,
        "nrms_h": _rms(dh[ok]) / _rms(c[ok]) if finite.size else np.nan,
        "nrms_k": _rms(dk[ok]) / _rms(c[ok] ** 2) if finite.size else np.nan,
        "n": int(e.size),
    }


def _best(rows: dict, labels, max_invalid: float):
    ranked = sorted((s["median"], lab) for lab, s in rows.items()
                    if lab in labels and s["invalid"] <= max_invalid and np.isfinite(s["median"]))
    return ranked[0][1] if ranked else None


def cell_name(cell) -> str:
    sampling, noise = cell
    what = "mesh (hexagon, irregularity 0)" if sampling == MESH_NAME else f"{sampling} points"
    return f"{what}, noise {100 * noise:g} %"


def report(stats: dict, max_invalid: float) -> tuple[str, str, list[str]]:
    """Markdown: curvlab's best on points against APSS's best, points against the mesh, per-cell tables."""
    vs_apss = ["| cell | curvlab best | median e_rel | trimmed RMS | nRMS H | nRMS K | APSS best | median e_rel | "
               "trimmed RMS | nRMS H | nRMS K | curvlab / APSS (median e_rel, RMS, H, K) | 20 % ahead in all? |",
               "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    vs_mesh = ["| cell | points best | median e_rel | mesh best (same noise) | median e_rel | points / mesh |",
               "|---|---|---|---|---|---|"]
    details = []
    for cell in sorted(c for c in stats if c[0] != MESH_NAME):
        rows = stats[cell]
        ours = _best(rows, [lab for lab in rows if not lab.startswith("APSS")], max_invalid)
        peer = _best(rows, [lab for lab in rows if lab.startswith("APSS")], max_invalid)
        o, p = rows[ours], rows[peer]
        ratios = [o[m] / p[m] for m in ("median", "trimmed_rms", "nrms_h", "nrms_k")]
        vs_apss.append(f"| {cell_name(cell)} | {ours} | {o['median']:.4g} | {o['trimmed_rms']:.4g} | "
                       f"{o['nrms_h']:.4g} | {o['nrms_k']:.4g} | {peer} | {p['median']:.4g} | "
                       f"{p['trimmed_rms']:.4g} | {p['nrms_h']:.4g} | {p['nrms_k']:.4g} | "
                       f"{', '.join(f'{r:.3f}' for r in ratios)} | {'yes' if max(ratios) <= 0.8 else 'no'} |")
        mesh_rows = stats.get((MESH_NAME, cell[1]), {})
        mbest = _best(mesh_rows, list(mesh_rows), max_invalid)
        if mbest:
            m = mesh_rows[mbest]
            vs_mesh.append(f"| {cell_name(cell)} | {ours} | {o['median']:.4g} | {mbest} | {m['median']:.4g} | "
                           f"{o['median'] / m['median']:.2f} |")
    for cell in sorted(stats):
        rows = stats[cell]
        details += ["", f"### {cell_name(cell)}", "",
                    "| variant | median e_rel | trimmed RMS | excluded (e_rel >= 1) | invalid | nRMS H | nRMS K |",
                    "|---|---|---|---|---|---|---|"]
        for lab in sorted(rows, key=lambda x: (rows[x]["invalid"] > max_invalid, rows[x]["median"])):
            s = rows[lab]
            details.append(f"| {lab} | {s['median']:.4g} | {s['trimmed_rms']:.4g} | {100 * s['excluded']:.1f} % | "
                           f"{100 * s['invalid']:.1f} % | {s['nrms_h']:.4g} | {s['nrms_k']:.4g} |")
    return "\n".join(vs_apss), "\n".join(vs_mesh), details


def _init_worker():
    os.environ["CURV_THREADS"] = "1"


def main(samples: int, workers: int, max_invalid: float, out=None, extras: bool = False) -> int:
    """Run the protocol on ``samples`` surfaces per function and noise level and print the tables."""
    from concurrent.futures import ProcessPoolExecutor

    t0 = time.perf_counter()
    calibration = calibrate_apss()
    print("APSS sign and scale (converted: H = Mean / 2, K = Gauss):")
    for line in calibration:
        print("  " + line)
    jobs = [(fn, noise, s, extras) for noise in NOISES for fn in FUNCTIONS for s in range(samples)]
    pooled: dict = {}
    seconds: dict = {}
    facts: dict = {}
    with ProcessPoolExecutor(workers, initializer=_init_worker) as ex:
        for done, results in enumerate(ex.map(run_surface, jobs), 1):
            for cell, errors, secs, fact in results:
                for label, e in errors.items():
                    pooled.setdefault(cell, {}).setdefault(label, []).append(e)
                    seconds[label] = seconds.get(label, 0.0) + secs[label]
                for key, value in fact.items():
                    facts.setdefault(cell, {}).setdefault(key, []).append(value)
            print(f"\r{done}/{len(jobs)} surfaces", end="", flush=True)
    print()
    stats = {cell: {label: summarise(es) for label, es in rows.items()} for cell, rows in pooled.items()}
    vs_apss, vs_mesh, details = report(stats, max_invalid)
    elapsed = time.perf_counter() - t0
    header = [f"Protocol: points sampled from the study's random Monge patches (quadratic / ellipsoid_patch / "
              f"trigonometric, {samples} surfaces per function and noise level, seed 0), about {DENSITY} "
              f"points each, uniform random or blue-noise sampling; noise 100 % = 3-D Gaussian noise of "
              f"{100 * _noise_fraction():g} % of the matching study mesh's mean edge length per coordinate. "
              f"Normals estimated from the points (jet R2, oriented up), shared by every variant "
              f"({'extras: also normals fitted over R4, on points and mesh, and the jet at degree 4' if extras else 'no extras'}). Ranked "
              f"variants leave at most {100 * max_invalid:g} % of the evaluated points invalid. "
              f"{len(jobs)} surfaces in {elapsed:.0f} s on {workers} workers.", "",
              "APSS sign and scale (H = Mean / 2, K = Gauss, k = H +- sqrt(max(H^2 - K, 0))):", ""]
    header += [f"- {line}" for line in calibration]
    header += ["", "Clouds per cell (means over the surfaces):", ""]
    for cell, f in sorted(facts.items()):
        header.append(f"- {cell_name(cell)}: {np.mean(f['points']):.0f} points, {np.mean(f['evaluated']):.0f} "
                      f"evaluated; mean spacing (6th neighbour) = {np.mean(f['spacing_over_edge']):.3f} mesh "
                      f"edges; noise sigma = {np.mean(f['sigma_over_spacing']):.4f} spacings")
    text = "\n".join(header + ["", "#### curvlab on points against APSS", "", vs_apss,
                               "", "#### points against curvlab's mesh estimates", "", vs_mesh] + details) + "\n"
    print(text)
    slowest = sorted(seconds.items(), key=lambda kv: -kv[1])[:6]
    print("slowest variants (total s, point normals included):", ", ".join(f"{k} {v:.1f}" for k, v in slowest))
    if out:
        out.write_text(text)
        print(f"wrote {out}")
    return 0


def _noise_fraction() -> float:
    from curv.variants import NOISE_FRACTION

    return NOISE_FRACTION
