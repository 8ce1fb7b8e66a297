"""The shared per-corner helpers of meyer and ru (curv.estimators._triangle_corners)."""

from __future__ import annotations

import numpy as np
import pytest

from curv.estimators._triangle_corners import angle_sum, corner_triangle, turn_by_corner


def _sum_by_turns(angles, scales, degenerate):
    re, im, turns = 1.0, 0.0, 0
    for a, s, d in zip(angles, scales, degenerate):
        re, im, turns = turn_by_corner(re, im, turns, s * np.sin(a), s * np.cos(a), d)
    return angle_sum(re, im, turns)


@pytest.mark.parametrize("count", [1, 2, 3, 6, 7, 12, 40, 400])
def test_angle_sum_by_turns_equals_the_sum_of_angles(count):
    rng = np.random.default_rng(count)
    for _ in range(50):
        angles = rng.uniform(0, np.pi, count)
        # corner magnitudes |ab| |ac| from tiny to huge: the product must neither under- nor overflow
        scales = 10.0 ** rng.uniform(-60, 60, count)
        degenerate = rng.random(count) < 0.1
        expected = angles[~degenerate].sum()
        assert abs(_sum_by_turns(angles, scales, degenerate) - expected) <= 1e-12 * max(1.0, expected)


@pytest.mark.parametrize("angles", [[np.pi / 3] * 6, [np.pi / 2] * 4, [np.pi] * 2, [0.0, np.pi, np.pi, 0.0], [np.pi] * 5])
def test_angle_sum_at_exact_turns(angles):
    # whole turns (a flat vertex, a doubled one) land on the right side of 2 pi k, to rounding
    assert abs(_sum_by_turns(np.array(angles), np.ones(len(angles)), np.zeros(len(angles), bool))
               - sum(angles)) < 1e-12


def test_corner_triangle_cotangents_and_mixed_area():
    x = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]])  # right angle at a: cot b = cot c = 1
    out = corner_triangle(x, 0, 1, 2, False)
    twice_area, cos_a, cot_b, cot_c, area = out[11], out[12], out[13], out[14], out[15]
    assert twice_area == 1.0 and cos_a == 0.0 and cot_b == pytest.approx(1.0) and cot_c == pytest.approx(1.0)
    # not obtuse: the Voronoi area (|ab|^2 cot c + |ac|^2 cot b) / 8 = 1/4
    assert area == pytest.approx(0.25)
    # seen from b: angle 45 degrees, triangle not obtuse there; Voronoi area 1/8
    assert corner_triangle(x, 1, 2, 0, False)[15] == pytest.approx(0.125)
    # an obtuse corner at a gets half the area, the others a quarter
    y = np.array([[0.0, 0, 0], [1.0, 0, 0], [-1.0, 0.2, 0]])
    triangle_area = 0.5 * 0.2
    assert corner_triangle(y, 0, 1, 2, False)[15] == pytest.approx(triangle_area / 2)
    assert corner_triangle(y, 1, 2, 0, False)[15] == pytest.approx(triangle_area / 4)
    # a degenerate face gives nothing
    assert corner_triangle(x, 0, 1, 2, True)[13:] == (0.0, 0.0, 0.0)
