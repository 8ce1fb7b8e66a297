"""Is the smooth twin a fair judge? The check's measured errors against the true ones, per twin model.

Run by hand (not part of the test suite)::

    python benchmarks/bench_advise_twin.py                  # 6 analytic meshes, 3 twin models
    python benchmarks/bench_advise_twin.py --models default quartic

On meshes whose curvature is known exactly (Monge patches of the study, a geodesic sphere, an
ellipsoid, a torus; noisy and not), every candidate below runs on the mesh itself and is scored
against the truth (median e_rel over the evaluated vertices), and the self-check
(:func:`curv.advice.check.iter_check`, 3 copies of 64 centres) measures the same candidates on noisy
copies of the mesh's twin. The twin is built three ways:

- ``default``: the advisor's (heights up to degree 6 over a fitted sphere or plane, Gaussian
  weights, the terms the points cannot tell from noise dropped);
- ``quadric``: every patch a plain quadric over its tangent plane, uniform weights (the model of
  ``qs`` and of the degree-2 jet);
- ``quartic``: a plain quartic over the tangent plane, uniform weights (the degree-4 jet's model).

A twin that favoured the estimator sharing its model would make that estimator's measured error
smaller against its true one than the other candidates'. Reported per twin model: the median of
log(measured / true) per candidate and its range over the meshes (0: measured as it is; negative:
flattered), the median |log(measured / true)| over all, and the regret of the check's pick against
the true best.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

CANDIDATES = ("nc:R1", "qs:R2", "mru:R3", "jet:R2", "jet:R3;degree=4", "jet:R4;degree=4", "icc:R2",
              "mru:R4;fit_range=4;normals=fit")
MODELS = {"default": {}, "quadric": {"fixed_degree": 2, "weight_width": np.inf, "base": False},
          "quartic": {"fixed_degree": 4, "weight_width": np.inf, "base": False}}


def meshes():
    """(label, mesh, truth, evaluated) of the analytic meshes."""
    from tools.advice_table.extend import evaluated_for_table
    from curv.study.protocol import Task
    from curv.study.testmesh import build_test_mesh
    from curv.surfaces import make_surface

    for fn, n, irr, noise in [("trigonometric", 817, 10, 0.3), ("quadratic", 1261, 20, 1.0),
                              ("ellipsoid_patch", 3169, 5, 0.0)]:
        tm = build_test_mesh(Task(19500, fn, n, irr, noise, 0))
        yield f"{fn} {n} noise {noise}", tm.mesh, tm.truth, evaluated_for_table(tm.mesh)
    for name, n, noise in [("sphere", 642, 0.3), ("ellipsoid", 2562, 0.3), ("torus", 1200, 0.0)]:
        s = make_surface(name, n_vertices=n, noise=noise * 0.1, seed=7)
        yield f"{name} {n} noise {noise}", s.mesh, s.truth, np.ones(s.mesh.n_vertices, bool)


def _cell(logs: list) -> str:
    """A table cell: the median of one candidate's log(measured / true), its range over the meshes, the count."""
    if not logs:
        return "-"
    return f"{np.median(logs):+.2f} [{np.min(logs):+.2f}, {np.max(logs):+.2f}] ({len(logs)})"


def main(argv=None) -> int:
    import curv
    from curv.advice.shares import valid_masks
    from curv.advice.check import iter_check
    from curv.core.jit import run_to_end
    from curv.metrics import relative_error
    from curv.variants import Variant

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", default=list(MODELS), choices=list(MODELS))
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    ratios = {m: {v: [] for v in CANDIDATES} for m in args.models}
    regrets = {m: [] for m in args.models}
    for label, mesh, truth, ev in meshes():
        true = {}
        for vid in CANDIDATES:
            r = curv.estimate(mesh, **Variant.from_id(vid).kwargs)
            true[vid] = max(float(np.nanmedian(relative_error(truth.k1[ev], truth.k2[ev], r.k1[ev], r.k2[ev]))), 1e-6)
        centres, masks = valid_masks(mesh, list(CANDIDATES))
        pool = centres[np.all([masks[v] for v in CANDIDATES], axis=0)]
        line = [f"{label}: true best {min(true, key=true.get)}"]
        for model in args.models:
            rep = run_to_end(iter_check(mesh, {v: Variant.from_id(v).kwargs for v in CANDIDATES}, pool,
                                        twin_options=MODELS[model]))
            meas = {v: max(rep.measured[v].erel, 1e-6) for v in CANDIDATES if rep.measured[v].ok}
            for v in meas:
                ratios[model][v].append(np.log(meas[v] / true[v]))
            pick = min(meas, key=meas.get)
            regrets[model].append(true[pick] / min(true.values()))
            line.append(f"{model} picks {pick} (regret {regrets[model][-1]:.2f})")
        print("; ".join(line), flush=True)
    print("\n| candidate | " + " | ".join(f"{m}: median log(measured / true) [min, max] (meshes)" for m in args.models)
          + " |")
    print("|---|" + "---|" * len(args.models))
    for v in CANDIDATES:
        print(f"| {v} | " + " | ".join(_cell(ratios[m][v]) for m in args.models) + " |")
    print("| all: median abs | " + " | ".join(
        f"{np.median(np.abs(np.concatenate([ratios[m][v] for v in CANDIDATES if ratios[m][v]]))):.2f}"
        for m in args.models) + " |")
    print("| the pick's regret: median / max | " + " | ".join(
        f"{np.median(regrets[m]):.2f} / {np.max(regrets[m]):.2f}" for m in args.models) + " |")
    cmd = "benchmarks/bench_advise_twin.py " + " ".join(sys.argv[1:] if argv is None else argv)
    print(f"\nCommand: `{cmd}`; {time.perf_counter() - t0:.0f} s wall.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
