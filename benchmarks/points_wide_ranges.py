"""Diagnostic for the noisy point-cloud cells: curvlab beyond R4 against APSS at wider filter scales.

Run by hand from the repository root (about 5 minutes on a loaded 2-core machine)::

    .venv/bin/python benchmarks/points_wide_ranges.py 2      # 2 surfaces per function and sampling

The clouds are those of ``bench_accuracy.py --points`` at noise 100 % (same surfaces, samplings,
noise and seeds), but the evaluated points are kept farther from the border (no border point
within R8) so that R6-R8 supports stay inside the patch; ``mru`` and ``jet`` at R4, R6, R8 on
normals fitted over R4 and R6, APSS at scales 8, 12, 16. Prints the pooled measures per sampling.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import points_accuracy as pa  # noqa: E402

RANGES = (4, 6, 8)
NORMAL_RANGES = (4, 6)
APSS_SCALES = (8.0, 12.0, 16.0)
EVALUATION_RANGE = 8


def run_cloud(tm, function: str, sample: int, s_index: int, sampling: str) -> dict:
    """``{label: errors}`` of every variant on one noisy cloud of the surface of study mesh ``tm``."""
    from scipy.spatial import cKDTree

    import curv
    from curv.point_normals import border_points, point_normals
    from curv.core.pointcloud import PointCloud
    from curv.core.ranges import ball_radii, resolve
    from curv.surfaces import sample_points

    rng = np.random.default_rng([sample, pa.FUNCTIONS.index(function), s_index, 16])
    sampled = sample_points(tm.sampled.surface, pa.DENSITY, sampling=sampling, rng=rng)
    border = border_points(sampled.cloud)
    radii = ball_radii(sampled.cloud, resolve(curv.ESTIMATORS["qs"], EVALUATION_RANGE), uses_normals=False)
    ev = cKDTree(sampled.cloud.points[border]).query(sampled.cloud.points)[0] > radii
    points = sampled.cloud.points + rng.normal(scale=tm.noise_sigma, size=sampled.cloud.points.shape)
    cloud = PointCloud(points)
    t1, t2 = sampled.truth.k1[ev], sampled.truth.k2[ev]
    base = point_normals(cloud).normals
    out = {}
    for normal_range in NORMAL_RANGES:
        normals = point_normals(cloud, range=normal_range).normals.copy()
        normals[np.einsum("ij,ij->i", normals, base) < 0] *= -1.0
        for method in ("mru", "jet"):
            for k in RANGES:
                res = curv.estimate(cloud, method, k, normals=normals)
                out[f"{method} R{k} + normals R{normal_range}"] = pa._errors(t1, t2, res.k1[ev], res.k2[ev])
    for scale in APSS_SCALES:
        k1, k2, _, _ = pa.apss_curvature(points, base, scale)
        out[f"APSS scale {scale:g}"] = pa._errors(t1, t2, k1[ev], k2[ev])
    return out


def main(samples: int) -> int:
    from curv.study.protocol import Task
    from curv.study.testmesh import build_test_mesh

    pooled: dict = {}
    for function in pa.FUNCTIONS:
        for sample in range(samples):
            tm = build_test_mesh(Task(seed=0, function=function, density=pa.DENSITY, irregularity=0.0,
                                      noise=1.0, sample=sample))
            for s_index, sampling in enumerate(pa.SAMPLINGS):
                for label, e in run_cloud(tm, function, sample, s_index, sampling).items():
                    pooled.setdefault(sampling, {}).setdefault(label, []).append(e)
    for sampling, rows in pooled.items():
        stats = {label: pa.summarise(es) for label, es in rows.items()}
        print(f"{sampling} points, noise 100 %, evaluated: no border point within R{EVALUATION_RANGE}")
        for label in sorted(stats, key=lambda x: stats[x]["median"]):
            s = stats[label]
            print(f"  {label:28s} median {s['median']:.4f} trimmed RMS {s['trimmed_rms']:.4f} "
                  f"invalid {100 * s['invalid']:.1f} % nRMS H {s['nrms_h']:.4f} K {s['nrms_k']:.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(int(sys.argv[1]) if len(sys.argv) > 1 else 2))
