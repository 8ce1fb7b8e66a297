"""The work behind large files: opening a preview or a full-resolution piece, and the whole file to an
output file, off the GUI thread.

:func:`load_large` is what the source job runs for a file too large to draw (a preview) and for a
full-resolution piece; :class:`WholeFileJob` runs :func:`curv.tiles.iter_estimate_file` in a
generator worker: its ``yield`` carries the progress (tiles done, points a second, time left) and
is where Cancel takes effect (the run stops, keeps its finished tiles and writes no output).
"""

from __future__ import annotations

import atexit
from dataclasses import replace
from pathlib import Path

from curv.core.jit import run_to_end
from curv.tiles.files import iter_estimate_file
from curv.tiles.preview import file_size, read_preview
from curv.tiles.regions import FileRegions
from PySide6.QtCore import QObject, Signal
from superqt.utils import create_worker

from app.model import large
from app.model.sources import FileSource

__all__ = ["load_large", "WholeFileJob", "regions_of"]

_REGIONS: dict = {}


def regions_of(path) -> FileRegions:
    """The :class:`curv.tiles.regions.FileRegions` of ``path``, kept while the viewer runs (its tiles are
    sorted once, at the first full-resolution region)."""
    key = str(Path(path).resolve())
    if key not in _REGIONS:
        _REGIONS[key] = FileRegions(path)
    return _REGIONS[key]


@atexit.register
def _close_regions() -> None:
    for regions in _REGIONS.values():
        regions.close()
    _REGIONS.clear()


def load_large(source):
    """``(source, mesh, None)`` for a file too large to draw whole (its preview) or a full-resolution
    piece; None for anything else (loaded as usual). Runs in the source worker."""
    if isinstance(source, large.FullResolutionSource):
        around = run_to_end(regions_of(source.path).iter_around(source.centre, source.radius, source.jobs))
        return replace(source, ball=around.ball), around.shape, None
    if not isinstance(source, large.PreviewSource):
        if not isinstance(source, FileSource) or source.repairs:
            return None
        counts = file_size(source.path)
        if counts is None or counts[0] <= large.PREVIEW_LIMIT:
            return None
    try:
        preview = read_preview(source.path, large.PREVIEW_LIMIT)
    except ValueError:  # a format read whole (an ASCII or polygon PLY): drawn whole as before
        return None
    return large.PreviewSource(source.path, total=preview.total, words=preview.words), preview.shape, None


class WholeFileJob(QObject):
    """The whole file estimated tile by tile into an output file (module notes).

    Signals
    -------
    progress(str, float)
        What runs and the fraction done.
    done(str)
        The run's summary in one line.
    failed(str)
        One line (an interrupted run says it keeps its finished tiles).
    running(bool)
    """

    progress = Signal(str, float)
    done = Signal(str)
    failed = Signal(str)
    running = Signal(bool)

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self._worker = None
        self.output = None

    @property
    def busy(self) -> bool:
        return self._worker is not None

    def start(self, path, output, method: str, range_, keywords: dict, *, workers: int | None = None) -> None:
        """Run ``curv.tiles.iter_estimate_file(path, output, method, range_, **keywords)``."""
        if self._worker is not None:
            return
        self.output = Path(output)
        box = []
        worker = create_worker(iter_estimate_file, str(path), str(output), method, range_, workers=workers,
                               **keywords, _start_thread=False, _connect={
            "yielded": lambda step: self._progress(box[0], step),
            "returned": lambda run: self._done(box[0], run),
            "errored": lambda exc: self._failed(box[0], exc)})
        box.append(worker)
        self._worker = worker
        worker.start()
        self.running.emit(True)
        self.progress.emit(f"Whole file to {self.output.name}: starting", 0.0)

    def cancel(self) -> None:
        """Stop at the next step: no output is written; the finished tiles stay for the same run again."""
        if self._worker is None:
            return
        self._worker.quit()
        self._worker = None
        self.running.emit(False)
        self.failed.emit(f"Cancelled the whole file to {self.output.name}: nothing written; the same run again "
                         f"resumes from its finished tiles")

    def _progress(self, worker, step) -> None:
        if worker is self._worker:
            words = getattr(step, "message", "") or ""
            self.progress.emit(f"Whole file to {self.output.name}: {words}", float(step))

    def _done(self, worker, run) -> None:
        if worker is not self._worker:
            return
        self._worker = None
        self.running.emit(False)
        unit = "vertices" if run.mesh else "points"
        share = 100.0 * run.valid / max(run.points, 1)
        self.done.emit(f"Wrote {run.output.name}: {run.points:,} {unit} in {run.tiles} tiles, {share:.1f} % valid, "
                       f"{run.seconds['total']:.0f} s")

    def _failed(self, worker, exc) -> None:
        if worker is not self._worker:
            return
        self._worker = None
        self.running.emit(False)
        text = " ".join(str(exc).split()) or type(exc).__name__
        self.failed.emit(f"Whole file to {self.output.name} failed: {text}")
