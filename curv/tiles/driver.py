"""Where the tiles run: in this process, on a local Dask cluster, or on an existing one.

* **This process** (one worker): the kernels use every core (``CURV_THREADS``).
* **A local cluster** (the default for more than one worker): Dask's ``LocalCluster`` of worker
  processes, one thread each, each kernel single-threaded (``CURV_THREADS=1``), each worker's
  memory limited to its share of the budget (:mod:`curv.tiles.budget`): a worker that exceeds it is
  restarted by its nanny and its tile run again.
* **An existing cluster**: a scheduler's address (``tcp://host:8786``) or a
  ``distributed.Client``; its workers must see the run's scratch folder and the input
  (docs/LARGE_SCANS.md).

A failed tile is retried (:data:`RETRIES` times, then the run stops with that tile's error in one
line); a tile already finished is not submitted again; an interrupt cancels what is running and
shuts a local cluster down. Nothing here writes the output: the caller does, once every tile is
finished.
"""

from __future__ import annotations

import logging
import os
import time
from typing import Callable, Generator, Sequence

from ..core.errors import CurvError
from ..core.jit import forwarded

__all__ = ["Runner", "RETRIES", "TileFailed", "QUIET_CLUSTER"]

RETRIES = 2
"""Times a failed tile is run again (besides the restarts of a killed worker, which Dask counts)."""


QUIET_CLUSTER = {"distributed.admin.tick.interval": "1s", "distributed.worker.memory.monitor-interval": "1s",
                 "distributed.admin.system-monitor.interval": "2s"}
"""Dask settings of a local cluster: its event loops' health tick and its memory and system monitors
polled once a second instead of every 20-500 ms (measured: an idle cluster of two workers used 3.0 CPU
seconds in 30 s with Dask's defaults, 1.8 with these)."""


class TileFailed(CurvError, RuntimeError):
    """A tile kept failing: the message names it and its error in one line (the command prints it
    as it is: ``curv.core.errors.CurvError``'s one-line form)."""


class Runner:
    """Runs tile tasks (module notes); a context manager that releases a cluster it started.

    Parameters
    ----------
    workers : int
        Processes at once (1: this process, no cluster).
    worker_bytes : int
        A local cluster's memory limit per worker.
    scheduler : str, optional
        An existing cluster's scheduler address.
    client : distributed.Client, optional
        An existing client (used as it is, never closed here).
    """

    def __init__(self, *, workers: int = 1, worker_bytes: int | None = None, scheduler: str | None = None,
                 client=None):
        self.client = client
        self.worker_bytes = worker_bytes
        self._own_client = None
        self._cluster = None
        self.workers = workers
        if client is None and (scheduler is not None or workers > 1):
            try:
                from distributed import Client, LocalCluster
            except ImportError:
                from ..core.errors import CurvError

                raise CurvError("running tiles on several processes needs Dask's distributed "
                                "(pip install 'curvlab[study]')") from None
            if scheduler is not None:
                self._own_client = Client(scheduler, timeout=30)
            else:
                # one kernel thread through CURV_THREADS (curv.core.jit.launch), not NUMBA_NUM_THREADS:
                # numba stops every kernel once that variable reads differently after its threads
                # started, and a worker of a 10M-point run saw it do so mid-run (cause not found)
                env = {"CURV_THREADS": "1", "OMP_NUM_THREADS": "1"}
                if os.environ.get("NUMBA_CACHE_DIR"):
                    env["NUMBA_CACHE_DIR"] = os.environ["NUMBA_CACHE_DIR"]
                import dask

                # a tile runs for seconds to minutes: Dask's 20 ms ticks and 0.1 s memory polls only
                # cost CPU (10 % of a core for an idle cluster of two; 6 % with these)
                with dask.config.set(QUIET_CLUSTER):
                    self._cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                                 memory_limit=worker_bytes or "auto", dashboard_address=None,
                                                 silence_logs=logging.ERROR, env=env)
                self._own_client = Client(self._cluster)
            self.client = self._own_client

    @property
    def where(self) -> str:
        """In words: ``this process``, ``a local cluster of 2 workers`` or ``the cluster at ADDRESS``."""
        if self.client is None:
            return "this process"
        if self._cluster is not None:
            return f"a local cluster of {self.workers} worker processes"
        return f"the cluster at {self.client.scheduler.address}"

    def iter_run(self, function: Callable, tasks: Sequence[tuple], *, keys: Sequence[str],
                 steps: Callable | None = None) -> Generator:
        """Run ``function(*args)`` for each of ``tasks``; yields ``(result, None)`` as each finishes (in
        any order) and, in this process, ``(None, fraction)`` of the running task between (when
        ``steps``, the generator form of ``function``, is given: a stop takes effect there). ``keys``
        name the tasks on a cluster (unique per run and tile)."""
        if self.client is None:
            for args in tasks:
                if steps is None:
                    yield self._retrying(function, args), None
                else:
                    yield (yield from self._stepping(steps, function, args)), None
            return
        from distributed import as_completed

        futures = [self.client.submit(function, *args, key=key, retries=RETRIES, pure=False)
                   for args, key in zip(tasks, keys)]
        try:
            for future in as_completed(futures):
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001 - one line naming the tile
                    raise TileFailed(self._failure(future.key, exc)) from None
                yield result, None
        finally:
            pending = [f for f in futures if not f.done()]
            if pending:
                self.client.cancel(pending)

    @staticmethod
    def _stepping(steps, function, args):
        """``steps(*args)`` to its end, yielding ``(None, fraction)``; a failure is retried once
        through ``function`` as :meth:`_retrying` does (the steps of a failed try are not repeated)."""
        from ..core.errors import CurvError

        gen = steps(*args)
        try:
            return (yield from forwarded(gen, lambda step: (None, float(step))))
        except (CurvError, OSError):
            raise
        except Exception:  # noqa: BLE001 - run again, as a cluster would
            return Runner._retrying(function, args)

    @staticmethod
    def _retrying(function, args):
        from ..core.errors import CurvError

        for attempt in range(RETRIES + 1):
            try:
                return function(*args)
            except (CurvError, OSError):  # bad input or a full disk: running it again changes nothing
                raise
            except Exception as exc:  # noqa: BLE001 - as a cluster would, then one line naming it
                if attempt == RETRIES:
                    raise TileFailed(f"tile {args[0]}: {_one_line(exc)}") from None
                time.sleep(0.1)

    def _failure(self, key: str, exc: BaseException) -> str:
        """A cluster's tile failure in one line: a worker that kept dying is named as such (on a
        local cluster its nanny kills it past its memory limit)."""
        tile = str(key).rsplit("-", 1)[-1]
        if type(exc).__name__ == "KilledWorker":
            from ..memory import format_bytes

            limit = (f" (a local cluster's worker is stopped past its memory limit, "
                     f"{format_bytes(self.worker_bytes)})") if self._cluster is not None and self.worker_bytes else ""
            return (f"tile {tile}: every worker that ran it died{limit}; give more --memory, a smaller "
                    f"--tile-size or fewer --workers")
        return f"tile {tile}: {_one_line(exc)}"

    def close(self) -> None:
        if self._own_client is not None:
            self._own_client.close()
            self._own_client = None
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def _one_line(exc: BaseException) -> str:
    from ..core.paths import one_line

    return f"{type(exc).__name__}: {one_line(exc)}"
