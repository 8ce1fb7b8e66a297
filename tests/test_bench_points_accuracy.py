"""The point-cloud accuracy benchmark's conversions: APSS's values turned into curvlab's quantities,
and the evaluated points kept away from the patch border."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import points_accuracy  # noqa: E402


def _sphere(n, rng):
    p = rng.normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1)[:, None]


@pytest.mark.parametrize("radius", [0.5, 2.0])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_apss_conversion_gives_k_equal_one_over_r_on_a_sphere(radius, sign):
    pytest.importorskip("pymeshlab")
    p = _sphere(3000, np.random.default_rng(1))
    k1, k2, h, k = points_accuracy.apss_curvature(radius * p, sign * p)
    # outward normals: k1 = k2 = +1/r (curvlab's convention); inward: -1/r; K = 1/r^2 either way
    np.testing.assert_allclose(np.median(h), sign / radius, rtol=1e-3)
    np.testing.assert_allclose(np.median(k), 1.0 / radius**2, rtol=1e-3)
    np.testing.assert_allclose(np.median(k1), sign / radius, rtol=2e-2)
    np.testing.assert_allclose(np.median(k2), sign / radius, rtol=2e-2)
    assert np.all(k1 >= k2)


def test_apss_gets_only_the_points_with_a_normal():
    """A NaN normal zeroes every APSS fit whose ball holds it; the points without one are left out
    and get NaN, the others keep 1/r."""
    pytest.importorskip("pymeshlab")
    p = _sphere(3000, np.random.default_rng(5))
    normals = p.copy()
    normals[::300] = np.nan
    k1, k2, h, k = points_accuracy.apss_curvature(2.0 * p, normals, 12.0)
    lost = np.isnan(normals[:, 0])
    assert np.isnan(h[lost]).all() and np.isnan(k1[lost]).all()
    np.testing.assert_allclose(h[~lost], 0.5, rtol=1e-2)
    np.testing.assert_allclose(k[~lost], 0.25, rtol=2e-2)


def test_apss_conversion_separates_the_principal_curvatures_of_a_cylinder():
    pytest.importorskip("pymeshlab")
    rng = np.random.default_rng(2)
    t, z = rng.uniform(0.0, 2.0 * np.pi, 8000), rng.uniform(-4.0, 4.0, 8000)
    radius = 0.5
    v = np.column_stack([radius * np.cos(t), radius * np.sin(t), z])
    n = np.column_stack([np.cos(t), np.sin(t), np.zeros_like(t)])
    k1, k2, h, _ = points_accuracy.apss_curvature(v, n)
    mid = np.abs(z) < 2.0
    # "Mean" is k1 + k2, so H is half of it: 1 / (2r) on a cylinder, not 1 / r
    np.testing.assert_allclose(np.median(h[mid]), 0.5 / radius, rtol=2e-2)
    np.testing.assert_allclose(np.median(k1[mid]), 1.0 / radius, rtol=5e-2)
    assert abs(np.median(k2[mid])) < 0.1 / radius


def test_evaluated_points_stay_beyond_r4_of_the_border():
    import curv
    from curv.point_normals import border_points
    from curv.core.ranges import ball_radii, resolve
    from curv.surfaces import sample_points

    surface = curv.surfaces.SURFACES["quadratic"].random(np.random.default_rng(3))
    cloud = sample_points(surface, 1500, sampling="blue", rng=4).cloud
    ev = points_accuracy.evaluated_points(cloud)
    border = border_points(cloud)
    radii = ball_radii(cloud, resolve(curv.ESTIMATORS["qs"], 4), uses_normals=False)
    d = np.linalg.norm(cloud.points[:, None, :] - cloud.points[None, border, :], axis=2).min(axis=1)
    np.testing.assert_array_equal(ev, d > radii)
    assert 0 < ev.sum() < cloud.n_points - border.sum()
