"""Progress of a command's long work on stderr: a bar per phase on a terminal, a line every few seconds elsewhere.

The command line's ``curv estimate`` shows its phases (load, the estimate's ``setup`` or
``normals`` and ``orientation``, ``estimate``, ``checks``, write) with it; any command that drives
an ``iter_*`` generator of curv (a tiled run) can do the same::

    with PhaseProgress("qs R2") as progress:          # "bar" on a terminal, "lines" elsewhere
        progress.phase("load")                        # a phase of the command's own: no fraction known
        cloud = curv.load(path)
        result = progress.follow(curv.iter_estimate(cloud, "qs", 2))
        progress.phase("write")
        curv.save_result(out, cloud, result)
    # leaving the block ends the last phase

Interface:

- ``PhaseProgress(label="", *, mode=None, stream=None, interval=None)``: ``mode`` is
  ``"bar"`` (a tqdm bar per phase), ``"lines"`` (plain lines) or ``"off"``; None: a bar when
  ``stream`` (default ``sys.stderr``) is a terminal, else lines; ``interval`` the seconds between
  lines (default :data:`LINE_SECONDS`).
- :meth:`PhaseProgress.phase`: ends the current phase and starts another, its fraction unknown
  until an update gives one.
- :meth:`PhaseProgress.update`: a float, the fraction (0..1) of the current phase done, or a
  :class:`curv.core.jit.Progress`: a new non-empty ``phase`` starts that phase first, a new
  non-empty ``message`` is shown once as a note. A fraction below the last one starts the
  phase's timing again (a new pass over the points); a phase whose fractions are all 0 so far
  shows its elapsed time alone (a step without chunks, such as orienting the normals).
- :meth:`PhaseProgress.note`: a line for a person (e.g. the first-run compilation).
- :meth:`PhaseProgress.status`: the current phase's live words (a tiled run's ``tiles 3/40,
  1.2M points/s, 5.0 min left``), each replacing the last: shown after the bar, or at the end of
  the phase's line, in place of the time left measured here; a new phase starts without any.
- :meth:`PhaseProgress.follow`: drives a generator through :meth:`update` and returns its value.
- :meth:`PhaseProgress.close` (or leaving the ``with`` block): ends the last phase; a second call
  does nothing.

On a terminal each phase has a tqdm bar with the phase's elapsed time and the time left, left on
screen with the phase's time when it ends. Elsewhere (a log, a pipe) a line
``curv: qs R2: normals 45 % after 18 s, about 22 s left`` comes every ``interval`` seconds while
the work runs, from a ticker thread, so phases that block without reporting (reading and writing
files) are covered too; work shorter than ``interval`` writes nothing but its notes.

The time left is the phase's rest at its rate since its first measured fraction (what came before
it, such as compiling the kernels or a first chunk, is not counted), shown once that rate has been
measured for a second; a phase without fractions shows its elapsed time alone. Phases are timed
one by one: the whole run's time left is not guessed.
"""

from __future__ import annotations

import sys
import threading
import time
from typing import Generator

from .core.jit import forwarded, run_to_end

__all__ = ["PhaseProgress", "LINE_SECONDS", "MODES", "duration"]

LINE_SECONDS = 5.0
"""Seconds between two lines when the stream is not a terminal."""

MODES = ("bar", "lines", "off")

_RATE_SECONDS = 1.0
"""A phase's rate is trusted (and its time left shown) once it has been measured this long."""

_TICK_SECONDS = 0.5
"""How often the ticker refreshes a bar's elapsed time or checks whether a line is due."""


def duration(seconds: float) -> str:
    """``12 s``, ``3 min 20 s``, ``1 h 02 min``: a duration for a person."""
    seconds = max(0.0, float(seconds))
    if seconds < 60:
        return f"{seconds:.0f} s" if seconds >= 10 else f"{seconds:.1f} s"
    if seconds < 3600:
        return f"{int(seconds // 60)} min {int(seconds % 60):02d} s"
    return f"{int(seconds // 3600)} h {int(seconds % 3600 // 60):02d} min"


class _Phase:
    """One phase's timing: its start, its latest fraction and where its rate is measured from."""

    def __init__(self, name: str, now: float):
        self.name = name
        self.start = now
        self.fraction: float | None = None
        self.origin: tuple[float, float] | None = None  # (time, fraction) of the first measured fraction
        self.status = ""  # the work's own words (PhaseProgress.status), in place of the time left

    def record(self, fraction: float, now: float) -> None:
        fraction = min(max(float(fraction), 0.0), 1.0)
        if fraction == 0.0 and not self.fraction:
            return  # nothing measured yet (a step that reports no fraction): no "0 %" shown
        if self.fraction is not None and fraction < self.fraction:
            self.origin = None  # a new pass within the phase: its rate is measured anew
        self.fraction = fraction
        if self.origin is None and fraction > 0:
            self.origin = (now, fraction)

    def left(self, now: float) -> float | None:
        """Seconds left at the measured rate; None while it is not measured yet."""
        if self.origin is None or self.fraction is None:
            return None
        t0, f0 = self.origin
        if now - t0 < _RATE_SECONDS or self.fraction <= f0:
            return None
        rate = (self.fraction - f0) / (now - t0)
        return (1.0 - self.fraction) / rate

    def words(self, now: float) -> str:
        """``normals 45 % after 18 s, about 22 s left`` (or ``load after 3.0 s``)."""
        done = "" if self.fraction is None else f" {100 * self.fraction:.0f} %"
        text = f"{self.name}{done} after {duration(now - self.start)}"
        if self.status:
            return f"{text}, {self.status}"
        left = self.left(now)
        return text if left is None else f"{text}, about {duration(left)} left"


class PhaseProgress:
    """Progress of work in named phases on ``stream`` (module notes)."""

    def __init__(self, label: str = "", *, mode: str | None = None, stream=None, interval: float | None = None):
        self.stream = stream if stream is not None else sys.stderr
        if mode is None:
            isatty = getattr(self.stream, "isatty", None)
            mode = "bar" if isatty is not None and isatty() else "lines"
        if mode not in MODES:
            raise ValueError(f"mode must be one of {', '.join(MODES)}; got {mode!r}")
        self.mode = mode
        self.label = label
        self.interval = float(LINE_SECONDS if interval is None else interval)
        self._lock = threading.RLock()
        self._current: _Phase | None = None
        self._bar = None
        self._last_draw = 0.0
        self._last_line = time.perf_counter()
        self._notes: set[str] = set()
        self._closed = False
        self._ticker: threading.Thread | None = None
        self._stop = threading.Event()
        if mode != "off":
            self._ticker = threading.Thread(target=self._tick, name="curv progress", daemon=True)
            self._ticker.start()

    # -- the interface ----------------------------------------------------------------------------
    def phase(self, name: str) -> None:
        """End the current phase and start ``name`` (its fraction unknown until an update)."""
        with self._lock:
            if self._closed:
                return
            self._end_phase()
            now = time.perf_counter()
            self._current = _Phase(name, now)
            if self.mode == "bar":
                self._bar = self._new_bar(name)

    def update(self, step) -> None:
        """Record a step: a fraction of the current phase, or a :class:`~curv.core.jit.Progress`
        whose phase and message are taken first (module notes)."""
        with self._lock:
            if self._closed:
                return
            name = getattr(step, "phase", "") or ""
            if name and (self._current is None or name != self._current.name):
                self.phase(name)
            message = getattr(step, "message", "") or ""
            if message:
                self.note(message)
            if self._current is None:
                self.phase("work")
            now = time.perf_counter()
            self._current.record(float(step), now)
            if self.mode == "bar" and now - self._last_draw >= 0.1:
                self._draw(now)

    def note(self, text: str) -> None:
        """Show ``text`` once, on a line of its own (``curv: text``)."""
        with self._lock:
            if self._closed or self.mode == "off" or text in self._notes:
                return
            self._notes.add(text)
            line = f"curv: {text}"
            if self._bar is not None:
                self._bar.write(line, file=self.stream)
            else:
                self.stream.write(line + "\n")
                self.stream.flush()

    def status(self, text: str) -> None:
        """The current phase's live words (module notes); an empty ``text`` clears them."""
        with self._lock:
            if self._closed:
                return
            if self._current is None:
                self.phase("work")
            self._current.status = str(text)
            if self.mode == "bar":
                self._draw(time.perf_counter())

    def follow(self, gen: Generator):
        """Drive ``gen`` (an ``iter_*`` generator) to its end through :meth:`update`; return its value.

        An exception (a Ctrl-C included) closes ``gen`` before it propagates.
        """
        try:
            return run_to_end(forwarded(gen, self.update))
        finally:
            gen.close()

    def close(self, *, completed: bool = True) -> None:
        """End the last phase (a bar at 100 % unless ``completed`` is False: the work failed or was
        interrupted) and stop the ticker; nothing more is written."""
        with self._lock:
            if self._closed:
                return
            self._end_phase(completed=completed)
            self._closed = True
        self._stop.set()
        if self._ticker is not None and self._ticker is not threading.current_thread():
            self._ticker.join()

    def __enter__(self) -> "PhaseProgress":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(completed=exc_type is None)

    # -- drawing ----------------------------------------------------------------------------------
    def _title(self, name: str) -> str:
        return f"{self.label}: {name}" if self.label else name

    def _new_bar(self, name: str):
        from tqdm import tqdm

        return tqdm(total=100, desc=self._title(name), file=self.stream, leave=True, dynamic_ncols=True,
                    mininterval=0.1, bar_format="{desc} {elapsed}", disable=False)

    def _draw(self, now: float) -> None:
        """The bar's fraction and time left (under the lock)."""
        bar, phase = self._bar, self._current
        if bar is None or phase is None:
            return
        self._last_draw = now
        if phase.fraction is not None:
            bar.bar_format = "{desc} {percentage:3.0f}%|{bar}| {elapsed}{postfix}"
            bar.n = round(100 * phase.fraction, 1)
            left = phase.left(now)
            # tqdm writes its postfix after ", "
            if phase.status:
                bar.set_postfix_str(phase.status, refresh=False)
            else:
                bar.set_postfix_str("" if left is None else f"about {duration(left)} left", refresh=False)
        elif phase.status:
            bar.bar_format = "{desc} {elapsed}{postfix}"
            bar.set_postfix_str(phase.status, refresh=False)
        bar.refresh()

    def _end_phase(self, *, completed: bool = True) -> None:
        """Close the current phase (under the lock): a bar stays with its time, a line is due later."""
        phase, bar = self._current, self._bar
        self._current, self._bar = None, None
        if bar is not None:
            if completed and phase is not None and phase.fraction is not None:
                phase.fraction = 1.0
                phase.origin = None
                bar.bar_format = "{desc} {percentage:3.0f}%|{bar}| {elapsed}"
                bar.n = 100
            bar.refresh()
            bar.close()

    def _tick(self) -> None:
        """The ticker: a bar's elapsed time refreshed, a line written when one is due."""
        tick = max(0.01, min(_TICK_SECONDS, self.interval))
        while not self._stop.wait(tick):
            with self._lock:
                if self._closed or self._current is None:
                    continue
                now = time.perf_counter()
                if self.mode == "bar":
                    if now - self._last_draw >= tick:
                        self._draw(now)
                elif now - self._last_line >= self.interval:
                    self._last_line = now
                    self.stream.write(f"curv: {self._title(self._current.words(now))}\n")
                    self.stream.flush()
