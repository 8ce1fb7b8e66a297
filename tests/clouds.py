"""Point clouds shared by the point-cloud tests, sampled from curv.surfaces."""

from __future__ import annotations

import numpy as np

import curv
from curv.core.ranges import point_spacing
from curv.surfaces import Sphere, sample_points


def noisy_sphere_cloud():
    """4000 blue-noise points of a sphere of radius 2 with Gaussian noise of 0.02 (about 0.12
    spacings) and the exact normals: ``(cloud, median spacing)``."""
    s = sample_points(Sphere(2.0), 4000, sampling="blue", rng=5)
    rng = np.random.default_rng(1)
    points = s.cloud.points + rng.normal(scale=0.02, size=s.cloud.points.shape)
    cloud = curv.PointCloud(points, normals=s.truth.normals)
    return cloud, float(np.median(point_spacing(cloud)))
