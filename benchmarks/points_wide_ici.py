"""Point clouds, same footing: the adaptive width's interval rule, tuned and checked on held-out surfaces.

Run by hand from the repository root (about 4 minutes on an idle 2-core machine)::

    .venv/bin/python benchmarks/points_wide_ici.py 6      # surfaces 0-5 per function and sampling

The noisy clouds (noise 100 %), evaluated points, normals and APSS scale 16 of
``points_wide_ranges.py`` (its same-footing rule; APSS's best scale on both noisy cells). For every
cloud the candidates of :mod:`curv.estimators.jet_width` (the degree-4 jet over the
:data:`~curv.estimators.jet_width.WIDTH_FRACTIONS` of a ball of 13 median spacings, then the degree-2
smooth jet over the whole ball) are fitted once at the evaluated points, with their standard errors
and ball sizes; the choice rule (:func:`curv.estimators.jet_width.adaptive_choice`) is then applied
for each rule compared, without refitting. On the first surface of each function and sampling the
library's ``width="adaptive"`` is run too and must equal the rule applied here (the largest
difference is printed).

Rules compared: the library's (relative ICI, separate walks for k1 and k2, inverse-variance mean;
:data:`~curv.estimators.jet_width.GAMMA`, :data:`~curv.estimators.jet_width.RATIO`), the previous
one (plain ICI over k1 and k2 together, 2.5 standard errors, midpoint of the final intersection),
and a grid of interval widths and ratios. Each is scored as curvlab / APSS for median e_rel, the
trimmed RMS, nRMS H and nRMS K, pooled per cell over surfaces 0-2 (tuning), 3-5 (held out) and all.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import points_accuracy as pa  # noqa: E402
import points_wide_ranges as pw  # noqa: E402

APSS_SCALE = 16.0
GAMMAS = (2.5, 3.0, 4.0, 5.0, 6.0)
RATIOS = (0.0, 0.5, 0.7, 0.8, 0.85, 0.9)
MEASURES = ("median", "trimmed_rms", "nrms_h", "nrms_k")


def run_cloud(job) -> dict:
    """The candidates' fits at the evaluated points of one noisy cloud, its truth and APSS's values."""
    from scipy.spatial import cKDTree

    import curv
    from curv.core.pointcloud import PointCloud
    from curv.core.ranges import ball_radii, resolve
    from curv.estimators.jet import unknowns
    from curv.estimators.jet_width import (LAST_DEGREE, LAST_WEIGHTS, POINTS_PER_UNKNOWN, WIDTH_FRACTIONS,
                                           adaptive_choice)
    from curv.geometry.neighbourhood import support_sizes
    from curv.point_normals import border_points, point_normals
    from curv.study.protocol import Task
    from curv.study.testmesh import build_test_mesh
    from curv.surfaces import sample_points

    function, sample, s_index = job
    sampling = pa.SAMPLINGS[s_index]
    tm = build_test_mesh(Task(seed=0, function=function, density=pa.DENSITY, irregularity=0.0, noise=1.0,
                              sample=sample))
    rng = np.random.default_rng([sample, pa.FUNCTIONS.index(function), s_index, 16])
    sampled = sample_points(tm.sampled.surface, pa.DENSITY, sampling=sampling, rng=rng)
    border = border_points(sampled.cloud)
    points = sampled.cloud.points + rng.normal(scale=tm.noise_sigma, size=sampled.cloud.points.shape)
    cloud = PointCloud(points)
    median_spacing = float(np.median(ball_radii(cloud, resolve(curv.ESTIMATORS["jet"], 1), uses_normals=False)))
    reach = np.maximum(ball_radii(sampled.cloud, resolve(curv.ESTIMATORS["jet"], pw.REACH), uses_normals=False),
                       pw.REACH * median_spacing)
    ev = np.flatnonzero(cKDTree(sampled.cloud.points[border]).query(sampled.cloud.points)[0] > reach)
    normals = point_normals(cloud).normals
    radius = pw.REACH * median_spacing
    fits = [(f, 4, "uniform") for f in WIDTH_FRACTIONS] + [(1.0, LAST_DEGREE, LAST_WEIGHTS)]
    k1, k2, se1, se2 = (np.empty((len(fits), ev.size)) for _ in range(4))
    for j, (fraction, degree, weights) in enumerate(fits):
        res = curv.estimate(cloud, "jet", radius=fraction * radius, degree=degree, weights=weights,
                            normals=normals, vertices=ev)
        k1[j], k2[j], se1[j], se2[j] = res.k1[ev], res.k2[ev], res.k1_se[ev], res.k2_se[ev]
        counts, _ = support_sizes(cloud, np.full(len(points), fraction * radius), ev)
        se1[j, counts + 1 < POINTS_PER_UNKNOWN * unknowns(degree)] = np.nan
    check = np.nan
    if sample == 0:
        lib = curv.estimate(cloud, "jet", radius=radius, degree=4, width="adaptive", normals=normals, vertices=ev)
        _, _, e1, e2 = adaptive_choice(k1, k2, se1, se2)
        check = float(max(np.nanmax(np.abs(lib.k1[ev] - e1)), np.nanmax(np.abs(lib.k2[ev] - e2))))
    a1, a2, _, _ = pa.apss_curvature(points, normals, APSS_SCALE)
    return dict(cell=sampling, sample=sample, function=function, k1=k1, k2=k2, se1=se1, se2=se2,
                t1=sampled.truth.k1[ev], t2=sampled.truth.k2[ev], apss=pa._errors(sampled.truth.k1[ev],
                sampled.truth.k2[ev], a1[ev], a2[ev]), check=check)


def previous_rule(k1, k2, se1, se2, gamma=2.5):
    """The rule before this one: plain ICI over k1 and k2 together, midpoint of the final intersection."""
    m, n = k1.shape
    lo1, hi1 = np.full(n, -np.inf), np.full(n, np.inf)
    lo2, hi2 = lo1.copy(), hi1.copy()
    going, choice = np.ones(n, bool), np.full(n, -1)
    for j in range(m):
        step = going & np.isfinite(k1[j]) & np.isfinite(k2[j]) & np.isfinite(se1[j]) & np.isfinite(se2[j])
        with np.errstate(invalid="ignore"):
            n1, x1 = np.maximum(lo1, k1[j] - gamma * se1[j]), np.minimum(hi1, k1[j] + gamma * se1[j])
            n2, x2 = np.maximum(lo2, k2[j] - gamma * se2[j]), np.minimum(hi2, k2[j] + gamma * se2[j])
            meets = step & (n1 <= x1) & (n2 <= x2)
        going &= ~step | meets
        lo1, hi1, lo2, hi2 = (np.where(meets, a, b) for a, b in ((n1, lo1), (x1, hi1), (n2, lo2), (x2, hi2)))
        choice[meets] = j
    rows, own = np.arange(n), np.maximum(choice, 0)
    with np.errstate(invalid="ignore"):
        m1, m2 = 0.5 * (lo1 + hi1), 0.5 * (lo2 + hi2)
    ordered = (choice >= 0) & (m1 >= m2)
    e1, e2 = np.where(ordered, m1, k1[own, rows]), np.where(ordered, m2, k2[own, rows])
    e1[choice < 0] = np.nan
    e2[choice < 0] = np.nan
    return e1, e2


def score(clouds, rule, samples) -> dict:
    """``{cell: [curvlab / APSS for each of MEASURES]}`` pooled over the clouds of ``samples``."""
    pooled = {}
    for c in clouds:
        if c["sample"] not in samples:
            continue
        e1, e2 = rule(c["k1"], c["k2"], c["se1"], c["se2"])
        ours, theirs = pooled.setdefault(c["cell"], ([], []))
        ours.append(pa._errors(c["t1"], c["t2"], e1, e2))
        theirs.append(c["apss"])
    out = {}
    for cell, (ours, theirs) in sorted(pooled.items()):
        o, p = pa.summarise(ours), pa.summarise(theirs)
        out[cell] = [o[m] / p[m] for m in MEASURES] + [o["invalid"]]
    return out


def _line(label, result) -> str:
    return f"  {label:38s} " + "   ".join(
        f"{cell}: " + ", ".join(f"{x:.2f}" for x in r[:4]) + (f" ({100 * r[4]:.1f} % invalid)" if r[4] > 0.01 else "")
        for cell, r in result.items())


def main(samples: int, workers: int = 2) -> int:
    from concurrent.futures import ProcessPoolExecutor

    from curv.estimators.jet_width import GAMMA, RATIO, adaptive_choice

    t0 = time.perf_counter()
    jobs = [(fn, s, si) for s in range(samples) for fn in pa.FUNCTIONS for si in range(len(pa.SAMPLINGS))]
    clouds = []
    with ProcessPoolExecutor(workers, initializer=pw._init_worker) as ex:
        for done, c in enumerate(ex.map(run_cloud, jobs), 1):
            clouds.append(c)
            print(f"\r{done}/{len(jobs)} clouds", end="", flush=True)
    print(f"\n{len(jobs)} noisy clouds in {time.perf_counter() - t0:.0f} s on {workers} workers")
    checks = [c["check"] for c in clouds if np.isfinite(c["check"])]
    print(f"library width='adaptive' against the rule applied here: largest difference {max(checks):.3g} "
          f"over {len(checks)} clouds")
    splits = {"surfaces 0-2 (tuning)": range(3), "surfaces 3-5 (held out)": range(3, 6), "all": range(samples)}
    print("\ncurvlab / APSS scale 16: median e_rel, trimmed RMS, nRMS H, nRMS K")
    for name, s in splits.items():
        print(name)
        print(_line(f"library (gamma {GAMMA:g}, ratio {RATIO:g})", score(clouds, lambda *a: adaptive_choice(*a)[2:], s)))
        print(_line("previous (ICI, joint, midpoint, 2.5)", score(clouds, previous_rule, s)))
        print(_line("fixed degree 4, radius 13", score(clouds, lambda k1, k2, *_: (k1[5], k2[5]), s)))
    print("\ngrid (surfaces 0-2): gamma, ratio")
    for gamma in GAMMAS:
        for ratio in RATIOS:
            rule = (lambda g, r: lambda *a: adaptive_choice(*a, gamma=g, ratio=r)[2:])(gamma, ratio)
            print(_line(f"gamma {gamma:g}, ratio {ratio:g}", score(clouds, rule, range(3))))
    return 0


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("samples", type=int, nargs="?", default=6, help="surfaces per function and sampling")
    args = parser.parse_args()
    raise SystemExit(main(args.samples))
