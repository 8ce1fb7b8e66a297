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
    tw = bench.twin_regrets(bench.setting_twins(keys), np.log(erel))
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


def test_twin_regret_admits_the_calls_every_mesh_of_the_setting_has():
    bench = _bench()
    keys = [[0, "torus", 642, 0.0, 0.0, 0], [0, "torus", 642, 0.0, 0.0, 1]]
    log_values = np.log(np.array([[np.nan, 0.2, 0.1], [0.01, 0.05, 0.5]]))
    tw = bench.twin_regrets(bench.setting_twins(keys), log_values)
    # call 0 is missing on mesh 0, so it is out for both (on a held-out mesh every call runs): mesh 0
    # gets call 1 (0.2 / 0.1), mesh 1 call 2 over its best admitted call 1 (0.5 / 0.05, not / 0.01)
    np.testing.assert_allclose(tw["pair_regret"], [2.0, 10.0])
    np.testing.assert_allclose(tw["pooled"], [2.0, 10.0])


def test_noise_draws_change_the_noise_of_the_table_mesh_and_nothing_else():
    from tools.advice_table.extend import evaluated_for_table, table_mesh, variant_errors

    bench = _bench()
    calls = ["nc:R1", "jet:R2"]
    noisy = [0, "quadratic", 331, 8.0, 0.6, 0]
    first, again, other = (bench.noise_draw_errors((noisy, d, calls)) for d in (0, 0, 1))
    assert first == again and all(first[c] != other[c] for c in calls)
    clean = [0, "quadratic", 331, 8.0, 0.0, 0]
    mesh, truth, _ = table_mesh(clean)  # at level 0 every draw is the table's noise-free mesh
    assert bench.noise_draw_errors((clean, 3, calls)) == variant_errors(mesh, truth, evaluated_for_table(mesh), calls)
