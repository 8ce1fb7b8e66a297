"""The range rule: parsing, validation, continuous ranges and absolute radii (curv.core.ranges)."""

import numpy as np
import pytest

import curv
from curv.geometry.neighbourhood import supports
from curv.core.ranges import Range, ball_radii, parse_range, range_label, resolve
from tests.meshes import icosphere, torus_grid, tube

SUPPORTED = [name for name, spec in curv.ESTIMATORS.items() if spec.has_support]
RADIUS_WEIGHTED = {"csm", "icc", "an"}
"""Estimators whose result depends on the ball radius, not only on which vertices are in it."""
FIXED = [name for name, spec in curv.ESTIMATORS.items() if not spec.has_support]


@pytest.mark.parametrize("text, k", [(2, 2.0), ("2", 2.0), ("R2", 2.0), ("r3", 3.0), (2.5, 2.5), ("R2.5", 2.5),
                                     (np.float64(1.25), 1.25), (np.int64(4), 4.0)])
def test_parse_range_accepts_numbers_and_labels(text, k):
    assert parse_range(text) == k


@pytest.mark.parametrize("bad", ["R", "two", "", None, True, float("nan"), float("inf"), [2]])
def test_parse_range_rejects_the_rest_naming_the_forms(bad):
    with pytest.raises(curv.EstimatorError, match="a number k >= 1 such as 2 or 2.5, a label such as 'R2'"):
        parse_range(bad)


def test_labels_and_values():
    assert range_label(2) == "R2" and range_label(2.0) == "R2" and range_label(2.5) == "R2.5"
    assert Range(k=2.0).value == 2 and isinstance(Range(k=2.0).value, int)
    assert Range(k=2.5).value == 2.5 and Range(radius=0.3).value is None
    assert Range(radius=0.3).label == "r=0.3"


def test_default_range_is_r2_or_the_only_one():
    assert resolve(curv.ESTIMATORS["mru"]).k == 2
    assert resolve(curv.ESTIMATORS["meyer"]).k == 1


def test_range_and_radius_are_exclusive():
    with pytest.raises(curv.EstimatorError, match="either range= or radius="):
        resolve(curv.ESTIMATORS["qs"], 2, 0.3)


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), "x", True])
def test_radius_must_be_a_positive_length(bad):
    with pytest.raises(curv.EstimatorError, match="radius must be a positive length"):
        resolve(curv.ESTIMATORS["qs"], radius=bad)


@pytest.mark.parametrize("method", FIXED)
def test_fixed_ring_estimators_take_no_radius_and_no_other_range(method):
    spec = curv.ESTIMATORS[method]
    with pytest.raises(curv.EstimatorError, match="takes no radius"):
        resolve(spec, radius=0.5)
    with pytest.raises(curv.EstimatorError, match="fixed 1-ring"):
        resolve(spec, spec.ranges[0] + 0.5)


def test_support_radius_rule():
    m = icosphere(2)
    L = m.longest_edge
    np.testing.assert_allclose(ball_radii(m, Range(k=3), uses_normals=False), 3 * L, rtol=2e-9)
    np.testing.assert_allclose(ball_radii(m, Range(k=3), uses_normals=True), 2 * L, rtol=2e-9)
    np.testing.assert_allclose(ball_radii(m, Range(radius=0.4), uses_normals=True), 0.4, rtol=2e-9)


@pytest.mark.parametrize("method", SUPPORTED)
def test_radius_equals_range_times_edge_on_a_regular_mesh(method):
    # every vertex of a regular tube has a congruent 1-ring: the same longest edge L
    m = tube(24, 30)
    L = float(np.median(m.longest_edge))
    spec = curv.ESTIMATORS[method]
    k = 3
    factor = k - 1 if spec.uses_normals else k
    by_range = curv.estimate(m, method, k)
    by_radius = curv.estimate(m, method, radius=factor * L)
    interior = by_range.valid & np.isclose(m.longest_edge, L, rtol=1e-12)
    assert interior.sum() > 0.5 * m.n_vertices
    np.testing.assert_allclose(by_radius.k1[interior], by_range.k1[interior], atol=1e-12)
    np.testing.assert_allclose(by_radius.k2[interior], by_range.k2[interior], atol=1e-12)
    assert by_radius.range is None and by_radius.info["radius"] == pytest.approx(factor * L)


@pytest.mark.parametrize("method", SUPPORTED)
def test_results_change_continuously_with_the_range(method):
    """Between R2 and R2.01 only the vertices whose support gained a vertex change."""
    m = torus_grid(40, 20)[0]
    spec = curv.ESTIMATORS[method]
    k0 = max(2.0, min(spec.ranges))
    a = curv.estimate(m, method, k0)
    b = curv.estimate(m, method, k0 + 0.01)
    ra = ball_radii(m, Range(k=k0), uses_normals=spec.uses_normals)
    rb = ball_radii(m, Range(k=k0 + 0.01), uses_normals=spec.uses_normals)
    pa, _ = supports(m, ra)
    pb, _ = supports(m, rb)
    same_support = np.diff(pa) == np.diff(pb)
    assert same_support.sum() > 0.5 * m.n_vertices
    both = same_support & a.valid & b.valid
    if spec.name in RADIUS_WEIGHTED:
        # the radius itself enters these (clipping to the ball; an's balance of heights and
        # slopes): a 0.5 % larger ball moves the values a little, not a jump
        np.testing.assert_allclose(b.k1[both], a.k1[both], rtol=0.02, atol=1e-3)
    else:
        np.testing.assert_allclose(b.k1[both], a.k1[both], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(b.k2[both], a.k2[both], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("method", SUPPORTED)
def test_real_range_is_accepted_and_labelled(method):
    m = icosphere(3)
    res = curv.estimate(m, method, 2.5)
    assert res.range == 2.5 and res.info["range_label"] == "R2.5"
    assert res.valid.mean() > 0.9
    np.testing.assert_allclose(res.k1[res.valid], 1.0, atol=0.1)


def test_range_owner_helpers_follow_the_registry():
    from curv.estimators import ESTIMATORS, refusal, polygon_estimators
    from curv import Mesh
    from curv.core import ranges

    mru, meyer, an = ESTIMATORS["mru"], ESTIMATORS["meyer"], ESTIMATORS["an"]
    assert ranges.default_range(mru) == 2 and ranges.default_range(meyer) == 1
    assert ranges.nearest_allowed(an, 1) == 2 and ranges.nearest_allowed(an, 2.5) == 2.5
    assert ranges.nearest_allowed(meyer, 3) == 1
    assert ranges.allowed_paper_ranges(an) == (2, 3, 4) and ranges.allowed_paper_ranges(meyer) == (1,)
    assert "fixed 1-ring" in ranges.describe_ranges(meyer) and "radius" in ranges.describe_ranges(mru)
    assert isinstance(ranges.canonical_k(2.0), int) and ranges.canonical_k(2.5) == 2.5
    quad = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    assert refusal(mru, quad) is None
    msg = refusal(meyer, quad)
    assert "triangle" in msg and "jet" in msg and all(n in msg for n in polygon_estimators())
