"""Run a study: a generator of progress reports over tasks, results appended as they finish.

>>> gen = iter_study(settings, "study-out")        # doctest: +SKIP
>>> for progress in gen:                           # each yield is a cancel point
...     print(progress.done, "/", progress.total, progress.eta)

Stopping the generator (``gen.close()``, Ctrl-C, a crash) loses only the tasks still running: each
finished task is in ``results.csv`` already, and a rerun with the same output directory skips it.
"""

from __future__ import annotations

import json
import time
from concurrent.futures import FIRST_COMPLETED, Executor, wait
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Generator

from ..core.jit import run_to_end
from .executors import open_executor, parallelism, stop_executor
from .protocol import StudySettings, Task, Variant
from .store import ResultsFile
from .table import Table
from .tasks import run_task

__all__ = ["Progress", "iter_study", "run", "select", "RESULTS_NAME", "SETTINGS_NAME"]

RESULTS_NAME = "results.csv"
SETTINGS_NAME = "study.json"


@dataclass
class Progress:
    """Where a study run stands.

    Attributes
    ----------
    done, total : int
        Tasks finished in this run, and tasks this run has to do (already-done ones excluded).
    skipped : int
        Tasks found complete in the results file and not run again.
    elapsed : float
        Seconds since the run started.
    eta : float or None
        Estimated seconds left, from the work done so far weighted by mesh size; None at the start.
    task : Task or None
        The task that just finished (None for the first report).
    rows : list of dict
        Its result rows.
    errors : int
        Variant evaluations that raised so far in this run.
    """

    done: int
    total: int
    skipped: int
    elapsed: float
    eta: float | None = None
    task: Task | None = None
    rows: list = field(default_factory=list)
    errors: int = 0

    @property
    def fraction(self) -> float:
        return self.done / self.total if self.total else 1.0


def _todo(settings: StudySettings, done: dict[tuple, set[str]]) -> list[tuple[Task, tuple[Variant, ...]]]:
    out = []
    for task in settings.tasks():
        have = done.get(task.key, set())
        missing = tuple(v for v in settings.variants_for(task) if v.id not in have)
        if missing:
            out.append((task, missing))
    return out


def _weight(task: Task, variants: tuple[Variant, ...]) -> float:
    """Relative cost of a task for the ETA: linear in vertices and in variants."""
    return float(task.density) * len(variants)


def iter_study(
    settings: StudySettings,
    out_dir,
    *,
    executor: Executor | None = None,
    scheduler=None,
    workers: int | None = None,
) -> Generator[Progress, None, Table]:
    """Run the study, yielding a :class:`Progress` after every finished task.

    Parameters
    ----------
    settings : StudySettings
    out_dir : path-like
        Receives ``results.csv`` (appended to) and ``study.json`` (the settings).
    executor : concurrent.futures.Executor, optional
        Where tasks run; it is not shut down here. Default: one made by
        :func:`~curv.study.executors.open_executor` from ``scheduler`` and ``workers``.
    scheduler : str or cluster, optional
        Dask scheduler address (``tcp://host:port``); default a local process pool.
    workers : int, optional
        Local processes (``0``: in this process).

    Yields
    ------
    Progress
        One report before the first task and one after each task.

    Returns
    -------
    Table
        The results of the whole grid of ``settings`` (see :func:`select`).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / SETTINGS_NAME).write_text(json.dumps(settings.as_dict(), indent=2) + "\n")
    results = ResultsFile(out / RESULTS_NAME)
    todo = _todo(settings, results.done())
    skipped = settings.n_tasks - len(todo)
    total_w = sum(_weight(t, v) for t, v in todo) or 1.0
    t0 = time.perf_counter()
    yield Progress(done=0, total=len(todo), skipped=skipped, elapsed=0.0)
    if not todo:
        return select(results.load(), settings)

    own = executor is None
    ctx = open_executor(scheduler=scheduler, workers=workers) if own else nullcontext(executor)
    done = errors = 0
    done_w = 0.0
    with ctx as ex:
        window = 2 * parallelism(ex)
        queue = iter(todo)
        pending: dict = {}
        finished_ok = False
        try:
            while True:
                while len(pending) < window:
                    item = next(queue, None)
                    if item is None:
                        break
                    pending[ex.submit(run_task, *item)] = item
                if not pending:
                    break
                ready, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in ready:
                    task, variants = pending.pop(fut)
                    try:
                        rows = fut.result()
                    except Exception as exc:
                        raise RuntimeError(f"study task {task} failed: {exc}") from exc
                    results.append(rows)
                    done += 1
                    done_w += _weight(task, variants)
                    errors += sum(bool(r["error"]) for r in rows)
                    elapsed = time.perf_counter() - t0
                    yield Progress(done=done, total=len(todo), skipped=skipped, elapsed=elapsed,
                                   eta=elapsed * (total_w - done_w) / done_w, task=task, rows=rows,
                                   errors=errors)
            finished_ok = True
        finally:
            if not finished_ok:
                for fut in pending:
                    fut.cancel()
                if own:
                    stop_executor(ex, now=True)
    return select(results.load(), settings)


def run(settings: StudySettings, out_dir, **kwargs) -> Table:
    """Run :func:`iter_study` to the end and return its table (keyword arguments as there)."""
    return run_to_end(iter_study(settings, out_dir, **kwargs))


def select(table: Table, settings: StudySettings) -> Table:
    """The rows of ``table`` that belong to the grid of ``settings`` (a results file may hold more)."""
    return table.where(
        seed=settings.seed, function=settings.functions, density=settings.densities,
        irregularity=[float(x) for x in settings.irregularity], noise=[float(x) for x in settings.noise],
        sample=lambda s: s < settings.samples, variant=[v.id for v in settings.variants()],
    )
