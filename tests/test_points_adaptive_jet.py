"""The jet's adaptive width (``width="adaptive"``): the choice rule, and what it buys on known cases."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.core.errors import EstimatorError
from curv.estimators.jet_width import GAMMA, RATIO, WIDTH_FRACTIONS, WIDTHS, ici_walk
from tests.clouds import noisy_sphere_cloud
from tests.meshes import icosphere

HESSIAN = np.array([[1.6, 0.3], [0.3, -0.8]])


def _grid_cloud(height, n=61, step=0.05):
    """A square grid about the origin lifted by ``height(x, y)``, normals +z; the centre's index."""
    t = step * (np.arange(n) - n // 2)
    x, y = (a.ravel() for a in np.meshgrid(t, t))
    points = np.column_stack([x, y, height(x, y)])
    normals = np.zeros_like(points)
    normals[:, 2] = 1.0
    return curv.PointCloud(points, normals=normals), int(np.flatnonzero((x == 0) & (y == 0))[0])


def _error_at(res, c):
    exact = np.sort(-np.linalg.eigvalsh(HESSIAN))[::-1]  # house sign, normal +z
    return abs(res.k1[c] - exact[0]) + abs(res.k2[c] - exact[1])


def test_the_walk_stops_where_the_intersection_shrinks_below_the_ratio_of_the_new_interval():
    """gamma 2, ratio 0.5; columns: A all agree, B the second candidate moves off (plain ICI would go
    on: the intersection is not empty), C an unfitted candidate is skipped, D none fitted, E the
    first sits out (its standard error is NaN) and the walk starts at the second."""
    nan = np.nan
    k = np.array([[1.0, 1.0, 1.0, nan, 5.0],
                  [1.0, 1.3, nan, nan, 1.0],
                  [1.0, 1.0, 1.1, nan, 1.0]])
    se = np.array([[0.2, 0.1, 0.1, 0.1, nan],
                   [0.1, 0.1, 0.1, 0.1, 0.1],
                   [0.05, 0.1, 0.05, 0.1, 0.1]])
    choice, mean = ici_walk(k, se, gamma=2.0, ratio=0.5)
    # B: [0.8, 1.2] then [1.1, 1.5]: the intersection (0.1 wide) is under half the new interval (0.4)
    assert choice.tolist() == [2, 0, 2, -1, 2]
    # the estimate is the inverse-variance mean of the kept candidates: C (1.0 * 100 + 1.1 * 400) / 500
    np.testing.assert_allclose(mean[[0, 1, 2, 4]], [1.0, 1.0, 1.08, 1.0], rtol=1e-14)
    assert np.isnan(mean[3])
    # plain ICI (ratio 0) goes on at B while the intersection is not empty: all three kept
    choice0, mean0 = ici_walk(k, se, gamma=2.0, ratio=0.0)
    assert choice0[1] == 2
    np.testing.assert_allclose(mean0[1], 1.1, rtol=1e-14)
    assert 4.0 <= GAMMA <= 6.0 and 0.7 <= RATIO <= 0.85


def test_a_candidate_outside_the_intersection_ends_the_walk_even_if_a_later_one_agrees():
    se = np.full((3, 2), 0.1)
    k = np.array([[1.0, 1.0], [2.0, 1.05], [1.0, 1.0]])
    choice, mean = ici_walk(k, se, gamma=2.0, ratio=0.5)
    assert choice.tolist() == [0, 2]
    np.testing.assert_allclose(mean, [1.0, (1.0 + 1.05 + 1.0) / 3], rtol=1e-14)


def test_the_adaptive_width_keeps_the_exact_degree_4_fit_where_the_degree_2_fit_is_biased():
    """On a clean quartic height field every degree-4 candidate is exact at the centre and the last
    (degree 2, smooth) is not: its interval (the misfit in its residuals) leaves the walk there."""
    cloud, c = _grid_cloud(lambda x, y: 0.8 * x * x + 0.3 * x * y - 0.4 * y * y + 3 * (x ** 4 + y ** 4)
                           - 2 * x * x * y * y)
    for k in (5, 8):
        adaptive = curv.estimate(cloud, "jet", k, degree=4, width="adaptive")
        last = curv.estimate(cloud, "jet", k, degree=2, weights="smooth")
        assert adaptive.valid[c]
        assert _error_at(adaptive, c) < 1e-9
        assert _error_at(last, c) > 0.2


def test_the_adaptive_width_narrows_the_ball_where_higher_terms_bias_the_wide_fit():
    """A sextic height field: the degree-4 jet over the whole ball carries the x^6, y^6 terms as bias
    (0.45 at R8, 1.4 at R12); the walk stops at a narrower ball: about a tenth of it."""
    cloud, c = _grid_cloud(lambda x, y: 0.8 * x * x + 0.3 * x * y - 0.4 * y * y + 5 * x ** 6 + 3 * y ** 6)
    for k in (8, 12):
        adaptive = curv.estimate(cloud, "jet", k, degree=4, width="adaptive")
        fixed = curv.estimate(cloud, "jet", k, degree=4)
        assert _error_at(adaptive, c) < 0.2 * _error_at(fixed, c)


@pytest.fixture(scope="module")
def noisy_sphere():
    return noisy_sphere_cloud()


def test_on_a_noisy_sphere_the_walks_go_on_to_the_steadiest_fit(noisy_sphere):
    """A sphere has no term a degree-2 fit misses at 4 spacings that noise (0.12 spacings) does not
    hide: both walks reach the degree-2 smooth fit over the whole ball at nearly every point (all on
    this sample), and the estimate, the inverse-variance mean of the candidates, leans on it: k1's
    spread 0.110 against that fit's 0.096 (the fixed degree-4 jet 0.152), no point off it by more
    than 0.12 (2.6 when the narrowest degree-4 fits took part, ``POINTS_PER_UNKNOWN`` 2), median H
    0.9 % high where the fixed degree-4 jet is 2.7 % high."""
    cloud, spacing = noisy_sphere
    adaptive = curv.estimate(cloud, "jet", radius=4 * spacing, degree=4, width="adaptive", standard_errors=True)
    last = curv.estimate(cloud, "jet", radius=4 * spacing, degree=2, weights="smooth", standard_errors=True)
    fixed = curv.estimate(cloud, "jet", radius=4 * spacing, degree=4)
    assert adaptive.valid.mean() > 0.99
    # the standard errors reported are those of each walk's last candidate
    assert np.mean(adaptive.k1_se == last.k1_se) > 0.95 and np.mean(adaptive.k2_se == last.k2_se) > 0.95
    assert np.nanstd(adaptive.k1) < 1.3 * np.nanstd(last.k1) < np.nanstd(fixed.k1)
    assert np.nanmax(np.abs(adaptive.k1 - last.k1)) < 0.5
    assert abs(np.nanmedian(adaptive.mean) - 0.5) < 0.5 * abs(np.nanmedian(fixed.mean) - 0.5)
    assert (adaptive.k1[adaptive.valid] >= adaptive.k2[adaptive.valid]).all()


def test_fixed_is_the_default_and_unknown_widths_are_refused(noisy_sphere):
    cloud, _ = noisy_sphere
    default = curv.estimate(cloud, "jet", 2)
    fixed = curv.estimate(cloud, "jet", 2, width="fixed")
    assert np.array_equal(default.k1, fixed.k1, equal_nan=True)
    assert WIDTHS == ("fixed", "adaptive") and WIDTH_FRACTIONS[-1] == 1.0
    with pytest.raises(EstimatorError, match="width"):
        curv.estimate(cloud, "jet", 2, width="wide")


def test_on_a_mesh_the_option_changes_nothing_unless_asked():
    """The default mesh jet is untouched by the option; the adaptive one runs on a mesh too. Where no
    degree-4 candidate holds POINTS_PER_UNKNOWN points per unknown (R3: about 37 vertices) only the
    degree-2 smooth fit takes part and its values are the estimate."""
    mesh = icosphere(3, 1.0)
    default = curv.estimate(mesh, "jet", 3, degree=4)
    fixed = curv.estimate(mesh, "jet", 3, degree=4, width="fixed")
    assert np.array_equal(default.k1, fixed.k1) and np.array_equal(default.d1, fixed.d1)
    small = curv.estimate(mesh, "jet", 3, degree=4, width="adaptive")
    last = curv.estimate(mesh, "jet", 3, degree=2, weights="smooth")
    assert small.valid.all() and np.array_equal(small.k1, last.k1) and np.array_equal(small.k2, last.k2)
    adaptive = curv.estimate(icosphere(4, 1.0), "jet", 6, degree=4, width="adaptive")
    assert adaptive.valid.all()
    np.testing.assert_allclose(adaptive.mean, 1.0, rtol=5e-3)
