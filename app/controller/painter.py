"""Painting scenes in a worker: the colours of a large input take seconds of numpy work."""

from __future__ import annotations

from PySide6.QtCore import QObject, Signal
from superqt.utils import create_worker

from app.model.picture import Picture, Scene, paint

__all__ = ["Painter"]


class Painter(QObject):
    """Runs :func:`app.model.picture.paint` off the GUI thread, one scene at a time.

    A scene asked for while another is painted waits; a newer one replaces it (a burst of changes,
    a dragged slider, paints the first and the last). A painting that cannot stop midway finishes,
    and its picture is handed out only if no newer scene was asked for meanwhile.

    Signals
    -------
    painted(Picture, object)
        The picture of the newest scene asked for, with the key it was asked with.
    failed(str)
        Painting raised (a one-line message).
    """

    painted = Signal(object, object)
    failed = Signal(str)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._running = None  # (worker, key)
        self._next: tuple[Scene, object] | None = None

    @property
    def busy(self) -> bool:
        """True while a scene is painted or waits to be."""
        return self._running is not None or self._next is not None

    def paint(self, scene: Scene, key) -> None:
        """Paint ``scene`` in a worker; :attr:`painted` carries the picture and ``key``."""
        self._next = (scene, key)
        if self._running is None:
            self._start()

    def _start(self) -> None:
        scene, key = self._next
        self._next = None
        box = []
        worker = create_worker(paint, scene, _start_thread=False, _connect={
            "returned": lambda picture: self._done(box[0], picture, key),
            "errored": lambda exc: self._done(box[0], exc, key)})
        box.append(worker)
        self._running = (worker, key)
        worker.start()

    def _done(self, worker, out: Picture | Exception, key) -> None:
        if self._running is None or self._running[0] is not worker:
            return
        self._running = None
        if self._next is not None:  # a newer scene came meanwhile: this picture is stale
            self._start()
        elif isinstance(out, Exception):
            self.failed.emit(f"Could not colour the panes: {out}")
        else:
            self.painted.emit(out, key)
