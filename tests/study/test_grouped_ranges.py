"""A task estimates each estimator's plain ranges in one call: its rows equal one call per variant."""

from __future__ import annotations

import numpy as np
import pytest

from curv.study.metrics import METRIC_COLUMNS


@pytest.mark.parametrize("noise", [0.0, 1.0])
def test_task_rows_equal_one_call_per_variant(tiny_settings, noise):
    import curv
    from curv.geometry.normals import cached_max_normals
    from curv.study.metrics import summarize
    from curv.study.tasks import run_task
    from curv.study.testmesh import build_test_mesh

    settings = tiny_settings.with_(estimators=("csm:R1,R2,R3,R4", "icc:R4,R2", "qs:R1,R2", "an:R2,R4", "meyer:R1"),
                                   noise=(noise,))
    task = next(iter(settings.tasks()))
    variants = settings.variants_for(task)
    rows = run_task(task, variants)
    tm = build_test_mesh(task)
    normals = cached_max_normals(tm.mesh)
    region = np.flatnonzero(tm.evaluated)
    assert [r["variant"] for r in rows] == [v.id for v in variants] and len(rows) == 11
    for v, row in zip(variants, rows):
        # the study's old path: one estimate per variant, with the standard errors
        alone = curv.estimate(tm.mesh, v.method, v.range, normals=normals, vertices=region)
        assert not row["error"]
        for name, value in summarize(tm.truth, alone, tm.evaluated).items():
            if curv.ESTIMATORS[v.method].takes_levels and isinstance(value, float):
                # their ranges share one walk (csm, icc; the fits without standard errors): the
                # sums are added in another order
                assert np.isclose(row[name], value, rtol=1e-9, atol=1e-12, equal_nan=True), (v.id, name)
            else:
                assert row[name] == value or (np.isnan(row[name]) and np.isnan(value)), (v.id, name)
        assert row["seconds"] > 0.0


def test_a_failing_group_gives_each_row_its_error(tiny_settings, monkeypatch):
    from curv.study import tasks

    settings = tiny_settings.with_(estimators=("csm:R1,R2",))
    task = next(iter(settings.tasks()))

    def fails(*args, **kwargs):
        raise RuntimeError("broken\nestimator")

    monkeypatch.setattr("curv.api.estimate_table", fails)
    monkeypatch.setattr("curv.api.estimate", fails)
    rows = tasks.run_task(task, settings.variants_for(task))
    assert [r["error"] for r in rows] == ["RuntimeError: broken estimator"] * 2
    assert all(np.isnan(r[name]) for r in rows for name in ("rms_erel", "median_erel", "rms_h"))
