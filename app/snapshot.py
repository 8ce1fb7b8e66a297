"""Scripted snapshot: wait until the window shows every result, save its image, quit."""

from __future__ import annotations

import sys
from pathlib import Path

from PySide6.QtCore import QObject, QTimer
from PySide6.QtWidgets import QApplication

__all__ = ["Snapshot"]


class Snapshot(QObject):
    """Watches a :class:`MainWindow` and saves ``path`` once all panes are computed and drawn.

    With ``wait_for_advice`` it also waits for the advisor's answer for the shown mesh.
    ``status`` is 0 after a successful save, 1 on a load/estimate/advice failure or a timeout.
    """

    def __init__(self, window, path, *, timeout_s: float = 300.0, wait_for_advice: bool = False) -> None:
        super().__init__(window)
        self.window, self.path = window, Path(path)
        self.wait_for_advice = wait_for_advice
        self.status = 1
        self.window.quiet = True  # no dialogs: failures go to stderr
        self.window.grey_frames = False  # one frame: the picture saved
        self._timer = QTimer(self, interval=100)
        self._timer.timeout.connect(self._poll)
        self._deadline = QTimer(self, singleShot=True, interval=int(timeout_s * 1000))
        self._deadline.timeout.connect(lambda: self._finish(f"timed out after {timeout_s:g} s"))
        window.error_shown.connect(self._finish)
        self._done = False

    def start(self) -> None:
        self._timer.start()
        self._deadline.start()

    def ready(self) -> bool:
        """True when a mesh and its report are shown, every pane has its result and its colours are
        painted (and the advice is there, if waited for)."""
        doc, ctl = self.window.doc, self.window.controller
        return (doc.mesh is not None and doc.report is not None and not ctl.busy
                and all(p.key in doc.results for p in doc.panes) and not self.window.drawing.painter.busy
                and (not self.wait_for_advice or doc.advice_current))

    def _poll(self) -> None:
        if self._done or not self.ready():
            return
        self.window.redraw()
        if self.window.drawing.painter.busy:  # a large input's colours: painted in a worker first
            return
        self._timer.stop()
        QTimer.singleShot(50, self._save)  # let the window lay out and paint (the save processes the events)

    def _save(self) -> None:
        if self._done:
            return
        QApplication.processEvents()
        image = self.window.grab()  # renders every viewport (a render before it was a second frame)
        wanted = getattr(self.window, "requested_size", None)
        if wanted is not None and (image.width(), image.height()) != tuple(wanted):
            print(f"curvlab: the window could not be {wanted[0]}x{wanted[1]}; "
                  f"saved at its minimum {image.width()}x{image.height()}", file=sys.stderr)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if not image.save(str(self.path), "PNG"):
            self._finish(f"could not write {self.path}")
            return
        print(f"curvlab: wrote {self.path} ({image.width()}x{image.height()})")
        self._finish(None)

    def _finish(self, error: str | None) -> None:
        if self._done:
            return
        self._done = True
        self._timer.stop()
        self._deadline.stop()
        if error:
            print(f"curvlab: {error}", file=sys.stderr)
        self.status = 0 if error is None else 1
        self.window.close()
        QApplication.instance().exit(self.status)
