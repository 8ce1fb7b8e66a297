"""Kernels under the two kinds of concurrency curvlab has: viewer threads and the study's processes."""

import threading
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import curv
from curv.study.executors import _init_worker, open_executor, stop_executor
from tests.meshes import icosphere, torus_grid

METHODS = ("mru", "qs", "an", "nc")


def _estimate(args):
    vertices, faces, method, k = args
    res = curv.estimate(curv.Mesh(vertices, faces), method, k)
    return res.k1, res.k2, res.reason


@pytest.fixture(scope="module")
def torus():
    return torus_grid(120, 60)[0]


def test_two_threads_estimating_at_once_match_the_serial_results(torus):
    serial = {m: curv.estimate(torus, m, 3) for m in METHODS}
    results, errors = {}, []

    def work(method):
        try:
            for _ in range(3):
                results[method] = curv.estimate(torus, method, 3)
        except BaseException as exc:  # reported below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(m,)) for m in METHODS]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert not any(t.is_alive() for t in threads), "a concurrent estimate deadlocked"
    assert not errors
    for m in METHODS:
        np.testing.assert_array_equal(results[m].k1, serial[m].k1)
        np.testing.assert_array_equal(results[m].reason, serial[m].reason)


def test_forked_pool_after_kernels_ran_in_the_parent(torus):
    mesh = icosphere(3)
    parent = curv.estimate(mesh, "mru", 2)  # parallel kernels have run in this process
    args = [(mesh.vertices, mesh.triangles, "mru", 2)] * 4
    with open_executor(workers=2) as pool:
        assert isinstance(pool, ProcessPoolExecutor)
        out = [f.result(timeout=120) for f in [pool.submit(_estimate, a) for a in args]]
    for k1, k2, reason in out:
        np.testing.assert_array_equal(k1, parent.k1)
        np.testing.assert_array_equal(reason, parent.reason)


def test_fork_while_another_thread_runs_a_kernel(torus):
    """A child forked while the launch lock is held must not inherit it held."""
    stop = threading.Event()

    def busy():
        while not stop.is_set():
            curv.estimate(torus, "an", 4)

    worker = threading.Thread(target=busy)
    worker.start()
    try:
        mesh = icosphere(2)
        pool = ProcessPoolExecutor(max_workers=2, initializer=_init_worker)
        try:
            futures = [pool.submit(_estimate, (mesh.vertices, mesh.triangles, "qs", 2)) for _ in range(4)]
            out = [f.result(timeout=60) for f in futures]
        finally:
            stop_executor(pool, now=True)  # a hung child must fail the test, not hang it
    finally:
        stop.set()
        worker.join(timeout=120)
    expected = curv.estimate(mesh, "qs", 2)
    for k1, _, _ in out:
        np.testing.assert_array_equal(k1, expected.k1)


def test_colouring_on_one_thread_while_another_estimates():
    """The viewer colours on its GUI thread while a worker estimates: neither may take down the process.

    In a child process, because a clash in numba's thread pool aborts the interpreter.
    """
    import subprocess
    import sys
    import textwrap

    code = textwrap.dedent("""
        import threading
        import numpy as np
        import curv
        from curv.colors import apply_table, colour_table
        from tests.meshes import torus_grid

        mesh = torus_grid(300, 150)[0]
        done = threading.Event()
        worker = threading.Thread(target=lambda: ([curv.estimate(mesh, "qs", 3) for _ in range(3)], done.set()))
        worker.start()
        values, table, count = np.random.default_rng(0).normal(size=200_000), colour_table("coolwarm"), 0
        while not done.is_set():
            apply_table(values, (-1.0, 1.0), table, clip_shade=0.6)
            count += 1
        worker.join()
        print("coloured", count)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600,
                         cwd=str(__import__("pathlib").Path(__file__).resolve().parents[1]))
    assert out.returncode == 0, out.stderr[-2000:]
    assert int(out.stdout.split()[-1]) > 0
