"""A local Dask cluster that cannot finish a tiled run ends it in one line, never waits forever: its
workers all gone, a tile past its worker's memory limit every time; the pages of a mapped file do
not count against that limit (curv.tiles.driver)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from curv.tiles.driver import Runner, TileFailed  # noqa: E402

WORKER_BYTES = 300 * 2**20


def hold_memory(tile: int, nbytes: int, seconds: float) -> int:
    """A tile task that holds ``nbytes`` of its own memory for ``seconds``."""
    block = np.ones(nbytes // 8)
    time.sleep(seconds)
    return int(block.size) + tile


def read_mapped(tile: int, path: str, seconds: float) -> float:
    """A tile task that reads every page of a memory-mapped file and keeps it mapped for ``seconds``."""
    mapped = np.memmap(path, dtype=np.float64, mode="r")
    total = float(mapped.sum())
    time.sleep(seconds)
    return total + tile


def run_in_thread(gen, seconds: float, meanwhile=None):
    """Consume ``gen`` in a thread for at most ``seconds`` (calling ``meanwhile()`` here once it
    started): (results, error, still running)."""
    out = {"results": [], "error": None}

    def consume():
        try:
            for result, _ in gen:
                out["results"].append(result)
        except BaseException as exc:  # noqa: BLE001 - handed to the test
            out["error"] = exc

    thread = threading.Thread(target=consume, daemon=True)
    thread.start()
    if meanwhile is not None:
        meanwhile()
    thread.join(seconds)
    return out["results"], out["error"], thread.is_alive()


def test_a_local_cluster_left_without_workers_ends_the_run_in_one_line():
    with Runner(workers=2, worker_bytes=WORKER_BYTES) as runner:
        gen = runner.iter_run(time.sleep, [(30,), (30,)], keys=["curv-tile-ab12-0", "curv-tile-ab12-1"])
        runner._cluster.scale(0)  # every worker gone, none coming back: the run used to wait forever
        t0 = time.monotonic()
        results, error, waiting = run_in_thread(gen, 60)
        assert not waiting, "the run waited for workers that will never come"
        assert isinstance(error, TileFailed) and time.monotonic() - t0 < 30
        text = str(error)
        assert text.startswith("tile 0: the local cluster has no worker left") and "\n" not in text


def test_a_tile_past_its_workers_memory_limit_every_time_ends_the_run_naming_it_and_the_limit():
    with Runner(workers=2, worker_bytes=WORKER_BYTES) as runner:
        tasks = [(0, 10 * 2**20, 0.0), (1, 2 * WORKER_BYTES, 4.0)]
        gen = runner.iter_run(hold_memory, tasks, keys=["curv-tile-cd34-0", "curv-tile-cd34-1"])
        results, error, waiting = run_in_thread(gen, 120)
        assert not waiting
        assert isinstance(error, TileFailed), error
        text = str(error)
        assert text.startswith("tile 1: its worker went past its memory limit") and "limit 300.0 MiB" in text
        assert "--memory" in text and "--tile-size" in text and "\n" not in text


def test_a_local_worker_killed_once_mid_tile_gives_a_retry_and_every_result():
    import os
    import signal

    with Runner(workers=2, worker_bytes=WORKER_BYTES) as runner:
        tasks = [(0, 2**20, 3.0), (1, 2**20, 3.0)]
        gen = runner.iter_run(hold_memory, tasks, keys=["curv-tile-gh78-0", "curv-tile-gh78-1"])
        killed = []

        def kill_one_busy_worker():
            t0 = time.monotonic()
            while time.monotonic() - t0 < 30:
                busy = [address for address, keys in runner.client.processing().items() if keys]
                if busy:
                    nanny = next(n for n in runner._cluster.workers.values() if n.worker_address == busy[0])
                    time.sleep(1.0)  # mid-tile
                    os.kill(nanny.process.pid, signal.SIGKILL)
                    killed.append(busy[0])
                    return
                time.sleep(0.1)

        results, error, waiting = run_in_thread(gen, 120, kill_one_busy_worker)
        assert killed
    assert not waiting and error is None, error
    assert sorted(results) == [2**17, 2**17 + 1]


def test_the_pages_of_a_mapped_file_do_not_count_against_a_workers_limit(tmp_path):
    """A worker that reads a mapped file larger than its limit holds those pages in its resident
    size (Dask's nanny stopped it at 95 % of the limit, four times, then failed the tile); they are
    the page cache's, not the worker's."""
    path = tmp_path / "big.f8"
    np.full(WORKER_BYTES // 8 + 2**20, 0.5).tofile(path)
    with Runner(workers=2, worker_bytes=WORKER_BYTES) as runner:
        gen = runner.iter_run(read_mapped, [(0, str(path), 3.0)], keys=["curv-tile-ef56-0"])
        results, error, waiting = run_in_thread(gen, 120)
    assert not waiting and error is None, error
    assert results == [0.5 * (WORKER_BYTES // 8 + 2**20)]


def test_an_input_in_memory_tiled_on_a_cluster_equals_the_plain_tiled_call():
    """``estimate_tiled(client=...)`` runs its tiles through the same watched runner."""
    import curv
    from curv.tiles import estimate_tiled

    from meshes import torus_grid

    mesh = torus_grid(60, 30)[0]
    plain = estimate_tiled(mesh, "mru", 2, tile_size=600)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  env={"CURV_THREADS": "1"}) as cluster, distributed.Client(cluster) as client:
        tiled = estimate_tiled(mesh, "mru", 2, tile_size=600, client=client)
    assert tiled.info["tiles"] >= 3 and np.array_equal(tiled.reason, plain.reason)
    for name in ("k1", "k2", "d1", "d2", "normals"):
        assert np.array_equal(getattr(tiled, name), getattr(plain, name), equal_nan=True), name
    assert np.array_equal(plain.k1, curv.estimate(mesh, "mru", 2).k1, equal_nan=True)
