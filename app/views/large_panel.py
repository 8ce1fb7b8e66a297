"""The Large file panel: what a preview shows, the full resolution around the pick, the whole file to a file.

Shown for every input; its controls wake up for a file opened as a preview
(:class:`app.model.large.PreviewSource`) or a full-resolution piece of one.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Signal
from PySide6.QtWidgets import (QFileDialog, QFormLayout, QHBoxLayout, QLabel, QLineEdit, QProgressBar, QPushButton,
                               QWidget)

from app.controller.large import WholeFileJob
from app.model import Document
from app.model.inputs import is_points, unit_length
from app.model.large import FullResolutionSource, PreviewSource, pane_job, whole_file_suffixes
from app.model.region import index_region, show_region

__all__ = ["LargePanel", "attach_large_panel"]

DEFAULT_RADIUS_UNITS = 20.0
"""The radius offered for a full-resolution region, in the preview's spacings (mean edges)."""


class LargePanel(QWidget):
    """Controls for a large file (module notes).

    Parameters
    ----------
    doc : Document
    controller : app.controller.Controller
        Opens the full-resolution piece as the document's source.
    """

    message = Signal(str, bool)

    def __init__(self, doc: Document, controller, parent=None) -> None:
        super().__init__(parent)
        self.doc, self.controller = doc, controller
        self.job = WholeFileJob(self)
        self.shown = QLabel()
        self.shown.setWordWrap(True)
        self.shown.setObjectName("large_shown")
        self.radius = QLineEdit()
        self.radius.setToolTip("Radius of the region read at full resolution around the picked point, in the "
                               "file's units")
        self.around = QPushButton("Full resolution around pick")
        self.around.setToolTip("Read the file's every point within the radius of the picked point (with the halo "
                               "the panes' estimates read) and estimate every pane there")
        self.back = QPushButton("Back to preview")
        self.back.setToolTip("Show the whole file's preview again")
        self.whole = QPushButton("Whole file to…")
        self.whole.setToolTip("Estimate the active pane's estimator on the whole file, tile by tile, into an output "
                              "file (LAS/LAZ keeps every record of a LAS input)")
        self.bar = QProgressBar()
        self.bar.setRange(0, 1000)
        self.bar.setTextVisible(False)
        self.cancel = QPushButton("Cancel")
        self.cancel.setToolTip("Stop the whole-file run: nothing is written; the same run again resumes")
        self.status = QLabel()
        self.status.setWordWrap(True)
        self.status.setObjectName("large_status")
        form = QFormLayout(self)
        form.addRow(self.shown)
        form.addRow("Radius", self.radius)
        buttons = QHBoxLayout()
        buttons.addWidget(self.around)
        buttons.addWidget(self.back)
        form.addRow(buttons)
        run = QHBoxLayout()
        run.addWidget(self.whole)
        run.addWidget(self.bar, 1)
        run.addWidget(self.cancel)
        form.addRow(run)
        form.addRow(self.status)
        self.around.clicked.connect(self.full_resolution_around)
        self.radius.returnPressed.connect(self.full_resolution_around)
        self.back.clicked.connect(self.back_to_preview)
        self.whole.clicked.connect(self.whole_file_dialog)
        self.cancel.clicked.connect(self.job.cancel)
        self.job.progress.connect(self._progress)
        self.job.done.connect(lambda text: self._finished(text, False))
        self.job.failed.connect(lambda text: self._finished(text, True))
        self.job.running.connect(lambda running: self.sync())
        doc.mesh_changed.connect(self._on_mesh)
        doc.picked_changed.connect(lambda index: self.sync())
        self.sync()

    # -- the file behind what is shown ----------------------------------------------------------
    @property
    def large_path(self) -> str | None:
        source = self.doc.source
        return source.path if isinstance(source, (PreviewSource, FullResolutionSource)) else None

    # -- actions --------------------------------------------------------------------------------
    def full_resolution_around(self) -> None:
        """Open the file's points around the picked point at full resolution (module notes)."""
        doc = self.doc
        if self.large_path is None:
            return
        if doc.picked is None:
            self.message.emit("Pick a point in a pane first (click on the preview)", True)
            return
        if not self.radius.text().strip():
            self.radius.setText(f"{DEFAULT_RADIUS_UNITS * unit_length(doc.mesh):.3g}")
        try:
            radius = float(self.radius.text())
            if not radius > 0:
                raise ValueError
        except ValueError:
            self.message.emit(f"The radius must be a positive length; got {self.radius.text()!r}", True)
            return
        centre = tuple(float(v) for v in doc.mesh.vertices[doc.picked])
        jobs = tuple(pane_job(p) for p in doc.panes)
        self.controller.open_source(FullResolutionSource(self.large_path, centre=centre, radius=radius, jobs=jobs))
        self.message.emit(f"Reading {radius:g} around the pick at full resolution (the first time, the file is "
                          f"sorted into tiles)", False)

    def back_to_preview(self) -> None:
        if isinstance(self.doc.source, FullResolutionSource):
            self.controller.open_source(PreviewSource(self.doc.source.path))

    def whole_file_dialog(self) -> None:
        path = self.large_path or (getattr(self.doc.source, "path", None))
        if path is None or self.job.busy:
            return
        suffixes = whole_file_suffixes(path)
        pane = self.doc.panes[self.doc.active]
        stem = Path(path).stem
        suggested = str(Path(path).with_name(f"{stem}-{pane.method}{suffixes[0]}"))
        filters = ";;".join(f"{s.lstrip('.').upper()} (*{s})" for s in suffixes)
        out, _ = QFileDialog.getSaveFileName(self, "Whole file to", suggested, filters)
        if out:
            self.start_whole_file(out)

    def start_whole_file(self, output) -> None:
        """Estimate the active pane's call on the whole file into ``output`` (tiles, progress, Cancel)."""
        path = self.large_path or getattr(self.doc.source, "path", None)
        if path is None:
            return
        method, rng, keywords = pane_job(self.doc.panes[self.doc.active])
        self.job.start(path, output, method, rng, keywords)

    # -- model -> widgets ----------------------------------------------------------------------
    def _on_mesh(self, change) -> None:
        source = change.source
        if isinstance(source, FullResolutionSource) and source.ball is not None:
            show_region(self.doc, index_region(source.region_label, source.ball))
        if not isinstance(source, (PreviewSource, FullResolutionSource)):
            self.radius.clear()
        unit = "spacings" if change.mesh is not None and is_points(change.mesh) else "mean edge lengths"
        self.radius.setPlaceholderText(f"{DEFAULT_RADIUS_UNITS:g} {unit} of the preview")
        self.sync()

    def _progress(self, text: str, fraction: float) -> None:
        self.bar.setValue(int(1000 * max(0.0, min(1.0, fraction))))
        self.status.setText(text)

    def _finished(self, text: str, error: bool) -> None:
        self.status.setText(text)
        self.bar.setValue(0 if error else 1000)
        self.message.emit(text, error)
        self.sync()

    def sync(self) -> None:
        source = self.doc.source
        if isinstance(source, PreviewSource):
            self.shown.setText(f"Preview: {source.words}. Estimates here are the preview's; read a region at full "
                               f"resolution around a pick, or run the whole file to a file.")
        elif isinstance(source, FullResolutionSource):
            self.shown.setText(f"Full resolution: {source.label}. The panes are estimated at the points within the "
                               f"radius (the halo around them is grey).")
        else:
            self.shown.setText("The input is drawn whole.")
        large = self.large_path is not None
        self.around.setEnabled(large and self.doc.picked is not None and not self.job.busy)
        self.radius.setEnabled(large)
        self.back.setEnabled(isinstance(source, FullResolutionSource))
        path = getattr(source, "path", None)
        self.whole.setEnabled(path is not None and not self.job.busy)
        self.cancel.setEnabled(self.job.busy)
        self.bar.setVisible(self.job.busy)  # an idle bar reads as an empty field


def attach_large_panel(window) -> LargePanel:
    """Add the Large file dock to ``window`` (a :class:`~app.views.main_window.MainWindow`) beside the
    Region dock, and route its messages to the status bar; the Region dock's *Around picked vertex*
    reads at full resolution when a preview is shown."""
    from PySide6.QtCore import Qt
    from PySide6.QtWidgets import QDockWidget, QScrollArea

    panel = LargePanel(window.doc, window.controller)
    dock = QDockWidget("Large file", window)
    dock.setObjectName("dock_large")
    scroll = QScrollArea()
    scroll.setWidgetResizable(True)
    scroll.setWidget(panel)
    dock.setWidget(scroll)
    window.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, dock)
    if "region" in window.docks:
        window.tabifyDockWidget(window.docks["region"], dock)
    if "mesh" in window.docks:
        # a tabified dock comes to the front; a first run shows the mesh report there
        window.docks["mesh"].raise_()
    window.docks["large"] = dock
    panel.message.connect(lambda text, error: window.statusBar().showMessage(text, 8000))
    region = getattr(window, "region_panel", None)
    if region is not None:
        def around() -> bool:
            if not isinstance(window.doc.source, PreviewSource):
                return False
            if not panel.radius.text().strip() and region.radius.text().strip():
                panel.radius.setText(region.radius.text())
            panel.full_resolution_around()
            return True

        region.around_hook = around
    return panel
