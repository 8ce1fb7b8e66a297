"""Calibration of the per-vertex standard errors (``Curvature.k1_se``, ``k2_se``) on noisy analytic meshes.

Run by hand (not part of the test suite)::

    .venv/bin/python benchmarks/bench_uncertainty.py                 # docs/UNCERTAINTY.md's table
    .venv/bin/python benchmarks/bench_uncertainty.py --samples 1 --densities 817
    .venv/bin/python benchmarks/bench_uncertainty.py --normals      # an and mru by kind of normals

The meshes are the study's (:func:`curv.study.testmesh.build_test_mesh`): a random Monge patch of
eq. 5.1 (quadratic, ellipsoid patch, trigonometric) on the regular hexagon mesh at each density,
with 3D Gaussian noise of 0, 33, 67 and 100 % of the paper's level (:data:`curv.variants.NOISE_FRACTION`
of the mean edge length), evaluated away from the border as in the study. For every estimator and
range the table gives the share of (evaluated, valid) vertices with ``|k_est - k_true| <= 2 se``,
for k1 and k2 pooled over the surfaces, samples and densities, and the median of ``|k_est - k_true| / se``
over both. A Gaussian error of exactly the standard error's size would give 95 % and a median of 0.67;
above that the standard error is too small, below it too large.

``an`` and ``mru`` run with each ``noise_model`` (the default ``"sampled"``, ``"normals"`` and
the independent equations). ``--normals``: an and mru (``noise_model="normals"``) at R2 and R3 with the default
normals, ``normals="fit"`` and the exact normals, on six random trigonometric patches of 3169 vertices at 100 % noise (k1 only): their
standard errors model the default normals (made from the noisy mesh).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import curv
from curv.study.protocol import Task
from curv.study.testmesh import build_test_mesh
from curv.surfaces import PAPER_SURFACES

_NORMALS = {"noise_model": "normals"}
_INDEPENDENT = {"noise_model": "independent"}
VARIANTS = (("nc", 1, {}), ("nc", 2, {}), ("nc", 4, {}), ("qs", 1, {}), ("qs", 2, {}), ("qs", 4, {}),
            ("an", 2, {}), ("an", 3, {}), ("an", 4, {}), ("an", 2, _NORMALS), ("an", 3, _NORMALS), ("an", 4, _NORMALS),
            ("an", 2, _INDEPENDENT), ("an", 3, _INDEPENDENT), ("an", 4, _INDEPENDENT),
            ("mru", 2, {}), ("mru", 3, {}), ("mru", 4, {}),
            ("mru", 2, _NORMALS), ("mru", 3, _NORMALS), ("mru", 4, _NORMALS),
            ("mru", 2, _INDEPENDENT), ("mru", 3, _INDEPENDENT), ("mru", 4, _INDEPENDENT),
            ("jet", 2, {}), ("jet", 3, {}), ("jet", 4, {}), ("jet", 4, {"degree": 4}))
NOISE = (0.0, 0.33, 0.67, 1.0)


def label(method: str, k: int, opts: dict) -> str:
    return f"{method} R{k}" + "".join(f" {name.replace('_', ' ')} {value}" for name, value in opts.items())


def error_ratios(res, truth, evaluated) -> np.ndarray:
    """(2, c) ``|k_est - k_true| / se`` of k1 and k2 at the evaluated valid vertices that have a
    standard error (not those whose fit has no spare equation: nc and qs R1 at a vertex of 5 or
    fewer neighbours, on an irregular mesh)."""
    ok = evaluated & res.valid & np.isfinite(res.k1_se) & np.isfinite(res.k2_se)
    with np.errstate(divide="ignore", invalid="ignore"):  # se = 0 where a noise-free fit is exact
        return np.stack([np.abs(k[ok] - kt[ok]) / se[ok]
                         for k, kt, se in ((res.k1, truth.k1, res.k1_se), (res.k2, truth.k2, res.k2_se))])


def normals_study(seed: int) -> None:
    """The share of k1 within 2 se (median ``|err| / se``) of an and mru by kind of normals."""
    kinds = ("default", "fit", "exact")
    ratios: dict = {}
    for sample in range(6):
        tm = build_test_mesh(Task(seed=seed, function="trigonometric", density=3169, irregularity=0.0, noise=1.0,
                                  sample=sample))
        for method, k in (("an", 2), ("an", 3), ("mru", 2), ("mru", 3)):
            for kind in kinds:
                opts = {} if kind == "default" else {"normals": "fit" if kind == "fit" else tm.truth.normals}
                opts["noise_model"] = "normals"
                res = curv.estimate(tm.mesh, method, k, **opts)
                ok = tm.evaluated & res.valid
                with np.errstate(divide="ignore", invalid="ignore"):
                    r = np.abs(res.k1[ok] - tm.truth.k1[ok]) / res.k1_se[ok]
                ratios.setdefault((method, k, kind), []).append(r)
    print(f"Share of k1 within 2 se (median |err| / se); six random trigonometric patches, 3169 vertices, "
          f"100 % noise, seed {seed}\n")
    print("| | default | `normals=\"fit\"` | exact |")
    print("|---|---|---|---|")
    for method, k in (("an", 2), ("an", 3), ("mru", 2), ("mru", 3)):
        cells = []
        for kind in kinds:
            r = np.concatenate(ratios[method, k, kind])
            cells.append(f"{100 * np.mean(r <= 2.0):.0f} % ({np.median(r):.2f})")
        print(f"| {method} R{k} | " + " | ".join(cells) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--densities", type=int, nargs="+", default=[817, 3169, 12481])
    parser.add_argument("--samples", type=int, default=2, help="random surfaces per function and density")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--normals", action="store_true", help="an and mru by kind of normals instead")
    parser.add_argument("--irregularity", type=float, default=0.0,
                        help="the study's vertex irregularity in degrees (default 0: the regular hexagon mesh)")
    args = parser.parse_args()
    t0 = time.perf_counter()
    if args.normals:
        normals_study(args.seed)
        print(f"\n{time.perf_counter() - t0:.0f} s")
        return
    # totals[(variant, noise)] and by_density[(variant, density)] at 100 % noise
    totals: dict = {}
    by_density: dict = {}
    for density in args.densities:
        for function in PAPER_SURFACES:
            for sample in range(args.samples):
                for noise in NOISE:
                    tm = build_test_mesh(Task(seed=args.seed, function=function, density=density,
                                              irregularity=args.irregularity, noise=noise, sample=sample))
                    for method, k, opts in VARIANTS:
                        res = curv.estimate(tm.mesh, method, k, **opts)
                        ratios = error_ratios(res, tm.truth, tm.evaluated)
                        key = label(method, k, opts)
                        totals.setdefault((key, noise), []).append(ratios)
                        if noise > 0:
                            by_density.setdefault((key, density), []).append(ratios)
    names = [label(*v) for v in VARIANTS]

    def cell(parts) -> str:
        r = np.concatenate(parts, axis=1)
        inside = 100 * np.mean(r <= 2.0, axis=1)
        return f"{inside[0]:.0f} / {inside[1]:.0f} ({np.median(r):.2f})"

    print(f"Share of vertices with |k - k_true| <= 2 se, k1 / k2 in %, (median |k - k_true| / se; 0.67 if "
          f"Gaussian with the error's size); "
          f"densities {', '.join(map(str, args.densities))}, {args.samples} random surfaces of each of "
          f"{', '.join(PAPER_SURFACES)} per density, seed {args.seed}, irregularity {args.irregularity:g} degrees\n")
    print("| estimator | " + " | ".join(f"noise {round(100 * x)} %" for x in NOISE) + " |")
    print("|---|" + "---|" * len(NOISE))
    for name in names:
        print(f"| {name} | " + " | ".join(cell(totals[name, x]) for x in NOISE) + " |")
    print("\nNoisy meshes (33-100 %) by density:\n")
    print("| estimator | " + " | ".join(f"{d} vertices" for d in args.densities) + " |")
    print("|---|" + "---|" * len(args.densities))
    for name in names:
        print(f"| {name} | " + " | ".join(cell(by_density[name, d]) for d in args.densities) + " |")
    print(f"\n{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
