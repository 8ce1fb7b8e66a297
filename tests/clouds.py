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


def ground_ball_and_roof(seed: int = 1) -> np.ndarray:
    """(20560, 3) points of a scene whose parts a tile cut orients apart: a 100 x 100 ground with a
    12-high hill at x = 80 (the highest point of the ground's part), a ball of radius 4 hovering half
    a spacing above the ground at x = 20 (its neighbours join it to the ground: the highest point of
    the left tile's part, whose tree turns the ground there down) and a flat roof at z = 25 over
    x = 30, apart from everything (its own part). Split in two tiles along x, the left tile's
    ground and ball must be turned over and its roof must not."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0.0, 100.0, size=(20000, 2))
    z = 12.0 * np.exp(-((xy[:, 0] - 80.0) ** 2 + (xy[:, 1] - 50.0) ** 2) / (2 * 12.0 ** 2))
    ball = rng.normal(size=(450, 3))
    ball = np.array([20.0, 50.0, 4.5]) + 4.0 * ball / np.linalg.norm(ball, axis=1, keepdims=True)
    angle, radius = rng.uniform(0.0, 2 * np.pi, 110), 4.0 * np.sqrt(rng.uniform(0.0, 1.0, 110))
    roof = np.column_stack([30.0 + radius * np.cos(angle), 30.0 + radius * np.sin(angle), np.full(110, 25.0)])
    return np.vstack([np.column_stack([xy, z]), ball, roof])
