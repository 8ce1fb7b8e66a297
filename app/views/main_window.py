"""The main window: viewports in the centre, docks for source / mesh / compare / advice (left) and
inspect / picked vertex (right), a status bar with progress and Cancel, menus (:mod:`.menus`).

The window wires the parts together and shows what the model says; drawing is
:class:`~.drawing.Drawing`'s, the exports' dialogs :class:`~.exporting.Exports`', and the work
(loading, estimating, writing files, finding edges) the controller's.
"""

from __future__ import annotations

import time
from pathlib import Path

from PySide6.QtCore import QEvent, QSettings, Qt, Signal
from PySide6.QtGui import QGuiApplication, QIcon
from PySide6.QtWidgets import (
    QApplication, QDialog, QDialogButtonBox, QDockWidget, QFileDialog, QLabel, QMainWindow, QMessageBox,
    QProgressBar, QPushButton, QScrollArea, QTextBrowser, QVBoxLayout,
)

from app.controller import Controller
from app.model import Document, FileSource, Layer, MeshChange, Pane, SurfaceSource, default_panes, pane_letter
from app.model.camera import UpAxis, View, first_view
from app.packaged import resource

from .advice_panel import AdvicePanel
from .compare_panel import ComparePanel
from .drawing import GLYPH_PIXELS, GREY_FRAME_DELAY_MS, Drawing
from .exporting import Exports
from .feature_controls import FeatureControl
from .geometry import prepare_geometry
from .help import about_text, guide_text
from .inspect_panel import InspectPanel
from .large_panel import attach_large_panel
from .menus import ADVISE_POINTS_TIP, ADVISE_TIP, WindowShortcuts, build_menus
from .mesh_panel import MeshPanel
from .pane_grid import PaneGrid
from .readout import Readout
from .region_panel import RegionPanel
from .session import restore_session, save_session
from .source_panel import SourcePanel
from .window_size import fit_to_screen, screen_room

__all__ = ["MainWindow", "MESH_FILTER", "DEFAULT_SOURCE", "GLYPH_PIXELS", "GREY_FRAME_DELAY_MS"]

MESH_FILTER = ("Meshes and point clouds (*.ply *.obj *.stl *.off *.gltf *.glb *.3mf *.xyz *.txt *.csv *.pcd *.pts *.las *.laz);;"
               "Meshes (*.ply *.obj *.stl *.off *.gltf *.glb *.3mf);;"
               "Point clouds (*.ply *.xyz *.txt *.csv *.pcd *.pts *.las *.laz);;All files (*)")
DEFAULT_SOURCE = SurfaceSource(name="saddle", n_vertices=3169)
MAX_RECENT = 8


class BusyBar(QProgressBar):
    """The status bar's progress bar; its busy animation (unknown progress) repaints
    :data:`BUSY_FRAMES_PER_S` times a second instead of the style's 60.

    Under software GL every repaint of a window that holds a 3D view composes the whole window:
    the style's animation took 30 % of a core (0.3 s of CPU a second, measured under Xvfb) from the
    loading and estimating it was showing.
    """

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self._last_frame = 0.0

    def event(self, event) -> bool:  # noqa: D102 (Qt API)
        if event.type() == QEvent.Type.StyleAnimationUpdate:
            event.accept()  # keeps the animation running; it is drawn at the slower rate
            now = time.monotonic()
            if now - self._last_frame >= 1.0 / BUSY_FRAMES_PER_S:
                self._last_frame = now
                self.update()
            return True
        return super().event(event)


BUSY_FRAMES_PER_S = 2


class MainWindow(QMainWindow):
    """The curvlab window.

    Parameters
    ----------
    settings : QSettings, optional
        Where the last directory, colour maps, recent files, panes, limits and layout persist
        (default: the user's ``curvlab`` settings).
    """

    error_shown = Signal(str)
    """Emitted with every error message shown to the user."""

    def __init__(self, *, settings: QSettings | None = None) -> None:
        super().__init__()
        self.setWindowTitle("curvlab")
        try:
            self.setWindowIcon(QIcon(str(resource("curvlab.svg"))))
        except FileNotFoundError:
            pass
        self.setAcceptDrops(True)
        self.settings = settings if settings is not None else QSettings("curvlab", "curvlab")
        self.quiet = False
        self.pending_layer: Layer | None = None
        self.doc = Document(default_panes=default_panes())
        self.controller = Controller(self.doc, self, prepare=prepare_geometry)
        self.grid = PaneGrid(self)
        self.setCentralWidget(self.grid)
        self.exports = Exports(self)

        self.source_panel = SourcePanel()
        self.inspect = InspectPanel(self.doc)
        self.compare = ComparePanel(self.doc)
        self.mesh_panel = MeshPanel(self.doc)
        self.readout = Readout(self.doc)
        self.advice_panel = AdvicePanel(self.doc)
        self.feature_control = FeatureControl(self.doc)
        self.inspect.pane_form.insertRow(3, "", self.feature_control)  # under the range and radius
        self.region_panel = RegionPanel(self.doc, self.grid)
        self.drawing = Drawing(self.doc, self.grid, self.controller, self.inspect, self)
        self.docks = {}
        for key, title, widget, area in [
            ("source", "Source", self.source_panel, Qt.DockWidgetArea.LeftDockWidgetArea),
            ("mesh", "Mesh report", self.mesh_panel, Qt.DockWidgetArea.LeftDockWidgetArea),
            ("compare", "Compare", self.compare, Qt.DockWidgetArea.LeftDockWidgetArea),
            ("advice", "Advice", self.advice_panel, Qt.DockWidgetArea.LeftDockWidgetArea),
            ("region", "Region", self.region_panel, Qt.DockWidgetArea.LeftDockWidgetArea),
            ("inspect", "Inspect", self.inspect, Qt.DockWidgetArea.RightDockWidgetArea),
            ("readout", "Picked vertex", self.readout, Qt.DockWidgetArea.RightDockWidgetArea),
        ]:
            dock = QDockWidget(title, self)
            dock.setObjectName(f"dock_{key}")
            scroll = QScrollArea()
            scroll.setWidgetResizable(True)
            scroll.setWidget(widget)
            scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
            scroll.setMinimumWidth(min(widget.minimumSizeHint().width() + 20, 360))
            dock.setWidget(scroll)
            self.addDockWidget(area, dock)
            self.docks[key] = dock
        self.tabifyDockWidget(self.docks["mesh"], self.docks["compare"])
        self.tabifyDockWidget(self.docks["compare"], self.docks["advice"])
        self.tabifyDockWidget(self.docks["advice"], self.docks["region"])
        self.docks["mesh"].raise_()  # first run: the mesh's report in front, Compare and Advice behind

        self.status_label = QLabel()
        self.status_label.setMinimumWidth(0)
        self.progress = BusyBar()
        self.progress.setMaximumWidth(220)
        self.progress.setRange(0, 100)
        self.cancel_button = QPushButton("Cancel")
        # clicking Cancel (or its disappearing) must not move the keyboard focus
        self.cancel_button.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.cancel_button.setToolTip("Stop the running work (Esc)")
        self.statusBar().addWidget(self.status_label, 1)
        self.statusBar().addPermanentWidget(self.progress)
        self.statusBar().addPermanentWidget(self.cancel_button)
        self._set_busy(False)
        build_menus(self)
        self._update_recent_menu()
        self._shortcuts = WindowShortcuts(self)
        QApplication.instance().installEventFilter(self._shortcuts)
        self._connect()
        self.large_panel = attach_large_panel(self)
        self._restore_settings()

    def _connect(self) -> None:
        doc, ctl = self.doc, self.controller
        doc.mesh_changed.connect(self._on_mesh)
        doc.panes_changed.connect(self._on_panes)
        doc.pane_changed.connect(self._on_pane)
        doc.result_changed.connect(self._on_result)
        doc.display.changed.connect(self._on_display)
        doc.picked_changed.connect(self._on_picked)
        ctl.busy_changed.connect(self._set_busy)
        ctl.progress.connect(self._on_progress)
        ctl.message.connect(lambda text: self.show_status(text))
        ctl.failed.connect(self.show_error)
        ctl.advising.connect(self.advice_panel.set_running)
        ctl.advice_progress.connect(self.advice_panel.set_progress)
        self.advice_panel.cancel_requested.connect(ctl.cancel_advice)
        doc.advice_changed.connect(lambda record: self.show_dock("advice"))
        self.advice_panel.apply_requested.connect(self.apply_pane)
        self.cancel_button.clicked.connect(ctl.cancel)
        self.source_panel.source_requested.connect(ctl.open_source)
        self.source_panel.open_requested.connect(self.open_dialog)
        self.mesh_panel.reload_requested.connect(ctl.open_source)
        self.inspect.recompute_requested.connect(lambda: ctl.recompute(doc.panes[doc.active].key))
        self.inspect.pane_requested.connect(lambda pane: ctl.compute_in_pane(doc.active, pane))
        self.inspect.message.connect(lambda text: self.show_status(text, error=True))
        self.region_panel.message.connect(lambda text, error: self.show_status(text, error=error))
        self.compare.link_toggled.connect(self.grid.set_linked)
        self.grid.activated.connect(lambda i: doc.set_active(i) if i < len(doc.panes) else None)
        self.grid.vertex_picked.connect(doc.set_picked)
        self.drawing.painter.failed.connect(self.show_error)

    # -- sources --------------------------------------------------------------------------------
    def open_path(self, path, *, repairs: tuple = (), loaded=None) -> None:
        """Load a mesh file in the background (the current scene stays until it succeeds); ``loaded``:
        its :func:`~app.controller.sources.preload`, already under way."""
        path = str(Path(path).expanduser())
        self.settings.setValue("last_dir", str(Path(path).resolve().parent))
        self.controller.open_source(FileSource(path, tuple(repairs)), loaded=loaded)

    def open_surface(self, source: SurfaceSource) -> None:
        """Mesh an analytic surface in the background and show it in the source panel."""
        self.source_panel.set_source(source)
        self.controller.open_source(source)

    def open_source_then(self, source, *, loaded=None) -> None:
        """Open a :class:`FileSource` (``loaded``: its preload, if started) or :class:`SurfaceSource`."""
        if isinstance(source, FileSource):
            self.open_path(source.path, repairs=source.repairs, loaded=loaded)
        else:
            self.open_surface(source)

    def open_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open mesh or point cloud", self.settings.value("last_dir", ""), MESH_FILTER)
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

    # -- advice ---------------------------------------------------------------------------------
    def advise(self) -> None:
        """Run the advisor on the shown mesh in the background; its panel shows the progress and the answer."""
        self.show_dock("advice")
        self.controller.advise()

    def apply_pane(self, pane: Pane) -> None:
        """Show ``pane``'s estimator and range in the active pane and compute it (the Advice panel's Apply)."""
        i = self.doc.active
        self.controller.compute_in_pane(i, pane)
        self.show_status(f"Pane {pane_letter(i)}: {pane.title}")

    def show_dock(self, key: str) -> None:
        """Show dock ``key`` and bring it to the front of its tab group.

        The Advice dock shares the left column with the Source dock: when shorter than 70 % of the
        column it grows to that, so that its summary, features and a good part of the ranking show.
        """
        dock = self.docks[key]
        dock.show()
        dock.raise_()
        source = self.docks["source"]
        if key == "advice" and not dock.isFloating() and source.isVisible() and not source.isFloating() \
                and self.dockWidgetArea(source) == self.dockWidgetArea(dock):
            column = source.height() + dock.height()
            wanted = int(0.7 * column)
            if dock.height() < wanted:
                self.resizeDocks([source, dock], [column - wanted, wanted], Qt.Orientation.Vertical)

    # -- model events ---------------------------------------------------------------------------
    def _on_mesh(self, change: MeshChange) -> None:
        doc = self.doc
        if isinstance(change.source, FileSource):
            self._add_recent(str(Path(change.source.path).resolve()))
        geometry = change.geometry if change.geometry is not None else prepare_geometry(change.mesh)
        self.drawing.new_mesh(geometry)
        view, up = first_view(points=doc.is_points, analytic=change.source.analytic,
                              georeferenced=geometry.georeferenced, up=self.up_axis())
        self._show_view(view, up, render=False)
        self.setWindowTitle(f"curvlab — {change.source.label}")
        points = doc.is_points
        self.docks["readout"].setWindowTitle("Picked point" if points else "Picked vertex")
        self.docks["mesh"].setWindowTitle("Point cloud report" if points else "Mesh report")
        # the advisor's table comes from the study's meshes: it has nothing to say about a point cloud
        self.action_advise.setEnabled(not points)
        self.action_advise.setToolTip(ADVISE_POINTS_TIP if points else ADVISE_TIP)
        if isinstance(change.source, SurfaceSource):
            self.source_panel.set_source(change.source)
        self.source_panel.show_current(change.source)
        layer, self.pending_layer = self.pending_layer, None
        if layer is not None and layer.needs_truth and change.truth is None:
            self.show_error(f"{layer.title} needs an analytic source; {change.source.label} has no exact curvature")
        elif layer is not None:
            doc.display.update(layer=layer)
        self.redraw()

    def _on_panes(self) -> None:
        self.grid.set_count(self.doc.view_count)
        self.drawing.forget_drawn()
        self.controller.request_missing()
        self.redraw()

    def _on_pane(self, i: int) -> None:
        self.controller.request_missing()
        if self.doc.panes[i].key in self.doc.results:
            self.redraw()
        else:  # keep the old colours on screen until the new result arrives
            self.drawing.update_titles()

    def _on_result(self, key) -> None:
        self.redraw()

    def _on_display(self, names: set) -> None:
        if "point_size" in names:
            self.grid.set_point_size(self.doc.display.state.point_size)
            if names == {"point_size"}:
                self.drawing.show_marker()  # the marker stays wider than the points
                self.grid.request_render()
                return
        self.redraw()

    def _on_picked(self, index) -> None:
        self.drawing.show_marker()

    # -- drawing and the camera -----------------------------------------------------------------
    def redraw(self, *, force: bool = False) -> None:
        """Bring the panes up to the document (:meth:`Drawing.redraw`)."""
        self.drawing.redraw(force=force)

    def update_titles(self) -> None:
        """Pane headers: estimator and status; no re-render needed."""
        self.drawing.update_titles()

    @property
    def grey_frames(self) -> bool:
        """Whether a new mesh is drawn grey while its estimates run (a scripted snapshot needs only
        the coloured frame)."""
        return self.drawing.grey_frames

    @grey_frames.setter
    def grey_frames(self, on: bool) -> None:
        self.drawing.grey_frames = bool(on)

    def up_axis(self) -> UpAxis:
        """The up axis chosen in the View menu (remembered), +y unless chosen otherwise."""
        try:
            return UpAxis(str(self.settings.value("view/up", UpAxis.Y.value)))
        except ValueError:
            return UpAxis.Y

    def set_view(self, view: View) -> None:
        """Look at the input from the standard ``view`` (the View menu) with the current up axis."""
        self._show_view(View(view), self.grid.up)

    def set_up_axis(self, up: UpAxis) -> None:
        """Draw ``up`` upwards from now on (remembered) and show the current view with it."""
        up = UpAxis(up)
        self.settings.setValue("view/up", up.value)
        self._show_view(self.grid.view, up)

    def _show_view(self, view: View, up: UpAxis, *, render: bool = True) -> None:
        self.grid.set_view(view, up, render=render)
        self.up_actions[up].setChecked(True)

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
        if hasattr(self, "action_cancel"):  # _set_busy runs once before the menus exist
            self.action_cancel.setEnabled(busy)
        self.update_titles()

    def _on_progress(self, label: str, fraction: float) -> None:
        if fraction < 0:
            self.progress.setRange(0, 0)
        else:
            self.progress.setRange(0, 100)
            self.progress.setValue(int(round(100 * fraction)))
        self.progress.setFormat("%p%")
        self.progress.setToolTip(label)
        self.show_status(label + "…")

    # -- help -------------------------------------------------------------------------------------
    def show_about(self) -> None:
        QMessageBox.about(self, "About curvlab", about_text())

    def show_guide(self) -> QDialog:
        """The guide in a scrolling dialog no taller than 80 % of the screen (non-blocking)."""
        box = QDialog(self)
        box.setWindowTitle("Estimators and ranges")
        box.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
        text = QTextBrowser(box)
        text.setHtml(guide_text())
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close, box)
        buttons.rejected.connect(box.close)
        lay = QVBoxLayout(box)
        lay.addWidget(text)
        lay.addWidget(buttons)
        screen = (self.screen() or QGuiApplication.primaryScreen()).availableGeometry()
        box.resize(min(820, int(0.9 * screen.width())), min(680, int(0.8 * screen.height())))
        box.open()
        return box

    # -- export ---------------------------------------------------------------------------------
    def export_ply(self, path) -> Path:
        """Write the active pane as a coloured PLY now (:meth:`Controller.export`): its colours exactly
        as shown, the curvature properties, the shown field and for an analytic source its errors."""
        return self.controller.export(path if str(path).lower().endswith(".ply") else f"{path}.ply",
                                      self.exports.colours())

    def export_vtu(self, path) -> Path:
        """Write the active pane as a VTK unstructured grid with the same point data (ParaView, pyvista)."""
        return self.controller.export(path if str(path).lower().endswith(".vtu") else f"{path}.vtu",
                                      self.exports.colours())

    def export_png(self, path) -> Path:
        """Save an image of the viewports (all panes) as PNG."""
        return self.exports.export_png(path)

    # -- settings and shutdown ------------------------------------------------------------------
    def fit_to(self, w: int, h: int) -> None:
        """Resize the window to ``w`` x ``h``, at most the room its screen has, and share it among the
        docks as on a first launch."""
        w, h = screen_room(self, w, h)
        self.resize(w, h)
        self.resizeDocks([self.docks["source"], self.docks["inspect"]], [int(w * 0.18), int(w * 0.23)],
                         Qt.Orientation.Horizontal)
        self.resizeDocks([self.docks["inspect"], self.docks["readout"]], [int(h * 0.72), int(h * 0.2)],
                         Qt.Orientation.Vertical)
        self.resizeDocks([self.docks["source"], self.docks["mesh"]], [int(h * 0.5), int(h * 0.4)],
                         Qt.Orientation.Vertical)

    def _restore_settings(self) -> None:
        geometry, state = self.settings.value("geometry"), self.settings.value("state")
        if geometry is None or not self.restoreGeometry(geometry):
            fit_to_screen(self)
        else:
            w, h = screen_room(self, self.width(), self.height())  # saved on a larger screen: fit this one
            if (w, h) != (self.width(), self.height()):
                fit_to_screen(self)
        if state is not None:
            self.restoreState(state)
        self.grid.up = self.up_axis()
        self.up_actions[self.grid.up].setChecked(True)
        restore_session(self.settings, self.doc)

    def _save_settings(self) -> None:
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("state", self.saveState())
        save_session(self.settings, self.doc)
        self.settings.sync()

    def closeEvent(self, event) -> None:  # noqa: N802
        """Stop the workers, save the layout and settings, release the render windows."""
        QApplication.instance().removeEventFilter(self._shortcuts)
        self.controller.shutdown(timeout_ms=5000)
        self._save_settings()
        self.grid.close_all()
        super().closeEvent(event)
