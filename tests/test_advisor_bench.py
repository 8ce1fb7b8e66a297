"""The table-level bound of the advisor's benchmark (``benchmarks/bench_advisor.py --twin-bound``)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np


def _bench():
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_advisor.py"
    spec = importlib.util.spec_from_file_location("bench_advisor_under_test", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_twin_regret_pairs_each_mesh_with_the_other_surfaces_of_its_setting_only():
    bench = _bench()
    # three random surfaces (samples 0-2) at one setting with crossed winners, and two at another
    # density that both want call x by far: a pairing across settings would change every number
    keys = [[0, "quadratic", 817, 8.0, 0.2, 0], [0, "quadratic", 817, 8.0, 0.2, 1],
            [0, "quadratic", 817, 8.0, 0.2, 2], [0, "quadratic", 1801, 8.0, 0.2, 0],
            [0, "quadratic", 1801, 8.0, 0.2, 1]]
    #                 x     y
    erel = np.array([[0.10, 0.20],    # A: x wins
                     [0.30, 0.14],    # B: y wins by 2.1
                     [0.12, 0.13],    # C: x wins narrowly
                     [0.01, 1.00],
                     [0.02, 0.50]])
    tw = bench.twin_regrets(keys, np.log(erel))
    pairs = {(int(i), round(float(r), 6)) for i, r in zip(tw["pair_mesh"], tw["pair_regret"])}
    # A given B's best call (y): 0.2 / 0.1; given C's (x): 1
    assert sorted(r for i, r in pairs if i == 0) == [1.0, 2.0]
    assert len(tw["pair_mesh"]) == 3 * 2 + 2 * 1
    # pooled twins (geometric mean of their errors): A's x 0.3 * 0.12 = 0.036 > y 0.14 * 0.13: y, 0.2 / 0.1;
    # B's x 0.1 * 0.12 < y 0.2 * 0.13: x; C's x 0.1 * 0.3 = 0.03 > y 0.2 * 0.14 = 0.028: y
    np.testing.assert_allclose(tw["pooled"][:3], [2.0, 0.3 / 0.14, 0.13 / 0.12])
    # with the mesh itself: x 0.1 * 0.3 * 0.12 = 0.0036 < y 0.2 * 0.14 * 0.13 = 0.00364 for all three
    np.testing.assert_allclose(tw["in_sample"][:3], [1.0, 0.3 / 0.14, 1.0])
    np.testing.assert_allclose(tw["pooled"][3:], [1.0, 1.0])


def test_twin_regret_chooses_among_the_calls_the_mesh_has():
    bench = _bench()
    keys = [[0, "torus", 642, 0.0, 0.0, 0], [0, "torus", 642, 0.0, 0.0, 1]]
    log_values = np.log(np.array([[np.nan, 0.2, 0.1], [0.01, 0.05, 0.5]]))
    tw = bench.twin_regrets(keys, log_values)
    # mesh 0 lacks the twin's best call 0: it gets the best of those it has (call 1: 0.2 / 0.1); mesh 1
    # gets call 2, mesh 0's best (0.5 / 0.01)
    np.testing.assert_allclose(tw["pair_regret"], [2.0, 50.0])
    np.testing.assert_allclose(tw["pooled"], [2.0, 50.0])
