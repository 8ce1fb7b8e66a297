"""Where the tiles run: in this process, on a local Dask cluster, or on an existing one.

* **This process** (one worker): the kernels use every core (``CURV_THREADS``).
* **A local cluster** (the default for more than one worker): Dask's ``LocalCluster`` of worker
  processes, one thread each, each kernel single-threaded (``CURV_THREADS=1``), each worker's
  memory limited to its share of the budget (:mod:`curv.tiles.budget`).
* **An existing cluster**: a scheduler's address (``tcp://host:8786``) or a
  ``distributed.Client``; its workers must see the run's scratch folder and the input
  (docs/LARGE_SCANS.md).

A failed tile is retried (:data:`RETRIES` times, then the run stops with that tile's error in one
line); a tile already finished is not submitted again; an interrupt cancels what is running and
shuts a local cluster down. Nothing here writes the output: the caller does, once every tile is
finished.

**A run never waits forever.** While tiles run, the driver looks at the cluster every
:data:`WATCH_SECONDS` (and so stops at once on Ctrl-C): the run stops with :class:`TileFailed`
when a local cluster has no worker left or none running for :data:`NO_WORKER_SECONDS` (an existing
cluster: :data:`NO_WORKER_SECONDS_ELSEWHERE`), and when a tile's worker died twice while running it.

**A local worker's memory limit counts its own memory**, its anonymous pages
(:func:`curv.memory.private_bytes`), not its resident size, which also holds the pages of the
memory-mapped input and scratch files: clean page cache, shared and dropped under pressure. Dask's
nanny and worker measure the resident size, so their terminate, pause and spill thresholds are off
on a local cluster (:data:`LOCAL_CLUSTER`; a worker paused past 80 % of its limit by mapped pages
took no more tiles and the run waited forever) and the driver stops a worker past its limit
itself, naming the tile (docs/LARGE_SCANS.md, "When a worker runs out of memory").
"""

from __future__ import annotations

import logging
import os
import signal
import time
from typing import Callable, Generator, Sequence

from ..core.errors import CurvError
from ..core.jit import forwarded

__all__ = ["Runner", "RETRIES", "TileFailed", "QUIET_CLUSTER", "LOCAL_CLUSTER", "WATCH_SECONDS",
           "NO_WORKER_SECONDS", "NO_WORKER_SECONDS_ELSEWHERE"]

RETRIES = 2
"""Times a failed tile is run again (besides the restarts of a killed worker, which Dask counts)."""


QUIET_CLUSTER = {"distributed.admin.tick.interval": "1s", "distributed.worker.memory.monitor-interval": "1s",
                 "distributed.admin.system-monitor.interval": "2s"}
"""Dask settings of a local cluster: its event loops' health tick and its memory and system monitors
polled once a second instead of every 20-500 ms (measured: an idle cluster of two workers used 3.0 CPU
seconds in 30 s with Dask's defaults, 1.8 with these)."""


LOCAL_CLUSTER = {**QUIET_CLUSTER, "distributed.worker.memory.terminate": False,
                 "distributed.worker.memory.pause": False, "distributed.worker.memory.spill": False,
                 "distributed.worker.memory.target": False, "distributed.scheduler.allowed-failures": 1,
                 "distributed.scheduler.worker-saturation": 1.0}
"""Dask settings of a local cluster: the quiet ticks, the memory thresholds on resident size off (the
driver keeps the limit on private memory: module notes), a tile whose worker died twice while
running it failed (a tile past its memory limit once is past it again; one death, as a worker
killed from outside, is still retried), and one tile at a time sent to a worker (Dask's default
sends two to a one-thread worker: a worker stopped past its limit was then charged with both)."""

WATCH_SECONDS = 1.0
"""How often the driver looks at the cluster while tiles run (the workers' memory, the workers left)."""

NO_WORKER_SECONDS = 60.0
"""A local cluster with no worker running this long stops the run (a restart takes a few seconds)."""

NO_WORKER_SECONDS_ELSEWHERE = 600.0
"""The same for an existing cluster, whose launcher may take minutes to replace a worker."""

_LOG = logging.getLogger(__name__)

_ENDED = ("closing", "closed", "closing_gracefully", "failed")


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

                with dask.config.set(LOCAL_CLUSTER):
                    self._cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                                 memory_limit=worker_bytes or "auto", dashboard_address=None,
                                                 silence_logs=logging.ERROR, env=env)
                self._own_client = Client(self._cluster)
            self.client = self._own_client
        self._causes: dict = {}  # task key -> why its worker was stopped (the driver's memory rule)
        self._next_watch = 0.0
        self._idle_since: float | None = None

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
        done = as_completed(futures)
        try:
            while not done.is_empty():
                batch = done.next_batch(block=False)
                for future in batch:
                    try:
                        result = future.result()
                    except Exception as exc:  # noqa: BLE001 - one line naming the tile
                        raise TileFailed(self._failure(future.key, exc)) from None
                    future.release()  # a worker stopped later must not run a finished tile again
                    yield result, None
                if not batch:
                    self._watch(futures)
                    time.sleep(0.1)  # a plain sleep: Ctrl-C stops it at once
        finally:
            pending = [f for f in futures if not f.done()]
            if pending:
                self.client.cancel(pending)

    def _watch(self, futures) -> None:
        """Every :data:`WATCH_SECONDS`: stop a local worker past its memory limit, and raise
        :class:`TileFailed` when no worker is left to run the unfinished ``futures`` (module notes)."""
        now = time.monotonic()
        if now < self._next_watch:
            return
        self._next_watch = now + WATCH_SECONDS
        waiting = next((str(f.key) for f in futures if not f.done()), "")
        if self._cluster is not None:
            self._keep_limits()
            if not [n for n in self._cluster.workers.values() if n.status.name not in _ENDED]:
                raise TileFailed(f"tile {_tile_of(waiting)}: the local cluster has no worker left (its nannies "
                                 f"could not restart them); {_REMEDY}")
        statuses = [w.get("status", "running") for w in self.client.scheduler_info()["workers"].values()]
        if "running" in statuses:
            self._idle_since = None
            return
        if self._idle_since is None:
            self._idle_since = now
        patience = NO_WORKER_SECONDS if self._cluster is not None else NO_WORKER_SECONDS_ELSEWHERE
        if now - self._idle_since > patience:
            state = f"{len(statuses)} workers, none running ({', '.join(sorted(set(statuses)))})" if statuses else "no worker"
            raise TileFailed(f"tile {_tile_of(waiting)}: {self.where} has had {state} for {patience:.0f} s; "
                             f"start workers, or {_REMEDY}")

    def _keep_limits(self) -> None:
        """Stop (SIGKILL) each local worker whose private memory is past its limit; its nanny starts
        another and the scheduler runs its tile again, or fails it after a second death."""
        if not self.worker_bytes:
            return
        from ..memory import format_bytes, private_bytes

        for nanny in list(self._cluster.workers.values()):
            process = getattr(nanny, "process", None)
            pid = getattr(process, "pid", None)
            own = private_bytes(pid) if pid else None
            if own is None or own <= self.worker_bytes:
                continue
            keys = self.client.processing(workers=[nanny.worker_address]).get(nanny.worker_address, [])
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                continue
            for key in keys:
                self._causes[str(key)] = (f"its worker went past its memory limit ({format_bytes(own)} of its own "
                                          f"memory, limit {format_bytes(self.worker_bytes)})")
            _LOG.info("a worker used %s of its own memory, past its limit of %s, while running %s: stopped",
                      format_bytes(own), format_bytes(self.worker_bytes), ", ".join(map(str, keys)) or "no tile")

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
        """A cluster's tile failure in one line: a worker that kept dying is named as such, with the
        cause where the driver stopped it (its memory limit)."""
        tile = _tile_of(key)
        if type(exc).__name__ == "KilledWorker":
            cause = self._causes.get(str(key))
            if cause is None:
                cause = "every worker that ran it died"
                if self._cluster is not None and self.worker_bytes:
                    from ..memory import format_bytes

                    cause += f" (a local worker's memory limit is {format_bytes(self.worker_bytes)})"
            return f"tile {tile}: {cause}; {_REMEDY}"
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


_REMEDY = "give more --memory, a smaller --tile-size or fewer --workers"


def _tile_of(key: str) -> str:
    """The tile number in a task key (``curv-tile-RUN-TILE``)."""
    return str(key).rsplit("-", 1)[-1]


def _one_line(exc: BaseException) -> str:
    from ..core.paths import one_line

    return f"{type(exc).__name__}: {one_line(exc)}"
