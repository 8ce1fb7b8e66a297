"""The jet's smooth weights (``weights="smooth"``): exactness, sign and scale, invariance, continuity."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import curv
from curv.core.errors import EstimatorError
from curv.estimators.jet import WEIGHTS, smooth_weight
from curv.surfaces import Sphere, Torus, sample_points
from tests.clouds import noisy_sphere_cloud


def _grid_cloud(height, n=21, step=0.05, side=1.0):
    """A square grid symmetric about the origin lifted by ``height(x, y)``, normals ``side * z``.

    The grid's symmetry under (x, y) -> (-x, -y) makes z an exact axis of the (weighted) PCA at the
    origin for an even ``height``, so a jet of enough degree must reproduce the height there exactly.
    """
    t = step * (np.arange(n) - n // 2)
    x, y = (a.ravel() for a in np.meshgrid(t, t))
    points = np.column_stack([x, y, height(x, y)])
    normals = np.zeros_like(points)
    normals[:, 2] = side
    centre = int(np.flatnonzero((x == 0) & (y == 0))[0])
    return curv.PointCloud(points, normals=normals), centre


def test_the_weight_is_one_at_the_centre_and_falls_smoothly_to_zero_at_the_edge():
    assert smooth_weight(0.0, 4.0) == 1.0
    assert smooth_weight(4.0, 4.0) == 0.0 and smooth_weight(5.0, 4.0) == 0.0
    np.testing.assert_allclose(smooth_weight(1.0, 4.0), 0.75 ** 4)
    assert smooth_weight(3.0, 0.0) == 1.0  # r2 <= 0: the uniform fit
    assert WEIGHTS == ("uniform", "smooth")


@pytest.mark.parametrize("side", [1.0, -1.0])
@pytest.mark.parametrize("degree, height, hessian", [
    (2, lambda x, y: 0.8 * x * x + 0.3 * x * y - 0.4 * y * y, [[1.6, 0.3], [0.3, -0.8]]),
    (4, lambda x, y: 0.8 * x * x + 0.3 * x * y - 0.4 * y * y + 0.7 * x ** 4 - 0.5 * x * x * y * y + 0.2 * y ** 3 * x,
     [[1.6, 0.3], [0.3, -0.8]]),
])
def test_smooth_fit_is_exact_on_a_polynomial_height_field(degree, height, hessian, side):
    cloud, c = _grid_cloud(height, side=side)
    res = curv.estimate(cloud, "jet", 5, degree=degree, weights="smooth")
    # the house sign: with the normal along +z the surface bends away from it, so k = -eig(H)
    exact = np.sort(-side * np.linalg.eigvalsh(np.array(hessian)))[::-1]
    assert res.valid[c]
    np.testing.assert_allclose([res.k1[c], res.k2[c]], exact, atol=1e-9)
    assert abs(abs(res.d1[c, 0]) - abs(np.linalg.eigh(np.array(hessian))[1][:, 0 if side > 0 else 1][0])) < 1e-6


@pytest.mark.parametrize("side", [1.0, -1.0])
@pytest.mark.parametrize("radius", [0.5, 2.0])
def test_sphere_sign_and_scale(radius, side):
    s = sample_points(Sphere(radius), 4000, sampling="blue", rng=7)
    cloud = curv.PointCloud(s.cloud.points, normals=side * s.truth.normals)
    res = curv.estimate(cloud, "jet", 2, weights="smooth")
    assert res.valid.all()
    assert (res.k1 >= res.k2).all()
    np.testing.assert_allclose(np.median(res.mean) * radius, side * 1.0, rtol=5e-3)
    np.testing.assert_allclose(np.median(res.gaussian) * radius ** 2, 1.0, rtol=1e-2)


@pytest.mark.parametrize("k", [2, 3, 4])
def test_smooth_weights_halve_the_degree_2_bias_on_a_sphere(k):
    """A degree-2 jet cannot hold a sphere; its bias grows with the ball (0.6 %, 1.5 %, 2.7 % in H at
    R2-R4 on this sample). The smooth weights lean on the nearer points: about half of it."""
    s = sample_points(Sphere(1.0), 4000, sampling="blue", rng=7)
    cloud = curv.PointCloud(s.cloud.points, normals=s.truth.normals)
    bias = {w: np.median(curv.estimate(cloud, "jet", k, weights=w).mean) - 1.0 for w in WEIGHTS}
    assert 0.0 < bias["smooth"] < 0.6 * bias["uniform"]


def test_rigid_motion_and_scale_invariance():
    base = sample_points(Torus(), 5000, rng=4, with_normals=True)
    rot = Rotation.from_euler("xyz", [0.3, -1.1, 2.0]).as_matrix()
    for degree in (2, 4):
        ref = curv.estimate(base.cloud, "jet", 4, degree=degree, weights="smooth")
        for scale in (1.0, 1e3):
            moved = curv.PointCloud(scale * base.cloud.points @ rot.T + [5.0, -2.0, 7.0],
                                    normals=base.cloud.normals @ rot.T)
            res = curv.estimate(moved, "jet", 4, degree=degree, weights="smooth")
            assert np.array_equal(res.valid, ref.valid)
            np.testing.assert_allclose(scale * res.k1, ref.k1, rtol=1e-6, atol=1e-9)
            np.testing.assert_allclose(scale * res.k2, ref.k2, rtol=1e-6, atol=1e-9)
            dots = np.abs(np.einsum("ij,ij->i", res.d1[res.valid], ref.d1[res.valid] @ rot.T))
            assert np.median(dots) > 1 - 1e-9


@pytest.fixture(scope="module")
def noisy_sphere():
    return noisy_sphere_cloud()


@pytest.mark.parametrize("weights, continuous", [("smooth", True), ("uniform", False)])
def test_a_slightly_wider_ball_moves_the_smooth_fit_only_slightly(noisy_sphere, weights, continuous):
    """A point crossing the ball's edge jumps the uniform fit; the smooth weight is 0 there, so it
    cannot. On a noisy sphere (noise 0.12 spacings) a 0.2 % wider ball moves every smooth estimate
    by less than 0.01 (the estimate's own noise is about 0.1), the uniform ones by up to about 0.05."""
    cloud, spacing = noisy_sphere
    a = curv.estimate(cloud, "jet", radius=4 * spacing, weights=weights)
    b = curv.estimate(cloud, "jet", radius=4 * spacing * 1.002, weights=weights)
    jump = np.nanmax(np.abs(a.k1 - b.k1))
    assert (jump < 0.01) == continuous, jump


def test_smooth_weights_take_less_of_the_sphere_s_bias_at_a_given_range(noisy_sphere):
    """At the same ball the smooth fit leans on nearer points: less of the degree-2 jet's bias on a
    sphere (the uniform fit's median H is 1.7 % high at 4 spacings, the smooth one's 0.1 %), more
    noise (about 2.7x the spread): the reason it pays only at wider balls (docs/ACCURACY.md)."""
    cloud, spacing = noisy_sphere
    uniform = curv.estimate(cloud, "jet", radius=4 * spacing)
    smooth = curv.estimate(cloud, "jet", radius=4 * spacing, weights="smooth")
    assert abs(np.nanmedian(smooth.mean) - 0.5) < 0.25 * abs(np.nanmedian(uniform.mean) - 0.5)
    assert np.nanstd(smooth.k1) > 1.5 * np.nanstd(uniform.k1)


def test_uniform_is_the_default_and_unknown_weights_are_refused(noisy_sphere):
    cloud, _ = noisy_sphere
    default = curv.estimate(cloud, "jet", 2)
    uniform = curv.estimate(cloud, "jet", 2, weights="uniform")
    assert np.array_equal(default.k1, uniform.k1, equal_nan=True)
    with pytest.raises(EstimatorError, match="weights"):
        curv.estimate(cloud, "jet", 2, weights="gaussian")
