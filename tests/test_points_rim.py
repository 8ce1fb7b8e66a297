"""The open-scan rim: points whose support is one-sided are borders; closed clouds keep none."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

import curv
from curv.point_normals import border_points
from curv.surfaces import QuadraticPatch, Sphere, sample_points


def _to_edge(xy):
    hull = ConvexHull(xy)
    return np.min(-(xy @ hull.equations[:, :2].T + hull.equations[:, 2]), axis=1)


def test_the_rim_of_an_open_scan_gets_no_value_and_the_inside_does():
    """8000 uniform random points of an open quadratic patch: within 0.015 of its edge (about 0.6
    of a spacing) 31 % of the points had a qs R2 value before the one-sided test (their support
    lies on one side), 1.7 % now; the inside keeps 97 %."""
    cloud = sample_points(QuadraticPatch(), 8000, rng=5).cloud
    res = curv.estimate(cloud, "qs", 2)
    rim = _to_edge(cloud.points[:, :2]) < 0.015
    assert rim.sum() > 100
    assert res.valid[rim].mean() <= 0.10
    assert res.valid[~rim].mean() >= 0.90
    # what is not valid on the rim says why: the border (on it, or the support reaches it)
    assert (res.reason[rim & ~res.valid] == curv.Reason.BORDER).mean() > 0.95


@pytest.mark.slow
def test_a_large_closed_sphere_gains_no_false_border():
    """200,000 uniform random points of a sphere: the gap test alone marks 7 (clumps and voids of
    random sampling), the one-sided test adds none."""
    assert border_points(sample_points(Sphere(), 200000, rng=3).cloud).sum() <= 7
