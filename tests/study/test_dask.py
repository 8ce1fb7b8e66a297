"""The same tasks on a Dask distributed cluster, through its concurrent.futures executor."""

from __future__ import annotations

import pytest

from curv.study import run

from study_helpers import assert_same_results as _assert_same

distributed = pytest.importorskip("distributed")


def test_dask_cluster_gives_the_same_results(tmp_path, tiny_settings):
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        on_dask = run(tiny_settings, tmp_path / "dask", scheduler=cluster.scheduler_address)
    local = run(tiny_settings, tmp_path / "local", workers=0)
    assert len(on_dask) == tiny_settings.n_tasks * 3
    _assert_same(on_dask, local)
