"""Where study tasks run: anything with the ``concurrent.futures.Executor`` interface.

- :class:`InlineExecutor`: in this process, one task at a time (tests, debugging, profiling).
- a local :class:`~concurrent.futures.ProcessPoolExecutor` (the default);
- a Dask distributed cluster through ``Client(address).get_executor()`` when a scheduler address
  is given (``tcp://HOST:PORT``); the workers must have curvlab installed.
"""

from __future__ import annotations

import os
import signal
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from typing import Iterator

__all__ = ["InlineExecutor", "open_executor", "parallelism", "stop_executor"]


class InlineExecutor(Executor):
    """Runs each submitted call at once in the calling thread; the returned future is done."""

    def submit(self, fn, /, *args, **kwargs) -> Future:
        future: Future = Future()
        future.set_running_or_notify_cancel()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # handed to the caller through the future, like a pool does
            future.set_exception(exc)
        return future


def _init_worker() -> None:
    """Pool initializer: Ctrl-C is the parent's to handle (it stops the workers itself), and each
    worker runs its kernels on one thread: the pool already keeps every core busy."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ["CURV_THREADS"] = "1"


@contextmanager
def open_executor(*, scheduler=None, workers: int | None = None) -> Iterator[Executor]:
    """An executor for the study, closed on exit.

    Parameters
    ----------
    scheduler : str or dask.distributed cluster, optional
        Dask scheduler address (``tcp://host:8786``) or a cluster object (e.g. ``LocalCluster``).
        ``None`` runs locally.
    workers : int, optional
        Local worker processes; default ``os.cpu_count()``; ``0`` runs in this process.

    Yields
    ------
    concurrent.futures.Executor
    """
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError:  # pragma: no cover - depends on the installed extras
            raise RuntimeError("--scheduler needs dask.distributed: pip install 'curvlab[study]'") from None
        client = Client(scheduler)
        try:
            yield client.get_executor(pure=False)
        finally:
            client.close()
        return
    if workers == 0:
        yield InlineExecutor()
        return
    pool = ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1, initializer=_init_worker)
    try:
        yield pool
    finally:
        stop_executor(pool)


def parallelism(executor: Executor) -> int:
    """How many tasks the executor runs at once (a guess is fine: it sizes the submission window)."""
    if isinstance(executor, InlineExecutor):
        return 1
    if isinstance(executor, ProcessPoolExecutor):
        return executor._max_workers
    client = getattr(executor, "_client", None)
    if client is not None:
        try:
            return max(1, sum(client.nthreads().values()))
        except Exception:  # the cluster may be scaling or unreachable for a moment
            return 4
    return getattr(executor, "_max_workers", 2)


def stop_executor(executor: Executor, *, now: bool = False) -> None:
    """Shut an executor down; with ``now``, also end worker processes that are still busy.

    Only for executors this package created: a pool's worker processes are ours to end.
    """
    if now and isinstance(executor, ProcessPoolExecutor):
        executor.shutdown(wait=False, cancel_futures=True)
        for proc in list((getattr(executor, "_processes", None) or {}).values()):
            if proc.is_alive():
                proc.terminate()
        for proc in list((getattr(executor, "_processes", None) or {}).values()):
            proc.join(timeout=5)
        return
    if isinstance(executor, (ProcessPoolExecutor, InlineExecutor)):
        executor.shutdown(wait=True, cancel_futures=True)
    else:  # e.g. dask's ClientExecutor, whose shutdown has no cancel_futures
        executor.shutdown(wait=True)
