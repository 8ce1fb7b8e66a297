"""Accuracy of every curvlab variant and of the peers on the paper's protocol (§5.1).

Run by hand (not part of the test suite)::

    .venv/bin/python benchmarks/bench_accuracy.py --out docs/accuracy_table.md     # 10 surfaces a cell
    .venv/bin/python benchmarks/bench_accuracy.py --quick                          # 2 surfaces: smoke run
    .venv/bin/python benchmarks/bench_accuracy.py --points --samples 10            # point clouds vs APSS
    .venv/bin/python benchmarks/bench_accuracy.py --points --wide --samples 3      # both at their widest, same footing

``--points`` runs the protocol on point clouds instead (``benchmarks/points_accuracy.py``).

The meshes are the study's (:func:`curv.study.testmesh.build_test_mesh`): the 3169-vertex hexagon
lifted onto a random Monge patch of each of the three functions of eq. 5.1, at irregularity 0 and 25
degrees and noise 0 and 100 % (standard deviation ``NOISE_FRACTION`` = 10 % of the mean edge
length per coordinate), ``--samples`` random surfaces per function and cell. Each estimate is
scored by ``e_rel`` (eq. 5.2, :func:`curv.metrics.relative_error`) at the study's evaluated vertices
(no border vertex within R4 of the clean mesh). Per cell, pooled over its meshes: the median of
``e_rel`` over the evaluated vertices the estimator gave a value for, the paper's trimmed RMS (RMS of
the ``e_rel < 1`` values) and the share of evaluated vertices left invalid. A variant competes for
"best" only if it leaves at most :data:`MAX_INVALID_SHARE` of the vertices invalid.

Variants:

- curvlab: every registry estimator at each of its named ranges (through ``curv.estimate``, Max
  normals), the jet at degrees 3 and 4 (``curv.estimate(..., degree=d)``), and the estimators that
  use normals again with fitted normals
  (:func:`curv.fitted_normals.fitted_normals` at the stated range and degree, passed as ``normals=``).
- peers, each checked for sign and scale on an outward sphere first (:func:`calibrate`; the
  factor found there is applied everywhere and printed): libigl ``principal_curvature`` (k-ring 2
  and 4, ball of 2 and 4 mean edge lengths); pymeshlab ``compute_curvature_principal_directions_per_vertex``
  ('Quadric Fitting' and 'Scale Dependent Quadric Fitting' at 2 and 4 mean edge lengths; the
  values are read from the vertex quality as 'Max Curvature' and 'Min Curvature'); VTK
  ``vtkCurvatures`` through pyvista (mean H and Gaussian K, ``k = H +- sqrt(max(H^2 - K, 0))``);
  trueform ``principal_curvatures`` k=2 and k=4.

Runs on a process pool (``--workers``, default 2, one numba thread each).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

IRREGULARITIES = (0.0, 25.0)
NOISES = (0.0, 1.0)
DENSITY = 3169
MAX_INVALID_SHARE = 0.01
"""A variant that leaves more of the evaluated vertices invalid than this is listed but not ranked."""

FIT_NORMALS = ((4, 2), (3, 4))
"""(range, degree) of the fitted normals tried with the normal-using estimators: R4 degree 2 averages
noise out, R3 degree 4 is the most accurate on clean meshes (docs/ACCURACY.md)."""

JET_DEGREES = (3, 4)
"""Jet degrees run besides the default one."""

NORMAL_USERS = ("ru", "mru", "an", "icc")
"""Estimators whose result rides on the vertex normals and that are re-run with fitted normals."""


# --- peers -------------------------------------------------------------------------------------

def _igl(ring: bool, radius: int):
    def run(v, f):
        import igl

        _, _, pv1, pv2, bad = igl.principal_curvature(v, f.astype(np.int64), radius=radius, useKring=ring)
        k1, k2 = np.array(pv1, float), np.array(pv2, float)
        if len(bad):
            k1[np.asarray(bad)] = np.nan
            k2[np.asarray(bad)] = np.nan
        return k1, k2
    return run


def _meshlab(method: str, scale_edges: float | None = None):
    def run(v, f):
        import pymeshlab as ml

        out = []
        for which in ("Max Curvature", "Min Curvature"):
            ms = ml.MeshSet()
            ms.add_mesh(ml.Mesh(vertex_matrix=v, face_matrix=f.astype(np.int32)))
            kwargs = dict(method=method, curvcolormethod=which, autoclean=False)
            if scale_edges is not None:
                edge = np.linalg.norm(v[f[:, 0]] - v[f[:, 1]], axis=1).mean()
                kwargs["scale"] = ml.PureValue(scale_edges * edge)
            ms.apply_filter("compute_curvature_principal_directions_per_vertex", **kwargs)
            out.append(np.array(ms.current_mesh().vertex_scalar_array(), float))
        return out[0], out[1]
    return run


def _vtk(v, f):
    import pyvista as pv

    poly = pv.PolyData(v, np.column_stack([np.full(len(f), 3), f]).ravel())
    h = np.asarray(poly.curvature("mean"), float)
    k = np.asarray(poly.curvature("gaussian"), float)
    root = np.sqrt(np.maximum(h * h - k, 0.0))
    return h + root, h - root


def _trueform(ring: int):
    def run(v, f):
        import trueform as tf

        k0, k1 = tf.principal_curvatures((f.astype(np.int32), v.astype(np.float64)), k=ring)
        return np.array(k0, float), np.array(k1, float)
    return run


PEERS = {
    "libigl k-ring 2": _igl(True, 2),
    "libigl k-ring 4": _igl(True, 4),
    "libigl ball radius 2": _igl(False, 2),
    "libigl ball radius 4": _igl(False, 4),
    "pymeshlab quadric fit": _meshlab("Quadric Fitting"),
    "pymeshlab scale-dependent quadric fit (2x edge)": _meshlab("Scale Dependent Quadric Fitting", 2.0),
    "pymeshlab scale-dependent quadric fit (4x edge)": _meshlab("Scale Dependent Quadric Fitting", 4.0),
    "VTK mean + Gaussian": _vtk,
    "trueform k=2": _trueform(2),
    "trueform k=4": _trueform(4),
}


def calibrate(radius: float = 2.0) -> dict[str, tuple[float, str]]:
    """Sign and scale of every peer on an outward icosphere of radius ``radius`` (exact k = 1/r).

    Returns
    -------
    dict
        ``{peer: (factor, note)}``: the peer's values are multiplied by ``factor`` (+1 or -1: a
        scale other than 1 within 10 % is reported, not corrected) and re-sorted so k1 >= k2. The
        note also gives the value with the faces reversed, which says whether the peer's sign
        follows the face orientation (as curvlab's does) or is fixed.
    """
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=4, radius=radius)
    v, f = np.asarray(sphere.vertices, float), np.asarray(sphere.faces, np.int64)
    out = {}
    for name, fn in PEERS.items():
        k1, k2 = fn(v, f)
        mean = np.nanmedian(0.5 * (k1 + k2)) * radius
        sign = 1.0 if mean > 0 else -1.0
        f1, f2 = fn(v, f[:, ::-1].copy())
        flipped = np.nanmedian(0.5 * (f1 + f2)) * radius
        note = f"sphere r={radius:g}: median H*r = {mean:+.4f}, with the faces reversed {flipped:+.4f}"
        if abs(abs(mean) - 1.0) > 0.1:
            note += " (scale off by more than 10 %)"
        out[name] = (sign, note)
    return out


# --- curvlab -----------------------------------------------------------------------------------

def _sorted(k1, k2):
    return np.maximum(k1, k2), np.minimum(k1, k2)


def curvlab_variants() -> list[tuple[str, dict]]:
    """``[(label, how), ...]`` of every curvlab variant this benchmark runs."""
    import curv

    out = []
    for name, spec in curv.ESTIMATORS.items():
        for k in spec.ranges:
            out.append((f"{name} R{k}", {"method": name, "k": k}))
    if "jet" in curv.ESTIMATORS:
        for d in JET_DEGREES:
            for k in curv.ESTIMATORS["jet"].ranges:
                out.append((f"jet degree {d} R{k}", {"jet_degree": d, "k": k}))
    for name in NORMAL_USERS:
        if name not in curv.ESTIMATORS:
            continue
        for fit in FIT_NORMALS:
            for k in curv.ESTIMATORS[name].ranges:
                out.append((f"{name} R{k} + fitted normals R{fit[0]} d{fit[1]}",
                            {"method": name, "k": k, "fit": fit}))
    return out


# --- one mesh ----------------------------------------------------------------------------------

def _init_worker():
    os.environ["CURV_THREADS"] = "1"


def run_mesh(job):
    """All variants on one test mesh: ``(cell, {label: e_rel at the evaluated vertices}, {label: s})``."""
    import curv
    from curv.fitted_normals import fitted_normals
    from curv.metrics import relative_error
    from curv.geometry.normals import vertex_normals
    from curv.study.protocol import Task
    from curv.study.testmesh import build_test_mesh

    function, irregularity, noise, sample, signs = job
    tm = build_test_mesh(Task(seed=0, function=function, density=DENSITY, irregularity=irregularity,
                              noise=noise, sample=sample))
    mesh, truth, ev = tm.mesh, tm.truth, tm.evaluated
    t1, t2 = truth.k1[ev], truth.k2[ev]
    max_normals = vertex_normals(mesh)
    fits = {fit: fitted_normals(mesh, range=fit[0], degree=fit[1]) for fit in FIT_NORMALS}
    errors, seconds = {}, {}
    for label, how in curvlab_variants():
        t0 = time.perf_counter()
        if "jet_degree" in how:
            res = curv.estimate(mesh, "jet", how["k"], normals=max_normals, degree=how["jet_degree"])
        else:
            normals = fits[how["fit"]] if "fit" in how else max_normals
            res = curv.estimate(mesh, how["method"], how["k"], normals=normals)
        k1, k2 = res.k1, res.k2
        seconds[label] = time.perf_counter() - t0
        errors[label] = relative_error(t1, t2, k1[ev], k2[ev])
    v, f = np.asarray(mesh.vertices, float), mesh.triangles.astype(np.int64)
    for name, fn in PEERS.items():
        t0 = time.perf_counter()
        k1, k2 = fn(v, f)
        k1, k2 = _sorted(signs[name] * k1, signs[name] * k2)
        seconds[name] = time.perf_counter() - t0
        errors[name] = relative_error(t1, t2, k1[ev], k2[ev])
    return (irregularity, noise), errors, seconds


# --- tables ------------------------------------------------------------------------------------

def summarise(pooled: list[np.ndarray]) -> dict:
    e = np.concatenate(pooled)
    finite = e[np.isfinite(e)]
    kept = finite[finite < 1.0]
    return {
        "median": float(np.median(finite)) if finite.size else np.nan,
        "trimmed_rms": float(np.sqrt(np.mean(kept**2))) if kept.size else np.nan,
        "excluded": float(1.0 - kept.size / finite.size) if finite.size else np.nan,
        "invalid": float(1.0 - finite.size / e.size) if e.size else np.nan,
        "n": int(e.size),
    }


def cell_name(cell) -> str:
    irr, noise = cell
    return f"irregularity {irr:g}, noise {100 * noise:g} %"


def report(stats: dict, peer_labels: set, *, top: int) -> tuple[str, list[str]]:
    """Markdown: the summary table (best curvlab vs best peer per cell) and one table per cell."""
    lines = ["| cell | curvlab best | median e_rel | best peer | median e_rel | curvlab / peer | 20 % lower? |",
             "|---|---|---|---|---|---|---|"]
    details = []
    for cell, rows in stats.items():
        ranked = sorted(((s["median"], label) for label, s in rows.items()
                         if s["invalid"] <= MAX_INVALID_SHARE and np.isfinite(s["median"])))
        ours = [(m, lab) for m, lab in ranked if lab not in peer_labels]
        peers = [(m, lab) for m, lab in ranked if lab in peer_labels]
        (om, ol), (pm, pl) = ours[0], peers[0]
        ratio = om / pm if pm > 0 else np.inf
        lines.append(f"| {cell_name(cell)} | {ol} | {om:.4g} | {pl} | {pm:.4g} | {ratio:.3f} | "
                     f"{'yes' if ratio <= 0.8 else 'no'} |")
        details += ["", f"### {cell_name(cell)}", "",
                    "| rank | variant | median e_rel | trimmed RMS | excluded (e_rel >= 1) | invalid |",
                    "|---|---|---|---|---|---|"]
        shown = [lab for _, lab in ours[:top]] + [lab for _, lab in peers]
        shown += [lab for lab in rows if lab not in shown and rows[lab]["invalid"] > MAX_INVALID_SHARE
                  and lab in peer_labels]
        order = {lab: i + 1 for i, (_, lab) in enumerate(ranked)}
        for lab in sorted(shown, key=lambda x: order.get(x, 10**6)):
            s = rows[lab]
            tag = " (peer)" if lab in peer_labels else ""
            details.append(f"| {order.get(lab, '-')} | {lab}{tag} | {s['median']:.4g} | {s['trimmed_rms']:.4g} | "
                           f"{100 * s['excluded']:.1f} % | {100 * s['invalid']:.1f} % |")
    return "\n".join(lines), details


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=10, help="random surfaces per function and cell")
    parser.add_argument("--quick", action="store_true", help="2 surfaces per function and cell")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--top", type=int, default=12, help="curvlab variants listed per cell")
    parser.add_argument("--out", type=Path, help="write the markdown tables here")
    parser.add_argument("--points", action="store_true",
                        help="point clouds sampled from the same patches, against MeshLab's APSS and the meshes")
    parser.add_argument("--extras", action="store_true",
                        help="--points: also normals fitted over R4 (points and mesh) and the jet at degree 4")
    parser.add_argument("--wide", action="store_true",
                        help="--points: both sides at their widest on the same deep-interior points "
                             "(benchmarks/points_wide_ranges.py)")
    args = parser.parse_args(argv)
    samples = 2 if args.quick else args.samples
    if args.points and args.wide:
        import points_wide_ranges

        return points_wide_ranges.main(samples, args.workers)
    if args.points:
        import points_accuracy

        return points_accuracy.main(samples, args.workers, MAX_INVALID_SHARE, args.out, extras=args.extras)
    t0 = time.perf_counter()
    cal = calibrate()
    signs = {name: sign for name, (sign, _) in cal.items()}
    print("peer calibration (outward icosphere, 2562 vertices):")
    for name, (sign, note) in cal.items():
        print(f"  {name:50s} factor {sign:+.0f}   {note}")
    jobs = [(fn, irr, noise, s, signs) for irr in IRREGULARITIES for noise in NOISES
            for fn in ("quadratic", "ellipsoid_patch", "trigonometric") for s in range(samples)]
    pooled: dict = {}
    seconds: dict = {}
    with ProcessPoolExecutor(args.workers, initializer=_init_worker) as ex:
        for done, (cell, errors, secs) in enumerate(ex.map(run_mesh, jobs), 1):
            for label, e in errors.items():
                pooled.setdefault(cell, {}).setdefault(label, []).append(e)
                seconds[label] = seconds.get(label, 0.0) + secs[label]
            print(f"\r{done}/{len(jobs)} meshes", end="", flush=True)
    print()
    stats = {cell: {label: summarise(es) for label, es in rows.items()} for cell, rows in pooled.items()}
    summary, details = report(stats, set(PEERS), top=args.top)
    elapsed = time.perf_counter() - t0
    header = [f"Protocol: {DENSITY}-vertex hexagon, functions quadratic / ellipsoid_patch / trigonometric, "
              f"{samples} surfaces per function and cell (seed 0), median e_rel pooled over the evaluated "
              f"vertices; ranked variants leave at most {100 * MAX_INVALID_SHARE:g} % invalid. "
              f"{len(jobs)} meshes in {elapsed:.0f} s on {args.workers} workers.", "",
              "Peer sign/scale check on an outward sphere (factor applied):", ""]
    header += [f"- {name}: factor {sign:+.0f}; {note}" for name, (sign, note) in cal.items()]
    text = "\n".join(header + ["", summary] + details) + "\n"
    print(text)
    slowest = sorted(seconds.items(), key=lambda kv: -kv[1])[:5]
    print("slowest variants (total s):", ", ".join(f"{k} {v:.1f}" for k, v in slowest))
    if args.out:
        args.out.write_text(text)
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
