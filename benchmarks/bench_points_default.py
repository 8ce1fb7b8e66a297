"""Which point estimator serves as the default on clouds: each at the default range R2, normals estimated.

    .venv/bin/python benchmarks/bench_points_default.py            # one seed, about 5 minutes on 2 cores
    .venv/bin/python benchmarks/bench_points_default.py --seeds 3

Clouds of about 8000 points sampled from analytic surfaces (``curv.surfaces.sample_points``: uniform
random, blue noise, and scan rows 4:1 where the surface allows them), clean and with 3-D Gaussian
noise of 0.05 spacings; no normals given, so each call fits and orients its own (as a scan without
normals). For each estimator that runs on points, at R2: the share of points valid, the median and
the 99th percentile of e_rel (paper eq. 5.2) over the valid points. The default is the registry's
``DEFAULT_ESTIMATORS["points"]`` (curv/estimators/registry.py), chosen from this table and
docs/accuracy_points_tables.md.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's curv

import curv  # noqa: E402
from curv.estimators import DEFAULT_ESTIMATORS  # noqa: E402
from curv.metrics import relative_error  # noqa: E402
from curv.surfaces import sample_points  # noqa: E402

SURFACES = ("quadratic", "trigonometric", "cylinder", "torus")
SAMPLINGS = ("uniform", "blue", "rows")
NOISES = (0.0, 0.05)
METHODS = ("qs", "jet", "mru")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=8000)
    parser.add_argument("--seeds", type=int, default=1)
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    args = parser.parse_args()
    print(f"default on clouds: {DEFAULT_ESTIMATORS['points']}; {args.points} points, R2")
    print(f"{'surface':<14}{'sampling':<9}{'noise':>6}  " + "  ".join(f"{m + ' valid, median, p99':<26}"
                                                                 for m in args.methods))
    table = []
    for surface in SURFACES:
        for sampling in SAMPLINGS:
            for noise in NOISES:
                cells = {m: [] for m in args.methods}
                try:
                    for seed in range(args.seeds):
                        s = sample_points(surface, args.points, sampling=sampling, noise=noise, rng=seed)
                        cloud = curv.PointCloud(s.cloud.points)
                        for m in args.methods:
                            res = curv.estimate(cloud, m, 2)
                            err = relative_error(s.truth.k1, s.truth.k2, res.k1, res.k2)
                            ok = res.valid & np.isfinite(err)
                            cells[m].append((res.valid.mean(), np.median(err[ok]), np.percentile(err[ok], 99)))
                except ValueError:  # a surface that cannot be sampled in rows
                    continue
                means = {m: np.mean(cells[m], axis=0) for m in args.methods}
                table.append(means)
                print(f"{surface:<14}{sampling:<9}{noise:>6g}  " + "  ".join(
                    f"{100 * v:5.1f} %, {med:8.4f}, {p99:7.3f} " for v, med, p99 in means.values()), flush=True)
    print("per estimator over the cells: lowest median e_rel in how many; its median e_rel over the cell's best "
          "(geometric mean, worst); lowest valid share")
    for m in args.methods:
        ratios = np.array([cell[m][1] / min(c[1] for c in cell.values()) for cell in table])
        wins = int(sum(r == 1.0 for r in ratios))
        print(f"  {m:<5} best in {wins:>2} of {len(table)}; {np.exp(np.log(ratios).mean()):.2f}x, worst "
              f"{ratios.max():.1f}x; valid >= {100 * min(cell[m][0] for cell in table):.1f} %")


if __name__ == "__main__":
    main()
