"""The residual measures that tell model error from noise (curv.advice.residuals)."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.advice.features import RESIDUAL_MEASURES, measure_features, residual_measures
from curv.advice.residuals import fit_residual_spreads
from curv.study.protocol import NOISE_FRACTION, Task
from curv.study.testmesh import build_test_mesh
from curv.surfaces import hexagon_mesh


def _noisy_plane(sigma: float, seed: int = 5) -> curv.Mesh:
    planar = hexagon_mesh(1801, irregularity_deg=10.0, rng=seed)
    z = np.random.default_rng(seed).normal(0.0, sigma, len(planar.xy))
    return curv.Mesh(np.c_[planar.xy, z], planar.triangles)


def test_both_spreads_are_the_noise_on_a_noisy_plane():
    # noise alone: the residual sum of squares over the degrees of freedom left estimates its variance
    # for both fits (dividing by the number of points instead would read the quartic's 25 % low)
    mesh = _noisy_plane(sigma=0.002)
    s2, s4 = fit_residual_spreads(mesh)
    ok = np.isfinite(s2) & np.isfinite(s4)
    assert ok.mean() > 0.9
    assert np.median(s2[ok]) == pytest.approx(0.002, rel=0.1)
    assert np.median(s4[ok]) == pytest.approx(0.002, rel=0.1)
    assert np.median(s4[ok] / s2[ok]) == pytest.approx(1.0, abs=0.1)


def test_the_quartic_leaves_little_of_a_smooth_surfaces_model_error():
    f = measure_features(build_test_mesh(Task(3, "trigonometric", 3169, 8.0, 0.0, 0)).mesh)
    assert f.residual_ratio < 0.01 and f.noise_raw4 < 1e-4


def test_a_noise_free_coarse_irregular_patch_is_told_from_a_noisy_one():
    """The quadric's residual on a coarse, irregularly lifted patch reads as noise (noise_raw); the
    quartic's does not, and the two spreads' ratio says which of the two the residual is."""
    clean = build_test_mesh(Task(4001, "quadratic", 469, 20.0, 0.0, 0)).mesh
    noisy = build_test_mesh(Task(4001, "quadratic", 469, 20.0, 0.3, 0)).mesh
    a, b = measure_features(clean), measure_features(noisy)
    truth = 0.3 * NOISE_FRACTION
    assert b.noise_raw4 == pytest.approx(truth, rel=0.25)  # noise: the quartic's spread is the noise
    assert a.noise_raw4 < 0.1 * truth  # no noise: little left
    assert a.noise_raw4 / b.noise_raw4 < 0.6 * a.noise_raw / b.noise_raw  # sharper than the quadric's measure
    assert a.residual_ratio < 0.2 < 0.5 < b.residual_ratio


def test_residual_measures_are_in_the_raw_measures_and_nan_without_support():
    mesh = _noisy_plane(sigma=0.001)
    f = measure_features(mesh)
    assert all(np.isfinite(getattr(f, k)) for k in RESIDUAL_MEASURES)
    one = curv.Mesh(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.1]]), np.array([[0, 1, 2], [1, 3, 2]]))
    r = residual_measures(one)  # 4 points: no quartic
    assert set(r) == set(RESIDUAL_MEASURES) and all(np.isnan(v) for v in r.values())


def test_spreads_are_measured_on_a_fixed_sample_of_a_larger_mesh():
    mesh = _noisy_plane(sigma=0.002)
    s2, s4 = fit_residual_spreads(mesh, sample=300)
    again = fit_residual_spreads(mesh, sample=300)
    assert s2.shape == (300,) and np.array_equal(s4, again[1], equal_nan=True)
