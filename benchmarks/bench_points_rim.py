"""The open-scan rim on point clouds: how many rim points still get a value, and false borders on closed clouds.

Run by hand (not part of the test suite)::

    python benchmarks/bench_points_rim.py                 # 3 open patches, 4 closed clouds
    python benchmarks/bench_points_rim.py --seeds 5 6 7 8 9 --skip-closed

Open: uniform random samples of 8000 points of the study's quadratic Monge patch (the hexagon of
apothem sqrt(3)/2, :class:`curv.surfaces.QuadraticPatch`), no noise, no normals given, estimated
with ``qs`` R2 (the library's points default). A point is *on the rim* when it lies within 0.015 of
the patch's edge (the convex hull of the samples, in the plane: 1.5 % of the patch's width, about
0.6 of a spacing); the issue's target: at most 10 % of them valid, at least 90 % of the others.

Closed: points the border test marks (:func:`curv.point_normals.border_points`, the gap test and
the one-sided supports) on clouds with no rim at all: uniform random spheres of 200,000 points,
a torus and a spheroid of 20,000, a blue-noise sphere of 4000 (every marked point is false).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

RIM_WIDTH = 0.015


def hull_distance(xy: np.ndarray) -> np.ndarray:
    """(n,) distance of each 2-D point inside its convex hull to the hull's edge."""
    from scipy.spatial import ConvexHull

    h = ConvexHull(xy)
    return np.min(-(xy @ h.equations[:, :2].T + h.equations[:, 2]), axis=1)


def open_patch(seed: int, n_points: int = 8000) -> dict:
    import curv
    from curv.core.ranges import point_spacing
    from curv.surfaces import QuadraticPatch, sample_points

    cloud = sample_points(QuadraticPatch(), n_points, rng=seed).cloud
    res = curv.estimate(cloud, "qs", 2)
    rim = hull_distance(cloud.points[:, :2]) < RIM_WIDTH
    return {"seed": seed, "rim": int(rim.sum()), "rim_valid": float(res.valid[rim].mean()),
            "interior_valid": float(res.valid[~rim].mean()),
            "rim_spacings": RIM_WIDTH / float(np.median(point_spacing(cloud)))}


def closed_clouds():
    from curv.surfaces import Ellipsoid, Sphere, Torus, sample_points

    yield "sphere, 200,000 uniform random", lambda: sample_points(Sphere(), 200000, rng=3).cloud
    yield "torus (1, 0.4), 20,000 uniform random", lambda: sample_points(Torus(1.0, 0.4), 20000, rng=5).cloud
    yield "spheroid (1, 1, 0.6), 20,000 uniform random", lambda: sample_points(Ellipsoid(1.0, 1.0, 0.6), 20000,
                                                                             rng=7).cloud
    yield "sphere, 4000 blue noise", lambda: sample_points(Sphere(), 4000, sampling="blue", rng=6).cloud


def main(argv=None) -> int:
    from curv.point_normals import border_points

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[5, 6, 7])
    parser.add_argument("--skip-closed", action="store_true")
    args = parser.parse_args(argv)
    print("| open patch seed | rim points (within 0.015: spacings) | rim valid | interior valid |")
    print("|---|---|---|---|")
    for seed in args.seeds:
        r = open_patch(seed)
        print(f"| {seed} | {r['rim']} ({r['rim_spacings']:.2f}) | {100 * r['rim_valid']:.1f} % | "
              f"{100 * r['interior_valid']:.1f} % |", flush=True)
    if not args.skip_closed:
        print("\n| closed cloud | points marked border (all false) | seconds |")
        print("|---|---|---|")
        for name, make in closed_clouds():
            cloud = make()
            t0 = time.perf_counter()
            marked = int(border_points(cloud).sum())
            print(f"| {name} | {marked} | {time.perf_counter() - t0:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
