"""Coordinates stored on a coarse grid: no fit over a few grid steps is marked valid, the normals
are fitted over enough of them, and the summary says so (laspy's ``plane.laz``; planes and spheres
rounded in code, whose curvature is known)."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.cli import main
from curv.core.ranges import point_spacing
from curv.point_normals import MIN_SUPPORT_STEPS, range_above_grid, support_floor
from curv.surfaces import Sphere, sample_points
from tests.laspy_samples import laspy_sample


def _plane(step, n=20000, seed=0):
    """A tilted plane z = 0.1 x + 0.05 y over [0, 2]², its coordinates rounded to ``step``."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 2, (n, 2))
    points = np.column_stack([xy, 0.1 * xy[:, 0] + 0.05 * xy[:, 1]])
    return curv.PointCloud(np.round(points / step) * step, georeferenced=True)


@pytest.fixture(scope="module")
def sphere():
    """A unit sphere (H = 1 outward), 20,000 points (spacing about 0.035), rounded to 0.01."""
    s = sample_points(Sphere(1.0), 20000, sampling="blue", rng=3)
    return curv.PointCloud(np.round(s.cloud.points / 0.01) * 0.01)


def test_the_grid_step_is_found():
    assert _plane(0.01).coordinate_step == pytest.approx(0.01)
    assert _plane(0.025).coordinate_step == pytest.approx(0.025)
    exact = sample_points(Sphere(1.0), 5000, rng=1).cloud
    assert exact.coordinate_step < 1e-4 * np.median(point_spacing(exact))


def test_a_quantised_plane_has_no_absurd_valid_value():
    cloud = _plane(0.01)  # spacing about 0.016: R2 is 3 grid steps
    floor = support_floor(cloud)
    assert floor == pytest.approx(MIN_SUPPORT_STEPS * 0.01)
    for method in ("qs", "jet", "mru"):
        narrow = curv.estimate(cloud, method, 2)
        assert not narrow.valid.any()
        assert narrow.info["quantised_supports"] == cloud.n_points
        k = range_above_grid(cloud, uses_normals=method == "mru")
        wide = curv.estimate(cloud, method, k)
        assert wide.valid.mean() > 0.7  # coincident (rounded together) and rim points aside
        # the grid's error stays far below 1 / r, the largest curvature a support can hold (truth 0)
        assert np.abs(wide.mean[wide.valid]).max() < 0.5 / floor
    assert narrow.info["widened_normals"] == cloud.n_points


def test_a_quantised_sphere_is_right_where_valid(sphere):
    floor = support_floor(sphere)
    assert floor == pytest.approx(0.1)
    narrow = curv.estimate(sphere, "qs", 2)  # r = 0.07 < 10 steps at most points
    wide_enough = 2 * point_spacing(sphere) * (1 + 1e-9) >= floor
    assert not narrow.valid[~wide_enough].any() and narrow.valid.mean() < 0.05
    for method in ("qs", "jet"):
        res = curv.estimate(sphere, method, 4)
        ok = res.valid
        assert ok.mean() > 0.95
        err = np.abs(res.mean[ok] - 1.0)
        # the grid's error in H is about q / r² in the median (0.45 here), at most about 10 x that
        grid_error = 0.01 / (4 * np.median(point_spacing(sphere))) ** 2
        assert np.median(err) < grid_error and err.max() < 10 * grid_error


def test_a_cloud_of_full_precision_is_untouched():
    cloud = sample_points(Sphere(1.0), 5000, rng=2).cloud
    res = curv.estimate(cloud, "qs", 2)
    assert res.info["quantised_supports"] == 0 and res.info["widened_normals"] == 0


def test_plane_laz_is_marked_at_r2_and_right_at_a_wide_range(capsys):
    cloud = curv.load(laspy_sample("plane.laz"))  # a real 2 m plane: 1 cm grid, spacing 1-1.4 cm
    assert cloud.coordinate_step == pytest.approx(0.01)
    for method in ("qs", "jet", "mru"):
        res = curv.estimate(cloud, method, 2)
        assert not res.valid.any()  # before: qs |H| up to 1.1e5 on valid points, jet 7.1e4, mru 3.6e3
        wide = curv.estimate(cloud, method, 12)
        assert wide.valid.mean() > 0.6
        assert np.abs(wide.mean[wide.valid]).max() < 3.0
    code = main(["estimate", str(laspy_sample("plane.laz")), "-m", "qs", "-q"])
    text = capsys.readouterr().out
    assert code == 0
    assert "coordinates stored on a grid of step 0.01: a fit narrower than 0.1 (10 steps) sees its stairs" in text
    assert "28,185 estimates over narrower supports are SINGULAR (no estimate there): try -r 10 or more" in text
