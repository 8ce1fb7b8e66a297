"""The main window: viewports in the centre, docks for source / inspect / compare / readout,
a status bar with progress and Cancel, menus for files and export."""

from __future__ import annotations

from pathlib import Path

import curv
import numpy as np
from PySide6.QtCore import QSettings, Qt, Signal
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (
    QDockWidget, QFileDialog, QLabel, QMainWindow, QMessageBox, QProgressBar, QPushButton, QScrollArea,
)

from app.controller import Controller
from app.model import Document, FileSource, Layer, Pane, SurfaceSource, colormap_names
from app.model.colour import map_colours

from .compare_panel import ComparePanel
from .geometry import direction_glyphs, glyph_subsample, prepare_geometry
from .inspect_panel import InspectPanel
from .pane_grid import PaneGrid
from .readout import Readout
from .source_panel import SourcePanel

__all__ = ["MainWindow", "MESH_FILTER", "DEFAULT_SOURCE"]

MESH_FILTER = "Meshes (*.ply *.obj *.stl *.off *.gltf *.glb *.3mf);;All files (*)"
DEFAULT_SOURCE = SurfaceSource(name="saddle", n_vertices=3169)
MAX_RECENT = 8


class MainWindow(QMainWindow):
    """The curvlab window.

    Parameters
    ----------
    settings : QSettings, optional
        Where the last directory, colour maps, recent files and layout persist (default: the
        user's ``curvlab`` settings).
    """

    error_shown = Signal(str)
    """Emitted with every error message shown to the user."""

    def __init__(self, *, settings: QSettings | None = None) -> None:
        super().__init__()
        self.setWindowTitle("curvlab")
        self.setAcceptDrops(True)
        self.settings = settings if settings is not None else QSettings("curvlab", "curvlab")
        self.quiet = False
        self.pending_layer: Layer | None = None
        names = [n for n in ("mru", "nc", "qs", "meyer", "ru", "an", "csm") if n in curv.ESTIMATORS]
        defaults = tuple(Pane(n, 2 if 2 in curv.ESTIMATORS[n].ranges else curv.ESTIMATORS[n].ranges[0])
                         for n in names)
        self.doc = Document(default_panes=defaults)
        self.controller = Controller(self.doc, self, prepare=prepare_geometry)
        self.grid = PaneGrid(self)
        self.setCentralWidget(self.grid)
        self._glyph_index = None

        self.source_panel = SourcePanel()
        self.inspect = InspectPanel(self.doc)
        self.compare = ComparePanel(self.doc)
        self.readout = Readout(self.doc)
        self.docks = {}
        for key, title, widget, area in [
            ("source", "Source", self.source_panel, Qt.DockWidgetArea.LeftDockWidgetArea),
            ("inspect", "Inspect", self.inspect, Qt.DockWidgetArea.RightDockWidgetArea),
            ("compare", "Compare", self.compare, Qt.DockWidgetArea.LeftDockWidgetArea),
            ("readout", "Picked vertex", self.readout, Qt.DockWidgetArea.RightDockWidgetArea),
        ]:
            dock = QDockWidget(title, self)
            dock.setObjectName(f"dock_{key}")
            scroll = QScrollArea()
            scroll.setWidgetResizable(True)
            scroll.setWidget(widget)
            scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
            scroll.setMinimumWidth(widget.minimumSizeHint().width() + 20)
            dock.setWidget(scroll)
            self.addDockWidget(area, dock)
            self.docks[key] = dock
        self.resizeDocks([self.docks["source"], self.docks["inspect"]], [270, 330], Qt.Orientation.Horizontal)
        self.resizeDocks([self.docks["source"], self.docks["compare"]], [330, 120], Qt.Orientation.Vertical)
        self.resizeDocks([self.docks["inspect"], self.docks["readout"]], [560, 200], Qt.Orientation.Vertical)

        self.status_label = QLabel()
        self.progress = QProgressBar()
        self.progress.setMaximumWidth(220)
        self.progress.setRange(0, 100)
        self.cancel_button = QPushButton("Cancel")
        self.statusBar().addWidget(self.status_label, 1)
        self.statusBar().addPermanentWidget(self.progress)
        self.statusBar().addPermanentWidget(self.cancel_button)
        self._set_busy(False)
        self._build_menus()
        self._connect()
        self._restore_settings()

    # -- set-up ---------------------------------------------------------------------------------
    def _build_menus(self) -> None:
        file_menu = self.menuBar().addMenu("&File")
        self.action_open = QAction("&Open…", self, shortcut=QKeySequence.StandardKey.Open,
                                   triggered=self.open_dialog)
        self.recent_menu = file_menu.addMenu("Open &Recent")
        self.action_export_ply = QAction("Export coloured &PLY…", self, triggered=self.export_ply_dialog)
        self.action_export_png = QAction("Export &screenshot…", self, triggered=self.export_png_dialog)
        self.action_quit = QAction("&Quit", self, shortcut=QKeySequence.StandardKey.Quit, triggered=self.close)
        file_menu.insertAction(self.recent_menu.menuAction(), self.action_open)
        file_menu.addSeparator()
        file_menu.addActions([self.action_export_ply, self.action_export_png])
        file_menu.addSeparator()
        file_menu.addAction(self.action_quit)
        view_menu = self.menuBar().addMenu("&View")
        view_menu.addAction(QAction("&Reset camera", self, shortcut="R", triggered=self.grid.reset_camera))
        view_menu.addSeparator()
        for dock in self.docks.values():
            view_menu.addAction(dock.toggleViewAction())
        self._update_recent_menu()

    def _connect(self) -> None:
        doc, ctl = self.doc, self.controller
        doc.mesh_changed.connect(self._on_mesh)
        doc.panes_changed.connect(self._on_panes)
        doc.pane_changed.connect(self._on_pane)
        doc.result_changed.connect(lambda key: self.redraw())
        doc.display.changed.connect(self._on_display)
        doc.picked_changed.connect(self._on_picked)
        ctl.busy_changed.connect(self._set_busy)
        ctl.progress.connect(self._on_progress)
        ctl.message.connect(lambda text: self.show_status(text))
        ctl.failed.connect(self.show_error)
        self.cancel_button.clicked.connect(ctl.cancel)
        self.source_panel.source_requested.connect(ctl.open_source)
        self.source_panel.open_requested.connect(self.open_dialog)
        self.inspect.recompute_requested.connect(lambda: ctl.recompute(doc.panes[doc.active].key))
        self.compare.link_toggled.connect(self.grid.set_linked)
        self.grid.activated.connect(lambda i: doc.set_active(i) if i < len(doc.panes) else None)
        self.grid.vertex_picked.connect(doc.set_picked)

    # -- sources --------------------------------------------------------------------------------
    def open_path(self, path) -> None:
        """Load a mesh file in the background (the current scene stays until it succeeds)."""
        path = str(Path(path).expanduser())
        self.settings.setValue("last_dir", str(Path(path).resolve().parent))
        self.controller.open_source(FileSource(path))

    def open_surface(self, source: SurfaceSource) -> None:
        """Mesh an analytic surface in the background and show it in the source panel."""
        self.source_panel.set_source(source)
        self.controller.open_source(source)

    def open_source_then(self, source) -> None:
        """Open a :class:`FileSource` or :class:`SurfaceSource`."""
        if isinstance(source, FileSource):
            self.open_path(source.path)
        else:
            self.open_surface(source)

    def open_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open mesh", self.settings.value("last_dir", ""), MESH_FILTER)
        if path:
            self.open_path(path)

    def dragEnterEvent(self, event) -> None:  # noqa: N802 (Qt API)
        if any(u.isLocalFile() for u in event.mimeData().urls()):
            event.acceptProposedAction()

    def dropEvent(self, event) -> None:  # noqa: N802
        files = [u.toLocalFile() for u in event.mimeData().urls() if u.isLocalFile()]
        if files:
            self.open_path(files[0])
            event.acceptProposedAction()

    def _add_recent(self, path: str) -> None:
        recent = [p for p in self._recent() if p != path]
        self.settings.setValue("recent", [path, *recent][:MAX_RECENT])
        self._update_recent_menu()

    def _recent(self) -> list[str]:
        value = self.settings.value("recent", [])
        return [value] if isinstance(value, str) else list(value or [])

    def _update_recent_menu(self) -> None:
        self.recent_menu.clear()
        for path in self._recent():
            self.recent_menu.addAction(path, lambda p=path: self.open_path(p))
        self.recent_menu.setEnabled(bool(self._recent()))

    # -- model events ---------------------------------------------------------------------------
    def _on_mesh(self) -> None:
        doc = self.doc
        if isinstance(doc.source, FileSource):
            self._add_recent(str(Path(doc.source.path).resolve()))
        prepared = self.controller.prepared  # built in the worker; rebuilt here only if missing
        base, edge = prepared if prepared is not None else prepare_geometry(doc.mesh)
        self.grid.set_geometry(base, edge_length=edge)
        self._glyph_index = glyph_subsample(doc.mesh.n_vertices, count=min(1500, max(doc.mesh.n_vertices // 6, 1)))
        self.setWindowTitle(f"curvlab — {doc.source.label}")
        if isinstance(doc.source, SurfaceSource):
            self.source_panel.set_source(doc.source)
        layer, self.pending_layer = self.pending_layer, None
        if layer is not None and layer.needs_truth and doc.truth is None:
            self.show_error(f"{layer.title} needs an analytic source; {doc.source.label} has no exact curvature")
        elif layer is not None:
            doc.display.update(layer=layer)
        self.redraw()

    def _on_panes(self) -> None:
        self.grid.set_count(self.doc.view_count)
        self.controller.request_missing()
        self.redraw()
        self._on_picked(self.doc.picked)

    def _on_pane(self, i: int) -> None:
        self.controller.request_missing()
        if self.doc.panes[i].key in self.doc.results:
            self.redraw()
        else:  # keep the old colours on screen until the new result arrives
            self.update_titles()

    def _on_display(self, names: set) -> None:
        for key in names & {"diverging_cmap", "sequential_cmap"}:
            self.settings.setValue(f"cmap/{key}", getattr(self.doc.display, key))
        self.redraw()

    def _on_picked(self, index) -> None:
        point = None if index is None else self.doc.mesh.vertices[index]
        for vp in self.grid.viewports:
            vp.set_marker(point)
        self.grid.render_all()

    # -- drawing --------------------------------------------------------------------------------
    def redraw(self) -> None:
        """Recolour every viewport in place from the document and render."""
        doc = self.doc
        if doc.mesh is None:
            return
        fields = doc.fields()
        state = doc.display.state
        for i, (vp, field) in enumerate(zip(self.grid.viewports, fields)):
            vp.set_active(i == doc.active and len(doc.panes) > 1)
            title = self._field_title(i)
            if field is None:
                vp.set_colours(None)
            else:
                values, clim, cmap = field
                map_colours(values, clim, cmap, out=vp.colours)
                vp.set_colours(vp.colours, clim=clim, cmap=cmap, title=title)
            res = doc.result(i) if i < len(doc.panes) else None
            if state.show_directions and res is not None:
                vp.set_glyphs(direction_glyphs(doc.mesh.vertices, res, length=1.6 * doc.mesh.mean_edge_length,
                                               index=self._glyph_index))
            else:
                vp.set_glyphs(None)
        self.update_titles()
        self.grid.render_all()
        res = doc.result(doc.active)
        self.inspect.show_values(fields[doc.active] if fields else None, table=doc.cmap(doc.active).table,
                                 n_invalid=None if res is None else int((~res.valid).sum()),
                                 n_vertices=doc.mesh.n_vertices)

    def update_titles(self) -> None:
        """Pane headers: estimator and status; no re-render needed."""
        for i, vp in enumerate(self.grid.viewports[:self.doc.view_count]):
            vp.set_title(self._pane_title(i), status=self._pane_message(i))

    def _pane_title(self, i: int) -> str:
        doc = self.doc
        if doc.is_difference(i):
            return f"A − B: {doc.panes[0].method} R{doc.panes[0].range} − {doc.panes[1].method} R{doc.panes[1].range}"
        pane = doc.panes[i]
        spec = curv.ESTIMATORS.get(pane.method)
        return f"{chr(65 + i)}: {pane.method} R{pane.range}" + (f" — {spec.title}" if spec else "")

    def _field_title(self, i: int) -> str:
        st = self.doc.display.state
        name = "e_rel" if st.layer is Layer.E_REL else st.quantity.title
        if st.layer is Layer.ERROR:
            name += " error"
        elif st.layer is Layer.EXACT:
            name += " (exact)"
        return ("A − B " if self.doc.is_difference(i) else "") + name

    def _pane_message(self, i: int) -> str:
        doc = self.doc
        if doc.is_difference(i):
            return ""
        key = doc.panes[i].key
        if key in doc.failures:
            return doc.failures[key]
        if key in self.controller.running_keys():
            return "computing…"
        return ""

    # -- status ---------------------------------------------------------------------------------
    def show_status(self, text: str, *, error: bool = False) -> None:
        self.status_label.setStyleSheet("color: #b00020;" if error else "")
        self.status_label.setText(text)

    def show_error(self, text: str) -> None:
        """Report a failure in the status bar and in a non-blocking dialog."""
        self.show_status(text, error=True)
        self.redraw()
        self.error_shown.emit(text)
        if self.isVisible() and not self.quiet:
            box = QMessageBox(QMessageBox.Icon.Warning, "curvlab", text, parent=self)
            box.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
            box.open()

    def _set_busy(self, busy: bool) -> None:
        self.progress.setVisible(busy)
        self.cancel_button.setVisible(busy)
        self.update_titles()

    def _on_progress(self, label: str, fraction: float) -> None:
        if fraction < 0:
            self.progress.setRange(0, 0)
        else:
            self.progress.setRange(0, 100)
            self.progress.setValue(int(round(100 * fraction)))
        self.progress.setFormat(f"%p%")
        self.progress.setToolTip(label)
        self.show_status(label + "…")

    # -- export ---------------------------------------------------------------------------------
    def export_ply(self, path) -> Path:
        """Write the active pane as a coloured PLY: its colours exactly as shown plus the curvature
        properties, and for an analytic source ``error_rel``, ``error_<q>`` and ``exact_<q>``."""
        doc = self.doc
        res = doc.result(doc.active)
        if res is None:
            raise RuntimeError("the active pane has no result to export yet")
        q = doc.display.quantity.value
        extra = {}
        if doc.truth is not None:
            from app.model.errors import relative_error
            extra = {"error_rel": relative_error(res, doc.truth),
                     f"error_{q}": res.quantity(q) - doc.truth.quantity(q),
                     f"exact_{q}": doc.truth.quantity(q)}
        colours = np.array(self.grid.viewports[doc.active].colours, dtype=np.uint8)
        return curv.save_ply(path, doc.mesh, res, quantity=q, colors=colours, extra=extra)

    def export_png(self, path) -> Path:
        """Save an image of the viewports (all panes) as PNG."""
        self.grid.render_all()
        image = self.grid.grab()
        if not image.save(str(path), "PNG"):
            raise OSError(f"could not write {path}")
        return Path(path)

    def export_ply_dialog(self) -> None:
        self._export_dialog("Export coloured PLY", "PLY (*.ply)", ".ply", self.export_ply)

    def export_png_dialog(self) -> None:
        self._export_dialog("Export screenshot", "PNG (*.png)", ".png", self.export_png)

    def _export_dialog(self, title, filt, suffix, writer) -> None:
        path, _ = QFileDialog.getSaveFileName(self, title, self.settings.value("last_dir", ""), filt)
        if not path:
            return
        path = path if path.endswith(suffix) else path + suffix
        try:
            writer(path)
        except Exception as exc:  # report, never lose the session
            self.show_error(f"Export failed: {exc}")
            return
        self.settings.setValue("last_dir", str(Path(path).parent))
        self.show_status(f"Wrote {path}")

    # -- settings and shutdown ------------------------------------------------------------------
    def _restore_settings(self) -> None:
        s = self.settings
        geometry, state = s.value("geometry"), s.value("state")
        if geometry is not None:
            self.restoreGeometry(geometry)
        if state is not None:
            self.restoreState(state)
        changes = {}
        for key, kind in (("diverging_cmap", "diverging"), ("sequential_cmap", "sequential")):
            value = s.value(f"cmap/{key}")
            if value and str(value) in colormap_names(kind):
                changes[key] = str(value)
        self.doc.display.update(**changes)

    def closeEvent(self, event) -> None:  # noqa: N802
        """Stop the workers, save the layout, release the render windows."""
        self.controller.shutdown(timeout_ms=5000)
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("state", self.saveState())
        self.settings.sync()
        self.grid.close_all()
        super().closeEvent(event)
