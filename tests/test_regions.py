"""Regions: ``estimate(..., vertices=idx)`` equals the full run at idx, NOT_COMPUTED elsewhere."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.estimators import ESTIMATORS
from creased_meshes import box
from meshes import torus_grid

METHODS = sorted(ESTIMATORS)


@pytest.fixture(scope="module")
def torus():
    return torus_grid(30, 14)[0]


def _region(mesh):
    rng = np.random.default_rng(3)
    return np.sort(rng.choice(mesh.n_vertices, size=37, replace=False))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("features", [None, 30])
def test_region_equals_full_run(torus, method, features):
    mesh = torus if features is None else box(4)
    idx = _region(mesh)
    full = curv.estimate(mesh, method, features=features)
    part = curv.estimate(mesh, method, vertices=idx, features=features)
    for name in ("k1", "k2", "d1", "d2", "reason", "valid"):
        assert np.array_equal(getattr(full, name)[idx], getattr(part, name)[idx], equal_nan=True), name
    rest = np.setdiff1d(np.arange(mesh.n_vertices), idx)
    assert np.all(part.reason[rest] == curv.Reason.NOT_COMPUTED)
    assert np.isnan(part.k1[rest]).all() and np.isnan(part.d1[rest]).all() and not part.valid[rest].any()
    assert part.k1.shape == (mesh.n_vertices,) and part.d1.shape == (mesh.n_vertices, 3)
    assert part.info["region"] == idx.size and full.info["region"] == mesh.n_vertices


@pytest.mark.parametrize("method", ["qs", "mru", "jet"])
def test_region_with_radius_fit_normals_and_chunks(torus, method):
    idx = _region(torus)[::-1]  # any order
    full = curv.estimate(torus, method, radius=0.6, normals="fit")
    part = curv.estimate(torus, method, radius=0.6, normals="fit", vertices=idx, block_size=5)
    assert np.array_equal(full.k1[idx], part.k1[idx], equal_nan=True)


def test_empty_region(torus):
    res = curv.estimate(torus, "qs", vertices=np.zeros(0, np.int64))
    assert np.all(res.reason == curv.Reason.NOT_COMPUTED)


@pytest.mark.parametrize("bad, message", [
    (np.array([0, 10**9]), "out of range"),
    (np.array([-1]), "out of range"),
    (np.array([0.5]), "indices"),
    (np.ones((2, 2), np.int64), "1-D"),
])
def test_bad_regions(torus, bad, message):
    with pytest.raises(curv.EstimatorError, match=message):
        curv.estimate(torus, "qs", vertices=bad)


def test_region_refuses_smoothed_values(torus):
    with pytest.raises(curv.EstimatorError, match="smooth"):
        curv.estimate(torus, "qs", vertices=[0, 1], smooth="values")
