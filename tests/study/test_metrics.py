"""Error measures of eq. 5.2 on hand-made cases with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from curv import Curvature
from curv.study.metrics import absolute_error, relative_error, summarize


def _curv(k1, k2, valid=None) -> Curvature:
    k1, k2 = np.asarray(k1, float), np.asarray(k2, float)
    n = k1.size
    valid = np.ones(n, bool) if valid is None else np.asarray(valid, bool)
    k1, k2 = np.where(valid, k1, np.nan), np.where(valid, k2, np.nan)
    z = np.zeros((n, 3))
    return Curvature(k1=k1, k2=k2, d1=z, d2=z, normals=z, valid=valid)


def test_errors_of_eq_5_2():
    e_abs = absolute_error([1.0, 2.0], [-1.0, 0.0], np.array([1.5, 1.0]), np.array([-1.0, 0.5]))
    np.testing.assert_allclose(e_abs, [0.5, 1.5])
    e_rel = relative_error([1.0, 2.0], [-1.0, 0.0], np.array([1.5, 1.0]), np.array([-1.0, 0.5]))
    np.testing.assert_allclose(e_rel, [0.25, 0.75])


def test_relative_error_on_flat_truth():
    e = relative_error([0.0, 0.0], [0.0, 0.0], np.array([0.0, 0.1]), np.array([0.0, 0.0]))
    assert e[0] == 0.0 and np.isinf(e[1])


def test_summary_excludes_outliers_and_invalid_vertices():
    truth = _curv([1.0, 1.0, 1.0, 1.0, 1.0], [0.0, 0.0, 0.0, 0.0, 0.0])
    # e_rel: 0.1, 0.3, 2.0 (excluded), invalid, not evaluated
    est = _curv([1.1, 1.3, 3.0, 9.0, 9.0], [0.0, 0.0, 0.0, 0.0, 0.0], valid=[1, 1, 1, 0, 1])
    evaluated = np.array([1, 1, 1, 1, 0], bool)
    s = summarize(truth, est, evaluated)
    assert s["n_evaluated"] == 4
    assert s["n_invalid"] == 1
    assert s["n_kept"] == 2
    assert s["excluded_share"] == pytest.approx(1 / 3)
    assert s["rms_erel"] == pytest.approx(np.sqrt((0.1**2 + 0.3**2) / 2))
    assert s["median_erel"] == pytest.approx(0.3)
    assert s["mean_eabs"] == pytest.approx((0.1 + 0.3 + 2.0) / 3)
    # H errors 0.05, 0.15, 1.0; scale c = 0.5 everywhere
    rms_h = np.sqrt((0.05**2 + 0.15**2 + 1.0**2) / 3)
    assert s["rms_h"] == pytest.approx(rms_h)
    assert s["nrms_h"] == pytest.approx(rms_h / 0.5)
    assert s["rms_k"] == pytest.approx(0.0)  # k2 = 0 exactly: K is exact
    assert s["nrms_k"] == pytest.approx(0.0)


def test_summary_with_no_valid_vertex_is_nan_not_an_error():
    truth = _curv([1.0, 2.0], [0.5, 0.5])
    est = _curv([1.0, 2.0], [0.5, 0.5], valid=[0, 0])
    s = summarize(truth, est, np.ones(2, bool))
    assert s["n_invalid"] == 2 and s["n_kept"] == 0
    assert np.isnan(s["rms_erel"]) and np.isnan(s["median_erel"]) and np.isnan(s["excluded_share"])


def test_exact_estimate_has_zero_error():
    truth = _curv([2.0, 0.5, -1.0], [1.0, -0.5, -3.0])
    s = summarize(truth, truth, np.ones(3, bool))
    assert s["rms_erel"] == 0.0 and s["median_erel"] == 0.0 and s["excluded_share"] == 0.0
    assert s["rms_h"] == 0.0 and s["rms_k"] == 0.0
