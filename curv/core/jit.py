"""How curv runs its numba kernels: decorators, threads, one launch at a time, chunked progress.

Every hot loop in curv is a numba kernel compiled with :data:`jit` (serial) or :data:`jit_parallel`
(``prange`` over vertices). This module is the one owner of how they are launched:

- **Threads.** ``CURV_THREADS`` caps the threads of every parallel kernel (default: the usable
  cores). numba's thread count is per calling thread, so :func:`launch` sets it on each call.
- **One parallel launch at a time.** numba's ``workqueue`` layer (chosen here: it needs no extra
  library and is fork-safe, so the study's process pool may fork after a kernel ran) does not allow
  two threads to launch parallel kernels at once. The viewer's panes estimate on worker threads in
  parallel, so launches take :data:`LAUNCH_LOCK`; since every kernel call covers a short chunk of
  vertices (:func:`iter_chunks`), two estimates interleave chunk by chunk.
- **Progress and cancel.** :func:`iter_chunks` cuts the vertices into chunks whose size adapts so
  that each kernel call lasts about :data:`TARGET_SECONDS`; it yields between chunks, which is
  where a caller may stop. Work that is not a generator all the way down (a cached property, a
  driver that runs its passes to the end) runs under :func:`iter_watched`, on a helper thread
  whose chunks and announced steps (:func:`announce`) it yields as progress, and which a cancel
  stops at its next chunk.
- **Compilation.** Kernels are cached on disk (``cache=True``), in a folder of their own for each
  state of curv's sources (:func:`source_fingerprint`: numba would otherwise keep a kernel's old
  machine code when only a helper it calls from another module changed); :func:`compile_pending`
  tells whether a first call will compile, so the CLI and the viewer can say so.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable, Generator, Iterable

import numba
from numba import njit

__all__ = [
    "jit", "jit_parallel", "jit_inlined", "JIT_OPTIONS", "prange", "threads", "launch", "iter_chunks", "run_to_end",
    "forwarded", "monotone",
    "rescaled", "thread_slices", "slice_bounds", "compile_pending", "COMPILE_MESSAGE", "Progress", "TARGET_SECONDS", "LAUNCH_LOCK",
    "source_fingerprint", "iter_watched", "announce", "POLL_SECONDS",
]

# must be chosen before the first parallel launch of the process
numba.config.THREADING_LAYER = "workqueue"


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return False
    return os.access(folder, os.W_OK | os.X_OK)


def source_fingerprint(package: Path) -> str:
    """A short hash of the contents of every ``.py`` file below ``package`` (16 hex digits).

    numba's cache knows a kernel by its own file only, not by the helpers of other modules it
    compiled in: after an edit (or a ``git pull``) that changed a helper and not the kernel's file,
    the kernel would load its old machine code from the cache. Each state of curv's sources
    therefore gets its own cache folder (:func:`_choose_cache_dir`).
    """
    digest = hashlib.blake2b(digest_size=8)
    for path in sorted(package.rglob("*.py")):
        digest.update(str(path.relative_to(package)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _prune_other_states(folder: Path, *, keep_days: float = 1.0) -> None:
    """Delete the cache folders of other source states beside ``folder`` unused for ``keep_days``."""
    import shutil

    now = time.time()
    for other in folder.parent.glob("numba-*"):
        try:
            if other != folder and now - other.stat().st_mtime > keep_days * 86400:
                shutil.rmtree(other, ignore_errors=True)
        except OSError:
            pass


def _choose_cache_dir() -> None:
    """Give numba a cache folder it can write and that belongs to this state of curv's sources.

    The folder is ``numba-<source_fingerprint>`` in curv's own ``__pycache__``, else in the user's
    cache folder, else in a per-user folder of the system's temporary directory (a read-only
    install run by a user without a home, as in a service or a test run as ``nobody``: numba
    raises at decoration time when it can write nowhere). Folders of earlier source states unused
    for a day are deleted. ``NUMBA_CACHE_DIR`` set by the user always wins.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    package = Path(__file__).resolve().parents[1]  # curv/
    state = f"numba-{source_fingerprint(package)}"
    home_cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "curvlab-numba"
    for base in (package / "__pycache__", home_cache, Path(tempfile.gettempdir()) / f"curvlab-numba-{os.getuid()}"):
        folder = base / state
        if _writable(folder):
            numba.config.CACHE_DIR = str(folder)
            try:
                os.utime(folder)  # in use: not pruned by another state's process
            except OSError:
                pass
            _prune_other_states(folder)
            return


_choose_cache_dir()

# error_model="numpy": a float division by zero gives inf/NaN as in numpy (and so lands in a
# validity check) instead of raising, which inside a parallel loop was swallowed and left rows unset
JIT_OPTIONS = {"cache": True, "nogil": True, "error_model": "numpy"}
"""The options of every kernel (also of an ``@overload``'s implementations: ``jit_options=JIT_OPTIONS``)."""

jit = njit(**JIT_OPTIONS)
"""Serial kernel or helper: ``@jit``."""

jit_parallel = njit(parallel=True, **JIT_OPTIONS)
"""Parallel kernel whose outer loop is a ``prange``: ``@jit_parallel``."""

jit_inlined = njit(inline="always", **JIT_OPTIONS)
"""``@jit`` inlined by numba into its callers: for a per-vertex helper a
kernel calls with many of the mesh's arrays, which a plain call passes array by array. csm and icc
took 25-50 % more CPU time at R4 with their crossing faces' helper as a plain call (100k-vertex
sphere, one thread); inlined, the same as with the loop written in the kernel."""

prange = numba.prange

TARGET_SECONDS = 0.05
"""Wanted duration of one kernel call: progress and cancel come at least this often (in practice
a few times this, as the chunk size adapts to the measured speed)."""

MIN_CHUNK = 256
MAX_CHUNK = 1 << 20

LAUNCH_LOCK = threading.Lock()
"""Held while a parallel kernel runs (see the module notes)."""



def _new_lock_in_child() -> None:
    # a fork taken while another thread held the lock would inherit it held, with no owner left
    global LAUNCH_LOCK
    LAUNCH_LOCK = threading.Lock()


os.register_at_fork(after_in_child=_new_lock_in_child)

COMPILE_MESSAGE = "compiling curvature kernels (first run only)..."


class Progress(float):
    """A fraction done (0..1) that may carry a status message for a person (e.g. compiling) and
    the name of the phase it measures.

    It is a float, so consumers that only want the fraction can ignore the rest. ``message`` is a
    note to show once (the first-run compilation); ``phase`` names the part of the work the
    fraction belongs to (``curv.estimate``'s ``"setup"``, ``"normals"``, ``"orientation"``,
    ``"estimate"``, ``"checks"``); empty: the phase of the previous step goes on. The fraction is
    that phase's own: it starts again from 0 when the phase changes.
    """

    message: str = ""
    phase: str = ""

    def __new__(cls, fraction: float, message: str = "", phase: str = ""):
        obj = super().__new__(cls, fraction)
        obj.message = message
        obj.phase = phase
        return obj


def threads() -> int:
    """Threads for parallel kernels: ``CURV_THREADS`` if set (capped by numba's pool), else all usable cores."""
    limit = numba.config.NUMBA_NUM_THREADS
    env = os.environ.get("CURV_THREADS", "").strip()
    if env.isdigit() and int(env) > 0:
        return max(1, min(int(env), limit))
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, limit))


def launch(kernel: Callable, *args):
    """Call a parallel kernel with :func:`threads` threads, one launch at a time in the process."""
    with LAUNCH_LOCK:
        numba.set_num_threads(threads())
        return kernel(*args)


@jit
def slice_bounds(lo, hi, t, parts):
    """Items ``start .. stop-1`` of slice t of ``parts`` equal slices of ``lo .. hi-1``: the items
    a parallel kernel's ``prange`` step t works on (each slice with its own scratch)."""
    return lo + (hi - lo) * t // parts, lo + (hi - lo) * (t + 1) // parts


def thread_slices(count: int, parts: int):
    """``(starts, stops)`` of ``parts`` contiguous, nearly equal slices of ``range(count)``."""
    import numpy as np

    bounds = (np.arange(parts + 1, dtype=np.int64) * count) // parts
    return bounds[:-1].copy(), bounds[1:].copy()


def iter_chunks(n: int, run: Callable[[int, int], None], *, chunk: int | None = None,
                start_fraction: float = 0.0, end_fraction: float = 1.0) -> Generator[float, None, None]:
    """Call ``run(lo, hi)`` over consecutive chunks of ``range(n)`` and yield the fraction done.

    Parameters
    ----------
    n : int
        Number of items (vertices).
    run : callable
        ``run(lo, hi)`` does the work for items ``lo .. hi-1`` (typically one kernel launch).
    chunk : int, optional
        Fixed chunk size; default adaptive, so that a call lasts about :data:`TARGET_SECONDS`.
    start_fraction, end_fraction : float
        The progress range this work maps to.

    Yields
    ------
    float
        Fraction done, after each chunk: the points where a caller may cancel.
    """
    size = chunk or 4 * MIN_CHUNK
    lo = 0
    span = end_fraction - start_fraction
    while lo < n:
        hi = min(n, lo + size)
        t0 = time.perf_counter()
        run(lo, hi)
        took = time.perf_counter() - t0
        if chunk is None and took > 0:
            # aim at the target, growing at most 4x a step so one slow region cannot overshoot far
            wanted = int(size * TARGET_SECONDS / took)
            size = max(MIN_CHUNK, min(MAX_CHUNK, 4 * size, wanted))
        lo = hi
        done = start_fraction + span * hi / max(n, 1)
        watcher = getattr(_WATCHED, "watcher", None)
        if watcher is not None:  # this thread runs under iter_watched: report the chunk (or stop here)
            watcher.chunk(done)
        yield done


def run_to_end(gen: Generator):
    """Drive a progress generator (an ``iter_*`` function's) to its end and return its value: what
    the functions without the ``iter_`` prefix do."""
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


def forwarded(gen: Generator, each: Callable[[object], object]) -> Generator:
    """``yield from gen`` with every step passed through ``each`` (what it returns is yielded);
    returns ``gen``'s value. Closing this (or an exception) closes ``gen``."""
    try:
        while True:
            try:
                step = next(gen)
            except StopIteration as stop:
                return stop.value
            yield each(step)
    finally:
        gen.close()


def rescaled(gen: Generator, start: float, end: float, *, phase: str | None = None) -> Generator[Progress, None, object]:
    """``yield from gen`` with its fractions mapped to ``start .. end`` (a part of a larger piece of
    work), messages kept, and phases kept or, with ``phase``, all named so; returns ``gen``'s value.
    Closing this closes ``gen``."""
    span = end - start
    return (yield from forwarded(gen, lambda done: Progress(
        start + span * float(done), getattr(done, "message", ""),
        getattr(done, "phase", "") if phase is None else phase)))


def monotone(gen: Generator) -> Generator[Progress, None, object]:
    """``yield from gen`` with every fraction at least the one before and at most 1 (for work whose
    fractions are sums of shares, which rounding may put a few ulps back); returns ``gen``'s value."""
    last = 0.0

    def forward(done) -> Progress:
        nonlocal last
        last = min(1.0, max(last, float(done)))
        return Progress(last, getattr(done, "message", ""), getattr(done, "phase", ""))

    return (yield from forwarded(gen, forward))


POLL_SECONDS = 0.1
"""How often :func:`iter_watched` yields while its work runs."""

_WATCHED = threading.local()
"""``_WATCHED.watcher``: the :class:`_Watcher` of the work this thread runs for :func:`iter_watched`."""


class _Stopped(Exception):
    """Raised at a chunk of watched work whose caller went away (a cancel)."""


class _Watcher:
    """What watched work reports: the fraction of its latest chunk loop and the step it is in."""

    def __init__(self, phase: str):
        self.phase = phase
        self.fraction = 0.0
        self.stopped = False

    def chunk(self, fraction: float) -> None:
        if self.stopped:
            raise _Stopped
        self.fraction = float(fraction)

    def step(self, name: str) -> None:
        if self.stopped:
            raise _Stopped
        self.phase, self.fraction = name, 0.0

    def progress(self) -> Progress:
        return Progress(self.fraction, "", self.phase)


def announce(step: str) -> None:
    """Say that a step of long work without chunks of its own begins (e.g. ``"orientation"``).

    Under :func:`iter_watched` the step becomes the phase of the progress it yields, from 0 until
    the next chunk loop reports; elsewhere nothing happens. A cancelled watch stops the work here.
    """
    watcher = getattr(_WATCHED, "watcher", None)
    if watcher is not None:
        watcher.step(step)


def iter_watched(work: Callable[[], object], *, phase: str = "") -> Generator[Progress, None, object]:
    """Run ``work()`` on a helper thread and yield its progress while it runs; return its value.

    For work that cannot yield itself (a cached property, a driver that runs its generators to
    the end with :func:`run_to_end`): every chunk of every :func:`iter_chunks` loop on that thread
    sets the fraction (that loop's), every :func:`announce` the phase. The progress is yielded
    every :data:`POLL_SECONDS` as :class:`Progress` with ``phase`` (the given one until a step is
    announced); nothing is yielded when the work ends sooner.

    Closing the generator (a caller's cancel) lets the work stop at its next chunk or announced
    step, in the background; an exception of ``work`` is raised here, with its traceback.
    """
    watcher = _Watcher(phase)
    done = threading.Event()
    outcome: dict = {}

    def run() -> None:
        _WATCHED.watcher = watcher
        try:
            outcome["value"] = work()
        except _Stopped:
            pass
        except BaseException as exc:  # handed to the caller's thread
            outcome["error"] = exc
        finally:
            _WATCHED.watcher = None
            done.set()

    thread = threading.Thread(target=run, name=f"curv {phase or 'work'}", daemon=True)
    thread.start()
    try:
        while not done.wait(POLL_SECONDS):
            yield watcher.progress()
    finally:
        watcher.stopped = True  # only matters when the caller left early
    if "error" in outcome:
        error = outcome.pop("error")
        raise error
    return outcome["value"]


def compile_pending(kernels: Iterable) -> bool:
    """Whether calling these kernels will compile some of them (no usable on-disk cache yet).

    A kernel already compiled in this process, or with an index file in numba's cache, is not
    pending. Reads numba's cache bookkeeping; if that ever changes shape, answers True (the message
    then shows once too often, never too rarely).
    """
    for kernel in kernels:
        if getattr(kernel, "overloads", None):
            continue
        try:
            cache = kernel._cache
            index = cache._cache_file._index_path
        except AttributeError:
            return True
        if not os.path.exists(index):
            return True
    return False
