"""Orienting a point cloud's estimated normals: "up" point by point (LiDAR), the propagation for
objects, the default per input, on laspy's real aerial scans and on surfaces with exact normals."""

from __future__ import annotations

import numpy as np
import plyfile
import pytest

import curv
from curv.cli import main
from curv.point_normals import GRAZING_COSINE, default_orientation, grid_ordered, point_normals
from curv.surfaces import Sphere, sample_points
from tests.laspy_samples import laspy_sample

SCANS = ["autzen_trim.laz", "vegetation_1_3.las", "simple1_4.las"]


@pytest.fixture(scope="module")
def sphere():
    return sample_points(Sphere(1.0), 6000, sampling="blue", rng=5)


def _check_up(res):
    """Every normal the estimate used is up or NaN, and the NaN ones are marked."""
    finite = np.isfinite(res.normals).all(axis=1)
    assert (res.normals[finite, 2] >= 0.0).all()
    assert (res.normals[res.valid, 2] >= 0.0).all()
    assert not res.valid[~finite].any()
    undecided = res.reason == curv.Reason.ORIENTATION
    assert np.isnan(res.normals[undecided]).all()
    return finite, undecided


@pytest.mark.parametrize("name", SCANS)
def test_real_aerial_scans_are_oriented_up_at_every_point(name):
    cloud = curv.load(laspy_sample(name))
    assert cloud.georeferenced and default_orientation(cloud) == "up"
    res = curv.estimate(cloud, "qs", 2)
    assert res.info["orientation"] == "up"
    finite, undecided = _check_up(res)
    assert finite.mean() > 0.7  # (simple1_4.las is on a 1 m grid at 2.4 m spacing: no estimate at R2)
    # walls and fences: edge-on, or their sides wobble across the horizontal; a few percent at most
    assert 0 < undecided.sum() < 0.2 * cloud.n_points
    # asked for by name on the bare points (not georeferenced): the same normals
    bare = curv.PointCloud(cloud.points)
    assert default_orientation(bare) == "top"
    again = curv.estimate(bare, "qs", 2, orient="up")
    np.testing.assert_array_equal(again.normals, res.normals)
    np.testing.assert_array_equal(again.reason, res.reason)


@pytest.mark.parametrize("method", ["mru", "jet"])
def test_every_estimator_reads_up_normals_on_a_real_scan(method):
    res = curv.estimate(curv.load(laspy_sample("autzen_trim.laz")), method, 2)
    _check_up(res)
    assert res.valid.mean() > 0.9


def test_up_on_a_sphere_is_up_point_by_point(sphere):
    """Up is not outward: the lower half's normals point inside (H = -1 there), and a band
    around the equator, whose normals are horizontal, has no decidable side."""
    est = point_normals(sphere.cloud, orient="up")
    assert est.orient == "up"
    finite = np.isfinite(est.normals).all(axis=1)
    assert (est.normals[finite, 2] >= 0.0).all()
    truth_nz = sphere.truth.normals[:, 2]
    assert est.ambiguous[np.abs(truth_nz) < 0.5 * GRAZING_COSINE].all()
    assert not est.ambiguous[np.abs(truth_nz) > 2.0 * GRAZING_COSINE].any()
    res = curv.estimate(sphere.cloud, "qs", 2, orient="up")
    top, bottom = res.valid & (truth_nz > 0.2), res.valid & (truth_nz < -0.2)
    np.testing.assert_allclose(res.mean[top], 1.0, atol=0.05)
    np.testing.assert_allclose(res.mean[bottom], -1.0, atol=0.05)
    # the default for an object is the propagation from its top: outward everywhere
    default = curv.estimate(sphere.cloud, "qs", 2)
    assert default.info["orientation"] == "top"
    np.testing.assert_allclose(np.median(default.mean[default.valid]), 1.0, atol=0.01)
    assert (default.mean[default.valid & (truth_nz < -0.2)] > 0).all()


def test_a_wall_on_the_ground_is_undecided_and_never_down():
    """An L of ground (z = 0) and a wall (x = 0) with 2 mm of noise: the ground is up, the wall's
    horizontal normals are left undecided rather than given a side."""
    rng = np.random.default_rng(2)
    ground = np.column_stack([rng.uniform(0.1, 2, 6000), rng.uniform(-1, 1, 6000), np.zeros(6000)])
    wall = np.column_stack([np.zeros(6000), rng.uniform(-1, 1, 6000), rng.uniform(0.1, 2, 6000)])
    points = np.vstack([ground, wall]) + rng.normal(scale=0.002, size=(12000, 3))
    res = curv.estimate(curv.PointCloud(points, georeferenced=True), "jet", 2)
    _, undecided = _check_up(res)
    on_ground, on_wall = np.arange(12000) < 6000, np.arange(12000) >= 6000
    inner_ground = on_ground & (points[:, 0] > 0.3) & (np.abs(points[:, 1]) < 0.8)
    assert not undecided[inner_ground].any() and res.valid[inner_ground].mean() > 0.95
    assert (res.normals[inner_ground & res.valid, 2] > 0.8).all()
    assert undecided[on_wall].mean() > 0.9


def test_grid_order_twin_keeps_the_georeferenced_flag():
    cloud = curv.PointCloud(np.random.default_rng(0).normal(size=(500, 3)), georeferenced=True)
    twin = grid_ordered(cloud)[0]
    assert twin.georeferenced and "georeferenced" in repr(cloud)


def test_cli_says_which_orientation_ran(tmp_path, capsys):
    out = tmp_path / "out.ply"
    code = main(["estimate", str(laspy_sample("vegetation_1_3.las")), "-m", "qs", "-q", "-o", str(out)])
    text = capsys.readouterr().out
    assert code == 0 and "oriented up (nz >= 0 at every point)" in text
    v = plyfile.PlyData.read(str(out))["vertex"].data
    names = v.dtype.names
    nz = v["nz"] if "nz" in names else v["normal_z"]
    assert (nz[np.isfinite(nz)] >= 0).all()
    code = main(["estimate", str(laspy_sample("vegetation_1_3.las")), "-m", "qs", "-q", "--orient-normals", "top"])
    assert code == 0 and "oriented by propagation from each part's top, turned up (Hoppe)" in capsys.readouterr().out


def test_up_does_not_read_the_free_sign_of_grazing_normals():
    """A grazing normal's sign is the fit's free choice: flipping every grazing normal changes no
    point's verdict (it once did on simple1_4.las, whose 81 exactly horizontal normals voted on
    their neighbours). Here a steep slope (nz = 0.31, decided) meets a band of horizontal normals."""
    from curv.point_normals.orientation import _orient_up

    rng = np.random.default_rng(5)
    points = np.column_stack([rng.uniform(-1, 1, 4000), rng.uniform(-1, 1, 4000), np.zeros(4000)])
    band = points[:, 0] > 0.0
    normals = np.where(band[:, None], [1.0, 0.0, 0.0], [0.95, 0.0, 0.312])
    cloud = curv.PointCloud(points, georeferenced=True)
    finite = np.ones(4000, bool)
    flipped = normals.copy()
    flipped[band] *= -1.0
    verdicts = [_orient_up(cloud, n.copy(), finite) for n in (normals, flipped)]
    np.testing.assert_array_equal(verdicts[0], verdicts[1])
    assert verdicts[0][band].all() and not verdicts[0][~band].any()
