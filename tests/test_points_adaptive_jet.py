"""The jet's adaptive width (``width="adaptive"``): the choice rule, and what it buys on known cases."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.core.errors import EstimatorError
from curv.estimators.jet_width import GAMMA, WIDTH_FRACTIONS, WIDTHS, ici_choice
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


def test_the_walk_keeps_the_last_candidate_whose_intervals_meet_all_before_it():
    se = np.full((4, 5), 0.1)
    k1 = np.array([[1.0, 1.0, 1.0, 1.0, np.nan],
                   [1.1, 1.1, 1.0, 1.0, np.nan],
                   [1.2, 2.0, 1.0, 1.0, np.nan],   # point 1: out of the intersection here
                   [1.45, 1.0, 1.0, 9.0, np.nan]])  # point 0: 1.45 - 0.2 > 1.0 + 0.2; point 3: out
    k2 = np.zeros((4, 5))
    k2[1, 2] = 5.0  # point 2: k2 leaves at the second candidate
    choice, mid1, mid2 = ici_choice(k1, k2, se, se, gamma=2.0)
    assert choice.tolist() == [2, 1, 0, 2, -1]
    # the estimate is the midpoint of the final intersection: point 0 keeps [1.0, 1.2] for k1
    np.testing.assert_allclose(mid1[:4], [1.1, 1.05, 1.0, 1.0])
    np.testing.assert_allclose(mid2[:4], 0.0, atol=1e-15)
    assert np.isnan(mid1[4]) and np.isnan(mid2[4])
    assert 2.0 <= GAMMA <= 3.0


def test_an_unfitted_candidate_is_skipped_not_a_stop():
    se = np.full((3, 2), 0.1)
    k1 = np.array([[1.0, np.nan], [np.nan, np.nan], [1.05, 1.0]])
    k2 = np.zeros((3, 2))
    se_missing = se.copy()
    se_missing[0, 1] = np.nan
    assert ici_choice(k1, k2, se_missing, se)[0].tolist() == [2, 2]


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


def test_on_a_noisy_sphere_the_walk_goes_on_to_the_steadiest_fit(noisy_sphere):
    """A sphere has no term a degree-2 fit misses at 4 spacings that noise (0.12 spacings) does not
    hide: the degree-2 smooth fit over the whole ball is chosen at most points (86 % on this sample),
    and the median H is that fit's (within 0.1 % of 1/r) where the fixed degree-4 jet is 2.7 % high."""
    cloud, spacing = noisy_sphere
    adaptive = curv.estimate(cloud, "jet", radius=4 * spacing, degree=4, width="adaptive")
    last = curv.estimate(cloud, "jet", radius=4 * spacing, degree=2, weights="smooth")
    fixed = curv.estimate(cloud, "jet", radius=4 * spacing, degree=4)
    assert adaptive.valid.mean() > 0.99
    assert np.mean(np.abs(adaptive.k1 - last.k1) < 0.25 * np.nanstd(last.k1)) > 0.75
    assert abs(np.nanmedian(adaptive.mean) - 0.5) < 0.2 * abs(np.nanmedian(fixed.mean) - 0.5)
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
    """The default mesh jet is untouched by the option; the adaptive one runs on a mesh too."""
    mesh = icosphere(3, 1.0)
    default = curv.estimate(mesh, "jet", 3, degree=4)
    fixed = curv.estimate(mesh, "jet", 3, degree=4, width="fixed")
    assert np.array_equal(default.k1, fixed.k1) and np.array_equal(default.d1, fixed.d1)
    adaptive = curv.estimate(mesh, "jet", 3, degree=4, width="adaptive")
    assert adaptive.valid.all()
    np.testing.assert_allclose(adaptive.mean, 1.0, rtol=2e-2)
