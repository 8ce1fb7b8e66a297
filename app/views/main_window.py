"""The main window: viewports in the centre, docks for source / mesh / compare / advice (left) and
inspect / picked vertex (right), a status bar with progress and Cancel, menus for files, export, view,
estimate and help."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from curv.estimators import ESTIMATORS
from curv.core.features import feature_edges
from curv.io import save_ply, save_vtu
from PySide6.QtCore import QEvent, QSettings, Qt, QTimer, Signal
from PySide6.QtGui import QAction, QGuiApplication, QIcon, QKeySequence
from PySide6.QtWidgets import (
    QDialog, QDialogButtonBox, QDockWidget, QFileDialog, QLabel, QMainWindow, QMessageBox, QProgressBar, QPushButton,
    QScrollArea, QTextBrowser, QVBoxLayout,
)

from app.controller import Controller
from app.model import (
    Document, FileSource, Layer, MeshChange, Pane, SurfaceSource, default_panes, export_payload, map_colours,
    pane_letter,
)
from app.model.region import REST_COLOUR, outside_region
from app.packaged import resource, sample_names

from .advice_panel import AdvicePanel
from .compare_panel import ComparePanel
from .feature_controls import FeatureControl
from .geometry import direction_glyphs, edge_lines, glyph_subsample, prepare_geometry
from .help import about_text, guide_text
from .inspect_panel import InspectPanel
from .large_panel import attach_large_panel
from .mesh_panel import MeshPanel
from .pane_grid import PaneGrid
from .readout import Readout
from .region_panel import RegionPanel
from .session import restore_session, save_session
from .source_panel import SourcePanel

__all__ = ["MainWindow", "MESH_FILTER", "DEFAULT_SOURCE"]

MESH_FILTER = ("Meshes and point clouds (*.ply *.obj *.stl *.off *.gltf *.glb *.3mf *.xyz *.txt *.csv *.pcd *.pts *.las *.laz);;"
               "Meshes (*.ply *.obj *.stl *.off *.gltf *.glb *.3mf);;"
               "Point clouds (*.ply *.xyz *.txt *.csv *.pcd *.pts *.las *.laz);;All files (*)")
DEFAULT_SOURCE = SurfaceSource(name="saddle", n_vertices=3169)
ADVISE_TIP = ("Measure this mesh's noise, irregularity and density and rank the estimators and ranges by the "
              "error the paper's study predicts; Apply in the Advice panel uses one (Ctrl+Shift+A)")
ADVISE_POINTS_TIP = "The advisor ranks estimators for meshes (its table comes from the study's meshes), not point clouds"
MAX_RECENT = 8
GLYPH_PIXELS = 900
"""One direction glyph per this many pixels of a pane at most, so glyphs never bury the colours."""
GREY_FRAME_DELAY_MS = 1000
"""A new mesh is first drawn grey only if its estimates have not arrived this long after it: a
frame of a large mesh takes seconds of the GUI thread under software GL, and the coloured frame
replaces it anyway."""


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
        self._geometry = None
        self._drawn = None  # what the viewports show (see _scene): unchanged scenes are not re-rendered
        self.grey_frames = True
        """Whether a new mesh is drawn grey while its estimates run (after GREY_FRAME_DELAY_MS);
        a scripted snapshot needs only the coloured frame."""
        self._first_frame_due = False
        self._grey_timer = QTimer(self, singleShot=True, interval=GREY_FRAME_DELAY_MS)
        self._grey_timer.timeout.connect(self._grey_frame)

        self.source_panel = SourcePanel()
        self.inspect = InspectPanel(self.doc)
        self.compare = ComparePanel(self.doc)
        self.mesh_panel = MeshPanel(self.doc)
        self.readout = Readout(self.doc)
        self.advice_panel = AdvicePanel(self.doc)
        self.feature_control = FeatureControl(self.doc)
        self.inspect.pane_form.insertRow(3, "", self.feature_control)  # under the range and radius
        self.region_panel = RegionPanel(self.doc, self.grid)
        self._feature_lines: dict = {}  # feature angle -> lines of the shown mesh
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
        self._build_menus()
        self._connect()
        self.large_panel = attach_large_panel(self)
        self._restore_settings()

    # -- set-up ---------------------------------------------------------------------------------
    def _build_menus(self) -> None:
        file_menu = self.menuBar().addMenu("&File")
        self.action_open = QAction("&Open…", self, shortcut=QKeySequence.StandardKey.Open,
                                   triggered=self.open_dialog)
        self.recent_menu = file_menu.addMenu("Open &Recent")
        self.sample_menu = file_menu.addMenu("Open &Sample")
        for name in sample_names():
            self.sample_menu.addAction(name, lambda n=name: self.open_path(str(resource(f"samples/{n}"))))
        self.action_export_ply = QAction("Export coloured &PLY…", self, shortcut="Ctrl+E",
                                         triggered=self.export_ply_dialog)
        self.action_export_vtu = QAction("Export &VTK (.vtu) for ParaView…", self, shortcut="Ctrl+Shift+E",
                                         triggered=self.export_vtu_dialog)
        self.action_export_png = QAction("Export &screenshot (PNG)…", self, shortcut="Ctrl+Shift+S",
                                         triggered=self.export_png_dialog)
        self.action_quit = QAction("&Quit", self, shortcut=QKeySequence.StandardKey.Quit, triggered=self.close)
        file_menu.insertAction(self.recent_menu.menuAction(), self.action_open)
        file_menu.addSeparator()
        file_menu.addActions([self.action_export_ply, self.action_export_vtu, self.action_export_png])
        file_menu.addSeparator()
        file_menu.addAction(self.action_quit)
        view_menu = self.menuBar().addMenu("&View")
        self.action_reset_camera = QAction("&Reset camera", self, shortcut="R", triggered=self.grid.reset_camera)
        view_menu.addAction(self.action_reset_camera)
        view_menu.addSeparator()
        for dock in self.docks.values():
            view_menu.addAction(dock.toggleViewAction())
        est_menu = self.menuBar().addMenu("&Estimate")
        self.action_recompute = QAction("&Recompute active pane", self, shortcut="F5",
                                        triggered=lambda: self.controller.recompute(self.doc.panes[self.doc.active].key))
        self.action_cancel = QAction("&Cancel", self, shortcut="Esc", triggered=self.controller.cancel)
        self.action_advise = QAction("&Advise estimator and range", self, shortcut="Ctrl+Shift+A",
                                     triggered=self.advise)
        self.action_advise.setIconText("Advise")
        self.action_advise.setToolTip(ADVISE_TIP)
        self.action_advise.setStatusTip("Rank the estimators and ranges for this mesh")
        est_menu.addActions([self.action_recompute, self.action_advise, self.action_cancel])
        self.inspect.advise_button.setDefaultAction(self.action_advise)
        self.advice_panel.advise_button.setDefaultAction(self.action_advise)
        help_menu = self.menuBar().addMenu("&Help")
        help_menu.addAction(QAction("Estimators and ranges…", self, shortcut=QKeySequence.StandardKey.HelpContents,
                                    triggered=self.show_guide))
        help_menu.addAction(QAction("&About curvlab", self, triggered=self.show_about))
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
        self._geometry = change.geometry if change.geometry is not None else prepare_geometry(change.mesh)
        self.grid.set_point_size(doc.display.state.point_size)
        self.grid.set_geometry(self._geometry.base, points=self._geometry.points_only)
        self._drawn = None
        self._first_frame_due = True
        self._feature_lines = {}
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
        self._drawn = None
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
        if "point_size" in names:
            self.grid.set_point_size(self.doc.display.state.point_size)
            for vp in self.grid.viewports:  # the marker stays wider than the points
                vp.set_marker(None if self.doc.picked is None else self.doc.mesh.vertices[self.doc.picked])
            if names == {"point_size"}:
                self.grid.render_all()
                return
        self.redraw()

    def _on_picked(self, index) -> None:
        point = None if index is None or self.doc.mesh is None else self.doc.mesh.vertices[index]
        for vp in self.grid.viewports:
            vp.set_marker(point)
        self.grid.render_all()

    # -- drawing --------------------------------------------------------------------------------
    def _scene(self) -> tuple:
        """Everything the viewports' pixels depend on (results by identity)."""
        doc = self.doc
        results = tuple(id(doc.results.get(p.key)) for p in doc.panes)
        return (id(doc.mesh), tuple(doc.panes), results, doc.view_count, doc.active, doc.picked,
                doc.display.state, len(self.grid.viewports))

    def redraw(self, *, force: bool = False) -> None:
        """Recolour every viewport in place from the document and render.

        A scene that is already on screen is not recoloured or rendered again (only the titles
        are updated): cancelling an estimate reverts the pane to the result it still shows, and
        must not stall the GUI on a render of a large mesh.
        """
        doc = self.doc
        if doc.mesh is None:
            return
        if self._first_frame_due and not force and self.controller.running_keys() \
                and all(doc.result(i) is None for i in range(len(doc.panes))):
            # a new mesh whose estimates run: the coloured frame is its first, unless they take long
            if self.grey_frames and not self._grey_timer.isActive():
                self._grey_timer.start()
            self.update_titles()
            return
        self._first_frame_due = False
        self._grey_timer.stop()
        scene = self._scene()
        if not force and scene == self._drawn:
            self.update_titles()
            return
        self._drawn = scene
        fields = doc.fields()
        state = doc.display.state
        for i, (vp, field) in enumerate(zip(self.grid.viewports, fields)):
            vp.set_active(i == doc.active and len(doc.panes) > 1, difference=doc.is_difference(i))
            title = state.field_title(difference=doc.is_difference(i))
            if field is None:
                vp.set_colours(None)
            else:
                values, clim, cmap = field
                map_colours(values, clim, cmap, out=vp.colours)
                outside = outside_region(doc.result(i), doc.panes[i].region) if i < len(doc.panes) else None
                if outside is not None:
                    vp.colours[outside] = REST_COLOUR
                vp.set_colours(vp.colours, clim=clim, cmap=cmap, title=title)
            res = doc.result(i) if i < len(doc.panes) else None
            if state.show_directions and res is not None:
                w, h = vp.plotter.width(), vp.plotter.height()
                count = int(min(1500, max(doc.mesh.n_vertices // 6, 1), max(w * h // GLYPH_PIXELS, 50)))
                length, lift = 1.6 * self._geometry.edge_length, None
                if doc.is_points:  # glyphs as long as their own spacing, floating above the points' spheres
                    length = 0.8 * self._geometry.edge_length * np.sqrt(doc.mesh.n_vertices / count)
                    lift = (0.5 * state.point_size + 1.0) * vp.pixel_length()
                vp.set_glyphs(direction_glyphs(doc.mesh.vertices, res, length=length, lift=lift,
                                               index=glyph_subsample(doc.mesh.n_vertices, count=count)))
            else:
                vp.set_glyphs(None)
            mesh = not doc.is_points  # a point cloud has no edges, and is drawn as points already
            vp.set_overlays(edges=state.show_edges and mesh, points=state.show_points and mesh,
                            borders=self._geometry.borders if state.show_borders and self._geometry else None,
                            features=self.feature_lines(i) if state.show_borders else None)
            vp.set_marker(None if doc.picked is None else doc.mesh.vertices[doc.picked])
        self.update_titles()
        self.grid.render_all()
        res = doc.result(doc.active)
        active = fields[doc.active] if fields else None
        outside = outside_region(res, doc.panes[doc.active].region)
        invalid = None if res is None else ~res.valid if outside is None else ~res.valid & ~outside
        self.inspect.show_values(active, table=(active[2] if active else doc.cmap(doc.active)).table,
                                 n_invalid=None if invalid is None else int(invalid.sum()),
                                 n_vertices=doc.mesh.n_vertices)

    def _grey_frame(self) -> None:
        if self._first_frame_due:
            self._first_frame_due = False
            self.redraw()

    def feature_lines(self, i: int):
        """The feature edges of view ``i``'s feature angle as lines, or None (no angle, difference pane)."""
        doc = self.doc
        angle = None if doc.is_difference(i) else doc.panes[i].features
        if angle is None or doc.mesh is None or doc.is_points:
            return None
        if angle not in self._feature_lines:
            self._feature_lines[angle] = edge_lines(doc.mesh, np.asarray(doc.mesh.edges)[feature_edges(doc.mesh, angle)])
        return self._feature_lines[angle]

    def update_titles(self) -> None:
        """Pane headers: estimator and status; no re-render needed."""
        for i, vp in enumerate(self.grid.viewports[:self.doc.view_count]):
            vp.set_title(self.doc.view_title(i), status=self._pane_message(i), detail=self._pane_detail(i))

    def _pane_detail(self, i: int) -> str:
        """The estimator's full name, shown in the header where it fits (always in its tooltip)."""
        doc = self.doc
        spec = None if doc.is_difference(i) else ESTIMATORS.get(doc.panes[i].method)
        return spec.title if spec else ""

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
        """Write the active pane as a coloured PLY: its colours exactly as shown, the curvature
        properties, the shown field (``shown``) and for an analytic source ``error_rel``,
        ``error_<q>`` and ``exact_<q>``; the header comment says what the colours show."""
        payload = export_payload(self.doc)
        colours = np.array(self.grid.viewports[self.doc.active].colours, dtype=np.uint8)
        return save_ply(path, self.doc.mesh, payload.result, quantity=self.doc.display.quantity.value,
                        colors=colours, extra=payload.extra, comment=payload.comment)

    def export_vtu(self, path) -> Path:
        """Write the active pane as a VTK unstructured grid with the same point data (ParaView, pyvista)."""
        payload = export_payload(self.doc)
        colours = np.array(self.grid.viewports[self.doc.active].colours, dtype=np.uint8)
        return save_vtu(path, self.doc.mesh, payload.result, colors=colours, extra=payload.extra)

    def export_png(self, path) -> Path:
        """Save an image of the viewports (all panes) as PNG."""
        self.grid.render_all()
        image = self.grid.grab()
        if not image.save(str(path), "PNG"):
            raise OSError(f"could not write {path}")
        return Path(path)

    def export_ply_dialog(self) -> None:
        self._export_dialog("Export coloured PLY", "PLY (*.ply)", ".ply", self.export_ply)

    def export_vtu_dialog(self) -> None:
        self._export_dialog("Export VTK unstructured grid", "VTK XML (*.vtu)", ".vtu", self.export_vtu)

    def export_png_dialog(self) -> None:
        self._export_dialog("Export screenshot", "PNG (*.png)", ".png", self.export_png)

    def _export_dialog(self, title, filt, suffix, writer) -> None:
        path, _ = QFileDialog.getSaveFileName(self, title, self.settings.value("last_dir", ""), filt)
        if not path:
            return
        path = path if path.lower().endswith(suffix) else path + suffix
        try:
            writer(path)
        except Exception as exc:  # report, never lose the session
            self.show_error(f"Export failed: {exc}")
            return
        self.settings.setValue("last_dir", str(Path(path).parent))
        self.show_status(f"Wrote {path}")

    # -- settings and shutdown ------------------------------------------------------------------
    def _fit_screen(self) -> None:
        """First launch: most of the available screen, centred (never larger than it)."""
        screen = self.screen() or QGuiApplication.primaryScreen()
        if screen is None:
            self.resize(1400, 860)
            return
        avail = screen.availableGeometry()
        w, h = int(min(avail.width() * 0.94, 1680)), int(min(avail.height() * 0.92, 1050))
        self.fit_to(w, h)
        self.move(avail.x() + (avail.width() - w) // 2, avail.y() + (avail.height() - h) // 2)

    def fit_to(self, w: int, h: int) -> None:
        """Resize the window to ``w`` x ``h`` and share it among the docks as on a first launch."""
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
            self._fit_screen()
        if state is not None:
            self.restoreState(state)
        restore_session(self.settings, self.doc)

    def _save_settings(self) -> None:
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("state", self.saveState())
        save_session(self.settings, self.doc)
        self.settings.sync()

    def closeEvent(self, event) -> None:  # noqa: N802
        """Stop the workers, save the layout and settings, release the render windows."""
        self.controller.shutdown(timeout_ms=5000)
        self._save_settings()
        self.grid.close_all()
        super().closeEvent(event)
