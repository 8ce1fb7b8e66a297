"""``estimate(..., standard_errors=False)`` (the default): the same curvatures and reasons, no standard errors."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.estimators import ESTIMATORS
from meshes import torus_grid

METHODS = sorted(ESTIMATORS)


@pytest.fixture(scope="module")
def noisy_torus():
    mesh = torus_grid(28, 13)[0]
    rng = np.random.default_rng(5)
    return curv.Mesh(mesh.vertices + rng.normal(scale=0.02, size=mesh.vertices.shape), mesh.faces)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("region", [False, True], ids=["whole", "region"])
def test_values_equal_without_standard_errors(noisy_torus, method, region):
    idx = np.sort(np.random.default_rng(2).choice(noisy_torus.n_vertices, 41, replace=False)) if region else None
    on = curv.estimate(noisy_torus, method, vertices=idx, standard_errors=True)
    off = curv.estimate(noisy_torus, method, vertices=idx, standard_errors=False)
    for name in ("k1", "k2", "d1", "d2", "reason", "valid"):
        assert np.array_equal(getattr(on, name), getattr(off, name), equal_nan=True), name
    assert np.isnan(off.k1_se).all() and np.isnan(off.k2_se).all()
    assert off.k1_se.shape == (noisy_torus.n_vertices,)
    if ESTIMATORS[method].skips_errors or method == "jet":
        # the fits do give them when asked (the switch is not a no-op)
        assert np.isfinite(on.k1_se[on.valid]).any()
    assert "standard_errors" not in off.info


@pytest.mark.parametrize("method", ["an", "mru"])
@pytest.mark.parametrize("noise_model", ["sampled", "independent", "normals"])
def test_noise_model_has_no_effect_without_standard_errors(noisy_torus, method, noise_model):
    ref = curv.estimate(noisy_torus, method, standard_errors=False)
    off = curv.estimate(noisy_torus, method, standard_errors=False, noise_model=noise_model)
    assert np.array_equal(ref.k1, off.k1, equal_nan=True) and np.isnan(off.k1_se).all()
