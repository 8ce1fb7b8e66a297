"""Where the wide jet's tails are: the same-footing comparison broken down by function.

Run by hand from the repository root (about 3 minutes)::

    .venv/bin/python benchmarks/points_wide_tails.py 3      # 3 surfaces per function and sampling

The noisy clouds and evaluated points of ``points_wide_ranges.py`` (same seeds, same rule); the
degree-4 jet over a ball of 13 median spacings, with the fixed and the adaptive width
(``width="adaptive"``), against APSS at scale 16. Prints, per sampling and function: the evaluated points, then for each side the trimmed RMS (over e_rel < 1), the median
e_rel and the share with e_rel >= 0.2, on all evaluated points and on the flattest fifth of them
(lowest curvature scale c = (|k1| + |k2|) / 2).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import points_accuracy as pa  # noqa: E402
import points_wide_ranges as pw  # noqa: E402

TAIL = 0.2
"""e_rel at or above which a point counts in the tail."""


def _measures(e: np.ndarray) -> tuple[float, float, float]:
    """Trimmed RMS, median and tail share of one set of e_rel values (NaN dropped)."""
    e = e[np.isfinite(e)]
    kept = e[e < 1.0]
    return float(np.sqrt(np.mean(kept ** 2))), float(np.median(e)), float(np.mean(e >= TAIL))


def run(samples: int) -> dict:
    """``{(sampling, function): [(e_jet, e_adaptive, e_apss, c)]}`` over the noisy clouds."""
    from scipy.spatial import cKDTree

    import curv
    from curv.core.pointcloud import PointCloud
    from curv.core.ranges import ball_radii, resolve
    from curv.metrics import relative_error
    from curv.point_normals import border_points, point_normals
    from curv.study.protocol import Task
    from curv.study.testmesh import build_test_mesh
    from curv.surfaces import sample_points

    out: dict = {}
    for function in pa.FUNCTIONS:
        for sample in range(samples):
            tm = build_test_mesh(Task(seed=0, function=function, density=pa.DENSITY, irregularity=0.0, noise=1.0,
                                      sample=sample))
            for s_index, sampling in enumerate(pa.SAMPLINGS):
                rng = np.random.default_rng([sample, pa.FUNCTIONS.index(function), s_index, 16])
                sampled = sample_points(tm.sampled.surface, pa.DENSITY, sampling=sampling, rng=rng)
                border = border_points(sampled.cloud)
                points = sampled.cloud.points + rng.normal(scale=tm.noise_sigma, size=sampled.cloud.points.shape)
                cloud = PointCloud(points)
                median_spacing = float(np.median(ball_radii(cloud, resolve(curv.ESTIMATORS["jet"], 1),
                                                            uses_normals=False)))
                reach = np.maximum(ball_radii(sampled.cloud, resolve(curv.ESTIMATORS["jet"], pw.REACH),
                                              uses_normals=False), pw.REACH * median_spacing)
                ev = cKDTree(sampled.cloud.points[border]).query(sampled.cloud.points)[0] > reach
                t1, t2 = sampled.truth.k1[ev], sampled.truth.k2[ev]
                normals = point_normals(cloud).normals
                res = curv.estimate(cloud, "jet", radius=pw.REACH * median_spacing, normals=normals, degree=4)
                ada = curv.estimate(cloud, "jet", radius=pw.REACH * median_spacing, normals=normals, degree=4,
                                    width="adaptive")
                k1, k2, _, _ = pa.apss_curvature(points, normals, 16.0)
                out.setdefault((sampling, function), []).append(
                    (relative_error(t1, t2, res.k1[ev], res.k2[ev]), relative_error(t1, t2, ada.k1[ev], ada.k2[ev]),
                     relative_error(t1, t2, k1[ev], k2[ev]), 0.5 * (np.abs(t1) + np.abs(t2))))
    return out


def main(samples: int) -> int:
    for (sampling, function), rows in sorted(run(samples).items()):
        e_jet, e_ada, e_apss, c = (np.concatenate([r[i] for r in rows]) for i in range(4))
        flat = c < np.percentile(c, 20)
        line = [f"{sampling:8s} {function:16s} {e_jet.size:5d} points"]
        for name, e in (("jet degree 4 radius 13", e_jet), ("adaptive", e_ada), ("APSS scale 16", e_apss)):
            rms, med, tail = _measures(e)
            frms, fmed, ftail = _measures(e[flat])
            line.append(f"{name}: RMS {rms:.4f} median {med:.4f} tail {100 * tail:.1f} % "
                        f"(flattest fifth: RMS {frms:.4f} median {fmed:.4f} tail {100 * ftail:.1f} %)")
        print("\n    ".join(line))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(int(sys.argv[1]) if len(sys.argv) > 1 else 3))
