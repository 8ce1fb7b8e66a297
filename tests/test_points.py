"""Curvature on point clouds: sign and scale, convergence, invariance, borders, refusals, normals, regions."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

import curv
from curv.core.errors import EstimatorError, MeshError
from curv.estimators import ESTIMATORS, point_estimators, refusal
from curv.point_normals import GRAZING_COSINE, point_normals
from curv.core.ranges import point_spacing
from curv.surfaces import Cylinder, Ellipsoid, QuadraticPatch, Sphere, Torus, sample_points

POINT_METHODS = ["nc", "qs", "an", "mru", "jet"]


@pytest.fixture(scope="module")
def sphere2():
    """2,000... uniform random points of a sphere of radius 2 (k1 = k2 = 0.5 outward)."""
    return sample_points(Sphere(2.0), 4000, rng=11)


def test_the_registry_names_the_point_estimators():
    assert point_estimators() == POINT_METHODS
    assert sorted(set(ESTIMATORS) - set(point_estimators())) == ["csm", "icc", "meyer", "ru"]


@pytest.mark.parametrize("method", POINT_METHODS)
def test_sign_and_scale_with_estimated_normals(sphere2, method):
    res = curv.estimate(sphere2.cloud, method, 2)
    # a few random spots leave a normal fit one-sided (curv.point_normals.ONE_SIDED_GAP): not trusted
    assert res.valid.mean() > 0.99
    assert (res.k1[res.valid] >= res.k2[res.valid]).all()
    np.testing.assert_allclose(np.median(res.mean[res.valid]), 0.5, rtol=0.01)
    np.testing.assert_allclose(np.median(res.gaussian[res.valid]), 0.25, rtol=0.02)
    # the default for a cloud that is not georeferenced turns the top of each part up: on a sphere that is outward
    assert (np.einsum("ij,ij->i", res.normals[res.valid], sphere2.cloud.points[res.valid]) > 0).all()
    assert res.info["normals"] == "jet R2" and res.info["points"]


@pytest.mark.parametrize("method", POINT_METHODS)
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_sign_follows_the_given_normals(sphere2, method, side):
    cloud = curv.PointCloud(sphere2.cloud.points, normals=side * sphere2.truth.normals)
    res = curv.estimate(cloud, method, 2)
    assert res.info["normals"] == "file"
    np.testing.assert_allclose(np.median(res.mean[res.valid]), side * 0.5, rtol=0.01)


def test_viewpoint_inside_gives_inward_normals_and_negative_curvature(sphere2):
    res = curv.estimate(sphere2.cloud, "qs", 2, orient=(0.0, 0.0, 0.0))
    np.testing.assert_allclose(np.median(res.mean[res.valid]), -0.5, rtol=0.01)


def _interior_error(sampled, method, margin):
    res = curv.estimate(sampled.cloud, method, 2)
    xy = np.hypot(sampled.cloud.points[:, 0], sampled.cloud.points[:, 1])
    inner = res.valid & (xy < margin)
    t = sampled.truth
    err = (np.abs(res.k1 - t.k1) + np.abs(res.k2 - t.k2))[inner]
    return np.sqrt(np.mean(err ** 2))


@pytest.mark.parametrize("method", ["qs", "jet", "mru"])
def test_error_shrinks_with_density(method):
    patch = QuadraticPatch(A=1.0, B=0.3, C=0.5, D=0.0, E=-0.5)
    coarse = _interior_error(sample_points(patch, 1500, sampling="blue", rng=3), method, 0.5)
    fine = _interior_error(sample_points(patch, 12000, sampling="blue", rng=3), method, 0.5)
    assert fine < coarse / 2.0


def test_rigid_motion_and_scale_invariance(sphere2):
    base = sample_points(Torus(), 5000, rng=4, with_normals=True)
    rot = Rotation.from_euler("xyz", [0.3, -1.1, 2.0]).as_matrix()
    for method in POINT_METHODS:
        ref = curv.estimate(base.cloud, method, 2)
        for scale in (1.0, 1e3):
            moved = curv.PointCloud(scale * base.cloud.points @ rot.T + [5.0, -2.0, 7.0],
                                    normals=base.cloud.normals @ rot.T)
            res = curv.estimate(moved, method, 2)
            assert np.array_equal(res.valid, ref.valid), method
            np.testing.assert_allclose(scale * res.k1, ref.k1, rtol=1e-6, atol=1e-9)
            np.testing.assert_allclose(scale * res.k2, ref.k2, rtol=1e-6, atol=1e-9)
            # directions turn with the cloud (up to sign)
            dots = np.abs(np.einsum("ij,ij->i", res.d1[res.valid], ref.d1[res.valid] @ rot.T))
            assert np.median(dots) > 1 - 1e-9


def test_border_of_an_open_patch():
    sampled = sample_points(QuadraticPatch(), 6000, rng=5)
    cloud = sampled.cloud
    res = curv.estimate(cloud, "jet", 2)
    border = res.reason == curv.Reason.BORDER
    hull = ConvexHull(cloud.points[:, :2]).vertices
    assert border[hull].all()
    # far inside (4 spacings from the hexagon's edge at apothem sqrt(3)/2): almost never
    apothem = np.sqrt(3) / 2
    angles = np.arctan2(cloud.points[:, 1], cloud.points[:, 0])
    r = np.hypot(cloud.points[:, 0], cloud.points[:, 1])
    # distance to the hexagon edge: apothem minus the projection on the nearest edge normal
    sector = np.round(angles / (np.pi / 3) - 0.5) * (np.pi / 3) + np.pi / 6
    to_edge = apothem - r * np.cos(angles - sector)
    deep = to_edge > 4 * np.median(point_spacing(cloud))
    assert border[deep].mean() < 0.002
    assert res.info["border_points"] == border.sum()


def test_closed_blue_noise_sphere_has_no_border():
    res = curv.estimate(sample_points(Sphere(), 4000, sampling="blue", rng=6).cloud, "qs", 2)
    assert not (res.reason == curv.Reason.BORDER).any()


def test_closed_uniform_random_torus_has_no_border():
    """A point whose six nearest sit in a clump has a small spacing of its own; the border test's
    ball takes its neighbours' spacing there (curv.point_normals.border_radii), or the clump alone
    reads as a rim (7 of these 20,000 points with the point's own spacing)."""
    from curv.point_normals import border_points

    cloud = sample_points(Torus(1.0, 0.4), 20000, rng=5).cloud
    assert not border_points(cloud).any()



def test_closed_uniform_random_spheroid_has_no_border_and_few_one_sided_normals():
    """Uniform random points leave random angular gaps: a support of n points leaves one wider than
    150 degrees with probability about n (1 - 150/360)^(n - 1) (18 % at 8 points, 3 % at 12), so
    the clumps' small R2 supports read as one-sided (126 of these 20,000 points, median support 11
    where the whole cloud's is 23), while the border test's larger ball sees no rim."""
    from curv.point_normals import border_points

    cloud = sample_points(Ellipsoid(1.0, 1.0, 0.6), 20000, rng=7).cloud
    assert not border_points(cloud).any()
    normals = point_normals(cloud)
    assert not normals.border.any()
    assert 0 < normals.one_sided.sum() < 0.01 * cloud.n_points

@pytest.mark.parametrize("method", ["meyer", "csm", "ru", "icc"])
def test_face_based_estimators_refuse_points(sphere2, method):
    with pytest.raises(MeshError, match="point clouds; use one of: nc, qs, an, mru, jet"):
        curv.estimate(sphere2.cloud, method)
    assert "nc, qs, an, mru, jet" in refusal(ESTIMATORS[method], sphere2.cloud)
    assert refusal(ESTIMATORS["qs"], sphere2.cloud) is None


def test_options_that_need_faces_or_points_refuse(sphere2):
    with pytest.raises(EstimatorError, match="point cloud takes neither"):
        curv.estimate(sphere2.cloud, "qs", features=30)
    with pytest.raises(EstimatorError, match="point cloud takes neither"):
        curv.estimate(sphere2.cloud, "qs", smooth="values")
    mesh = Sphere().mesh(642).mesh
    with pytest.raises(EstimatorError, match="knn= is for point clouds"):
        curv.estimate(mesh, "qs", knn=10)
    for bad in (2, 0, 3.5, True):
        with pytest.raises(EstimatorError, match="knn must be"):
            curv.estimate(sphere2.cloud, "qs", knn=bad)
    with pytest.raises(EstimatorError, match="knn=20 needs more than 20 points; the cloud has 12"):
        curv.estimate(curv.PointCloud(sphere2.cloud.points[:12]), "qs", knn=20)
    with pytest.raises(EstimatorError, match="one of range=, radius= or knn="):
        curv.estimate(sphere2.cloud, "qs", range=2, knn=10)


def test_knn_radius_and_range_agree_on_an_even_sample(sphere2):
    spacing = float(np.median(point_spacing(sphere2.cloud)))
    by_range = curv.estimate(sphere2.cloud, "jet", 2)
    by_radius = curv.estimate(sphere2.cloud, "jet", radius=2 * spacing)
    by_knn = curv.estimate(sphere2.cloud, "jet", knn=24)
    for res, label in ((by_range, "R2"), (by_radius, f"r={2 * spacing:g}"), (by_knn, "knn=24")):
        assert res.info["range_label"] == label
        np.testing.assert_allclose(np.median(res.mean[res.valid]), 0.5, rtol=0.01)


def test_an_and_mru_keep_the_k_minus_one_rule_on_points(sphere2):
    from curv.core.ranges import Range, ball_radii

    spacing = point_spacing(sphere2.cloud)
    radii = ball_radii(sphere2.cloud, Range(k=3), uses_normals=True)
    np.testing.assert_allclose(radii, 2 * spacing, rtol=1e-8)


@pytest.mark.parametrize("surface", [Sphere(), Torus(), Cylinder()], ids=["sphere", "torus", "cylinder"])
@pytest.mark.parametrize("orient", ["top", "outward"])
def test_orientation_is_consistent_and_outward(surface, orient):
    sampled = sample_points(surface, 5000, sampling="blue", rng=8)
    est = point_normals(sampled.cloud, orient=orient)
    ok = ~est.ambiguous & np.isfinite(est.normals).all(axis=1)
    assert ok.mean() > 0.995
    cos = np.einsum("ij,ij->i", est.normals[ok], sampled.truth.normals[ok])
    if isinstance(surface, Cylinder) and orient == "top":
        cos = np.abs(cos)  # an open tube's top point has a horizontal normal: either side is "up"
        assert (np.sign(np.einsum("ij,ij->i", est.normals[ok], sampled.truth.normals[ok])) ==
                np.sign(np.einsum("ij,ij->i", est.normals[ok][:1], sampled.truth.normals[ok][:1]))).all()
    assert (cos > 0.95).all()


def test_edge_on_points_towards_a_viewpoint_are_ambiguous(sphere2):
    view = np.array([100.0, 0.0, 0.0])
    res = curv.estimate(sphere2.cloud, "qs", 2, orient=view)
    est = point_normals(sphere2.cloud, orient=view)
    assert est.ambiguous.any()
    assert (res.reason[est.ambiguous] == curv.Reason.ORIENTATION).all()
    assert np.isnan(res.normals[est.ambiguous]).all() and np.isnan(res.k1[est.ambiguous]).all()
    pts = sphere2.cloud.points
    ray = (view - pts) / np.linalg.norm(view - pts, axis=1, keepdims=True)
    # every other point with a trusted normal faces the viewpoint
    seen = ~est.ambiguous & ~est.one_sided
    assert (np.einsum("ij,ij->i", est.normals[seen], ray[seen]) > 0).all()
    assert res.info["ambiguous_normals"] == est.ambiguous.sum()


def test_a_clean_closed_sample_has_no_ambiguous_normals(sphere2):
    assert not point_normals(sphere2.cloud).ambiguous.any()


@pytest.mark.parametrize("method", POINT_METHODS)
def test_region_equals_full_run_on_points(sphere2, method):
    idx = np.sort(np.random.default_rng(9).choice(sphere2.cloud.n_points, 50, replace=False))
    full = curv.estimate(sphere2.cloud, method, 2)
    part = curv.estimate(sphere2.cloud, method, 2, vertices=idx)
    for name in ("k1", "k2", "d1", "d2", "reason", "valid"):
        assert np.array_equal(getattr(full, name)[idx], getattr(part, name)[idx], equal_nan=True), name
    rest = np.setdiff1d(np.arange(sphere2.cloud.n_points), idx)
    assert (part.reason[rest] == curv.Reason.NOT_COMPUTED).all()


def test_coincident_points_are_degenerate_and_isolated_ones_too():
    pts = sample_points(Sphere(), 2000, rng=10).cloud.points
    cloud = curv.PointCloud(np.vstack([pts, pts[:7]]))
    res = curv.estimate(cloud, "mru", 2)
    assert (res.reason[2000:] == curv.Reason.DEGENERATE).all()
    assert res.info["coincident_points"] == 7
    # 19 points without a normal (one-sided) and 3 whose neighbours with normals lie along a curve
    assert res.valid[:2000].mean() > 0.985
    lone = curv.estimate(curv.PointCloud([[0.0, 0.0, 0.0]], normals=[[0.0, 0.0, 1.0]]), "qs", 2)
    assert lone.reason[0] == curv.Reason.DEGENERATE and np.isnan(lone.k1[0])


ROWS_MISSES = {
    # an's R2 support (the (k-1) rule: about 7 points) is imprecise on any irregular sample, not a
    # made-up value: its 99th percentile is 0.091 on uniform random points of the same patch too
    "an": "99th percentile |H error| 0.149 against max |H| 0.56 (0.091 on uniform random points)",
    # nc's one equation per neighbour weights the few far rows' normal curvatures like the near row's
    "nc": "99th percentile |H error| 0.43 against max |H| 0.56 (one-sided normals left out)",
}


@pytest.mark.parametrize("method", [pytest.param(m, marks=[pytest.mark.xfail(strict=True, reason=ROWS_MISSES[m])]
                                                 if m in ROWS_MISSES else []) for m in POINT_METHODS])
def test_scan_rows_give_no_made_up_values(method):
    sampled = sample_points(QuadraticPatch(), 4000, sampling="rows", ratio=4, rng=12)
    res = curv.estimate(sampled.cloud, method, 2)
    t = sampled.truth
    err = np.abs(res.mean - t.mean)[res.valid]
    assert res.valid.sum() > 200
    # what is valid is an estimate: within 10 % of the largest |H| of the patch
    assert np.percentile(err, 99) < 0.1 * np.abs(t.mean).max()


def test_a_one_sided_normal_support_is_singular_not_a_number():
    """On scan rows, points whose normal fit sees one side only have no normal and no estimate."""
    sampled = sample_points(QuadraticPatch(), 4000, sampling="rows", ratio=4, rng=12)
    res = curv.estimate(sampled.cloud, "qs", 2)
    one_sided = res.info["one_sided_normals"]
    assert one_sided > 0
    singular = (res.reason == curv.Reason.SINGULAR) & np.isnan(res.normals).any(axis=1)
    assert singular.sum() >= one_sided - res.info["border_points"]
    # the same rule leaves a uniform random sphere almost whole
    sphere = curv.estimate(sample_points(Sphere(), 3000, rng=1).cloud, "qs", 2)
    assert sphere.info["one_sided_normals"] < 0.01 * 3000
    assert sphere.valid.mean() > 0.99


def test_samplings_lie_on_the_surface_with_their_truth():
    s = sample_points(Sphere(1.5), 3000, sampling="blue", rng=1)
    np.testing.assert_allclose(np.linalg.norm(s.cloud.points, axis=1), 1.5)
    np.testing.assert_allclose(s.truth.k1, 1 / 1.5)
    from scipy.spatial import cKDTree

    d, _ = cKDTree(s.cloud.points).query(s.cloud.points, 2)
    assert d[:, 1].min() >= s.info["min_distance"] * (1 - 1e-12)
    assert abs(s.cloud.n_points - 3000) < 300
    rows = sample_points(QuadraticPatch(), 3000, sampling="rows", ratio=5, rng=2)
    ys = np.unique(np.round(rows.cloud.points[:, 1] / rows.info["row_gap"], 9))
    np.testing.assert_allclose(ys, np.round(ys))
    with pytest.raises(ValueError, match="rows"):
        sample_points(Sphere(), 1000, sampling="rows")
    noisy = sample_points(Sphere(), 3000, noise=0.5, rng=3)
    assert noisy.info["noise_sigma"] == pytest.approx(0.5 * noisy.info["spacing"])
    assert np.abs(np.linalg.norm(noisy.cloud.points, axis=1) - 1).max() > 0.1 * noisy.info["spacing"]


def test_a_surface_is_sampled_by_name_too_and_a_bad_one_refused_by_name():
    by_name = sample_points("sphere", 1000, rng=5)
    by_object = sample_points(Sphere(), 1000, rng=5)
    np.testing.assert_array_equal(by_name.cloud.points, by_object.cloud.points)
    with pytest.raises(ValueError, match="unknown surface 'spere'; choose one of sphere"):
        sample_points("spere", 1000)
    with pytest.raises(ValueError, match=r"^Box .*cannot be sampled as points"):
        sample_points("box", 1000)


@pytest.mark.parametrize("method", ["qs", "jet"])
def test_whole_cloud_in_grid_order_equals_the_points_in_their_own_order(method):
    """A whole cloud is estimated in its grid's cell order (for the cache); every row stays its own point's."""
    cloud = sample_points(Sphere(), 3000, rng=4).cloud
    whole = curv.estimate(cloud, method, 2)
    listed = curv.estimate(cloud, method, 2, vertices=np.arange(cloud.n_points))
    for name in ("k1", "k2", "d1", "d2", "reason"):
        assert np.array_equal(getattr(whole, name), getattr(listed, name), equal_nan=True), name
    assert whole.valid.mean() > 0.99


@pytest.mark.parametrize("sampling", ["uniform", "rows"])
def test_a_cloud_in_any_order_gives_each_point_its_own_estimate(sampling):
    """The estimate runs on the cloud's twin in grid order and maps the rows back: the same points
    in another order get the same decisions and, row for row, the same values (to rounding)."""
    kwargs = {"ratio": 4} if sampling == "rows" else {}
    cloud = sample_points(QuadraticPatch(), 3000, sampling=sampling, rng=6, **kwargs).cloud
    perm = np.random.default_rng(1).permutation(cloud.n_points)
    shuffled = curv.PointCloud(cloud.points[perm])
    for method in ("qs", "mru"):
        a, b = curv.estimate(cloud, method, 2), curv.estimate(shuffled, method, 2)
        assert np.array_equal(a.reason[perm], b.reason), method
        assert 200 < b.valid.sum() < b.n
        np.testing.assert_allclose(b.k1, a.k1[perm], rtol=0, atol=1e-6 * np.nanmax(np.abs(a.k1)))
        np.testing.assert_allclose(b.normals, a.normals[perm], rtol=0, atol=1e-6)
        assert {k: a.info[k] for k in ("border_points", "ambiguous_normals")} == \
               {k: b.info[k] for k in ("border_points", "ambiguous_normals")}
    # given normals follow their points: turned inward, k1 and k2 swap and change sign
    a = curv.estimate(cloud, "qs", 2)
    c = curv.estimate(shuffled, "qs", 2, normals=-a.normals[perm])
    ok = c.valid & a.valid[perm]
    assert ok.sum() > 200
    np.testing.assert_allclose(c.k2[ok], -a.k1[perm][ok], rtol=0, atol=1e-6 * np.nanmax(np.abs(a.k1)))
    np.testing.assert_allclose(c.k1[ok], -a.k2[perm][ok], rtol=0, atol=1e-6 * np.nanmax(np.abs(a.k1)))
