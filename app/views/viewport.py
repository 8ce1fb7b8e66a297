"""One VTK viewport (pyvistaqt ``QtInteractor``) drawing a pane: coloured mesh, colour bar,
direction glyphs, picked-vertex marker. Colours are updated in place, never by re-adding the mesh.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, QObject, Qt, Signal
from PySide6.QtWidgets import QFrame, QVBoxLayout
from superqt.utils import create_worker
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonCore import VTK_UNSIGNED_CHAR, vtkLookupTable
from vtkmodules.vtkRenderingCore import vtkCellPicker, vtkRenderer

from app.model.colors import contrasting_colours
from app.model.inputs import DEFAULT_POINT_SIZE

from .colour_bar import BAR_FRACTION, BAR_STRIP_PX, BAR_WIDTH_PX, scalar_bar
from .interactor import Interactor
from .marker import MarkerOverlay
from .pane_header import PaneHeader
from .picking import PointPick, clip_coordinates, drawn_point_at
from .style import PANE_COLOURS

__all__ = ["Viewport", "grey_colours"]


_GREY = np.array([200, 200, 200, 255], dtype=np.uint8)

ASYNC_PICK_POINTS = 500_000
"""Clouds from this many points find a clicked point in a worker (a pass over every point)."""
OVERLAY_MARKER_POINTS = 500_000
"""Inputs from this many points mark the picked vertex with a circle Qt draws over the pane: under
software GL a frame of 5M points takes seconds, and moving the marker in the scene needs one."""
MSAA_SAMPLES = 4
"""Multisamples per pixel for meshes of at most :data:`MSAA_MAX_CELLS` cells."""
MSAA_MAX_CELLS = 400_000
"""Larger meshes are smoothed by FXAA (one screen-space pass) instead of multisampling: under
software GL (Mesa's llvmpipe, Xvfb) 8-sample MSAA made a 2M-triangle frame 3-4x slower (2.5 s
against 0.7 s) while its triangles are smaller than a pixel anyway."""


class Viewport(QFrame):
    """A titled 3D view of the document mesh.

    Signals
    -------
    activated(int)
        The user clicked in this view (its index).
    vertex_picked(int)
        A click without drag hit vertex ``index`` of the mesh.
    """

    activated = Signal(int)
    vertex_picked = Signal(int)

    def __init__(self, index: int, parent=None) -> None:
        super().__init__(parent)
        self.index = index
        self.setObjectName(f"viewport{index}")
        self.setFrameShape(QFrame.Shape.Box)
        self.setLineWidth(2)
        self._title_parts = ("", "", "")
        self.header = PaneHeader(index, self)
        self.title, self.title_field = self.header.title, self.header.rest
        self.plotter = Interactor(self, auto_update=False, multi_samples=MSAA_SAMPLES)
        self.plotter.setAcceptDrops(False)  # the main window handles dropped files
        self.plotter.set_background("white")
        lay = QVBoxLayout(self)
        lay.setContentsMargins(1, 1, 1, 1)
        lay.setSpacing(0)
        lay.addWidget(self.header)
        lay.addWidget(self.plotter, 1)
        self.poly: pv.PolyData | None = None
        self.colours: np.ndarray | None = None
        self._mesh_actor = None
        self._glyph_actors: list = []
        self._overlay_actors: dict = {}
        self.field_title = ""
        self._marker_actor = None
        self._marker_point = None
        self._marker_colour = (255, 208, 0)
        self.marker_overlay = MarkerOverlay(self.plotter)
        self.plotter.frame_done = self._place_overlay
        self.glyph_colours = ((20, 20, 20), (31, 95, 191))
        self._lut = vtkLookupTable()
        self._bar = scalar_bar(self._lut)
        # the colour bar has its own strip under the mesh's renderer: the mesh never covers it
        self._bar_renderer = vtkRenderer()
        self._bar_renderer.SetBackground(1.0, 1.0, 1.0)
        self._bar_renderer.SetInteractive(False)
        self._bar_renderer.AddViewProp(self._bar)
        self.plotter.ren_win.AddRenderer(self._bar_renderer)
        self._bar.SetVisibility(False)
        self._press = None
        self._picks = 0
        self.picking = False
        """True while a click's point is searched for in a worker (large clouds)."""
        self._picker = vtkCellPicker()
        self._picker.SetTolerance(0.002)
        self.points_only = False
        self.plotter.installEventFilter(self)
        self.set_active(False)

    # -- geometry -------------------------------------------------------------------------------
    def set_geometry(self, base: pv.PolyData, *, points: bool = False,
                     point_size: float = DEFAULT_POINT_SIZE, grey: np.ndarray | None = None) -> None:
        """Show ``base`` (shared points and cells) all grey (``grey``, (n, 4) uint8 shared by every
        viewport and never written, or a new array) from the next :meth:`set_colours` on (until then
        it is hidden: a paint of the widget draws nothing of it).

        With ``points`` (a point cloud) every point is drawn as a shaded sphere ``point_size`` pixels
        wide (VTK's sphere impostors; they render under software GL too) and picking takes the point
        nearest the click. Meshes of more than :data:`MSAA_MAX_CELLS` cells are smoothed by FXAA
        instead of multisampling.
        """
        if self._mesh_actor is not None:
            self.plotter.remove_actor(self._mesh_actor, render=False)
        self.clear_glyphs()
        self.poly = base.copy(deep=False)
        self._grey = grey_colours(base.n_points) if grey is None else grey
        self._use_colours(self._grey)
        self.points_only = bool(points)
        # the mapper and actor built here, not by pyvista's add_mesh, which scans the colours (a
        # pass over every vertex, 0.1 s at 5M points) for a range that direct colours never use
        mapper = pv.DataSetMapper(self.poly)
        mapper.SetScalarModeToUsePointFieldData()
        mapper.SelectColorArray("rgba")
        mapper.SetColorModeToDirectScalars()
        mapper.ScalarVisibilityOn()
        style = dict(style="points", point_size=point_size, render_points_as_spheres=True) if points else \
            dict(interpolation="gouraud")
        self._mesh_actor = pv.Actor(mapper=mapper, prop=pv.Property(self.plotter.theme, **style))
        self._mesh_actor.SetVisibility(False)
        self.plotter.add_actor(self._mesh_actor, reset_camera=False, name="mesh", pickable=True, render=False)
        large = base.n_cells > MSAA_MAX_CELLS
        self.plotter.ren_win.SetMultiSamples(0 if large else MSAA_SAMPLES)
        self.plotter.renderer.SetUseFXAA(large)
        self.set_marker(None)

    def set_point_size(self, pixels: float) -> None:
        """Draw a point cloud's points ``pixels`` wide (a mesh is left alone)."""
        if self._mesh_actor is not None and self.points_only:
            self._mesh_actor.prop.point_size = float(pixels)

    @property
    def point_size(self) -> float | None:
        """The drawn width of a point cloud's points in pixels (None for a mesh)."""
        return float(self._mesh_actor.prop.point_size) if self._mesh_actor is not None and self.points_only else None

    def set_colours(self, rgba: np.ndarray | None, *, clim=None, cmap=None, title: str = "") -> None:
        """Draw the mesh in ``rgba`` (n, 4) uint8 (grey if None) and update the colour bar.

        VTK reads ``rgba`` itself, not a copy (:attr:`colours` is it): the caller hands over an array
        it does not write any more, such as a :class:`~app.model.picture.Picture`'s.
        """
        if self.colours is None:
            return
        if rgba is None:
            self._use_colours(self._grey)
            self._bar.SetVisibility(False)
        else:
            self._use_colours(rgba)
            self._set_bar(clim, cmap, title)
        self._mesh_actor.SetVisibility(True)

    def _use_colours(self, rgba: np.ndarray) -> None:
        """Make ``rgba`` the mesh's colour array (no copy: constant time at any size)."""
        rgba = np.ascontiguousarray(rgba, dtype=np.uint8)
        array = numpy_to_vtk(rgba, deep=False, array_type=VTK_UNSIGNED_CHAR)
        array.SetName("rgba")
        self.poly.GetPointData().AddArray(array)  # replaces the array of that name
        self.poly.GetPointData().SetActiveScalars("rgba")
        self.colours = rgba

    def _set_bar(self, clim, cmap, title: str) -> None:
        from curv.colors import CLIP_SHADE

        table = cmap.table
        self._lut.SetNumberOfTableValues(table.shape[0])
        for i, (r, g, b) in enumerate(table / 255.0):
            self._lut.SetTableValue(i, r, g, b, 1.0)
        self._lut.SetRange(*clim)
        lo, hi = table[0] / 255.0 * CLIP_SHADE, table[-1] / 255.0 * CLIP_SHADE
        self._lut.SetBelowRangeColor(*lo, 1.0)
        self._lut.SetAboveRangeColor(*hi, 1.0)
        self._lut.UseBelowRangeColorOn()
        self._lut.UseAboveRangeColorOn()
        self._lut.Build()
        self._bar.SetTitle("")  # the field's name is in the pane header: a VTK title collides with the labels
        self.field_title = title
        self._bar.SetVisibility(True)
        self._bar.Modified()
        self.glyph_colours = tuple(contrasting_colours(cmap, 2))
        self._marker_colour = contrasting_colours(cmap, 1, avoid=self.glyph_colours)[0]

    def set_title(self, text: str, *, status: str = "", detail: str = "") -> None:
        """The pane's header (:class:`~.pane_header.PaneHeader`): estimator (``text``, with ``detail``,
        its full name, where the header has room; elided where even ``text`` has not), the field the
        colours show, the direction legend and the status (computing, failed) in red."""
        self._title_parts = (text, status, detail)
        self._fit_title()

    def _fit_title(self) -> None:
        text, status, detail = self._title_parts
        field = self.field_title if self.field_title and self._bar.GetVisibility() else ""
        self.header.show_parts(text, detail=detail, field=field, legend=self.glyph_legend(), status=status)

    def header_html(self) -> str:
        """The header as shown: the estimator part (plain, perhaps elided), then the rich-text rest."""
        return self.header.html()

    def glyph_legend(self) -> str:
        """What the direction crosses mean, in their colours (empty while none are drawn)."""
        if not self._glyph_actors:
            return ""
        (r1, g1, b1), (r2, g2, b2) = self.glyph_colours
        return (f" &nbsp;·&nbsp; <b style='color:rgb({r1},{g1},{b1})'>━ d1</b> (k1) "
                f"<b style='color:rgb({r2},{g2},{b2})'>━ d2</b> (k2)")

    # -- overlays -------------------------------------------------------------------------------
    def clear_glyphs(self) -> None:
        for actor in self._glyph_actors:
            self.plotter.remove_actor(actor, render=False)
        self._glyph_actors = []

    def set_glyphs(self, lines: tuple[pv.PolyData, pv.PolyData] | None) -> None:
        """Draw (d1, d2) line glyphs in colours that contrast with the map (:attr:`glyph_colours`), or remove them."""
        self.clear_glyphs()
        if lines is None:
            return
        for poly, colour in zip(lines, self.glyph_colours):
            if poly.n_points:
                self._glyph_actors.append(self.plotter.add_mesh(
                    poly, color=tuple(c / 255 for c in colour), line_width=1.5, render=False,
                    reset_camera=False, pickable=False, lighting=False))

    def set_overlays(self, *, edges: bool, borders: pv.PolyData | None, points: bool,
                     features: pv.PolyData | None = None) -> None:
        """Wireframe edges on the mesh, border edges (``borders`` lines) and feature edges (``features``
        lines) highlighted, vertices as points."""
        if self._mesh_actor is not None:
            self._mesh_actor.prop.show_edges = bool(edges)
            self._mesh_actor.prop.edge_color = (0.25, 0.25, 0.25)
            self._mesh_actor.prop.line_width = 0.5
        for name in list(self._overlay_actors):
            self.plotter.remove_actor(self._overlay_actors.pop(name), render=False)
        if borders is not None and borders.n_points:
            self._overlay_actors["borders"] = self.plotter.add_mesh(
                borders, color=(0.9, 0.1, 0.1), line_width=3, render=False, reset_camera=False,
                pickable=False, lighting=False)
        if features is not None and features.n_points:
            self._overlay_actors["features"] = self.plotter.add_mesh(
                features, color=(0.05, 0.05, 0.05), line_width=3, render=False, reset_camera=False,
                pickable=False, lighting=False)
        if points and self.poly is not None:
            self._overlay_actors["points"] = self.plotter.add_mesh(
                pv.PolyData(np.asarray(self.poly.points)), color=(0.1, 0.1, 0.1), point_size=3,
                render_points_as_spheres=False, render=False, reset_camera=False, pickable=False, lighting=False)

    def set_marker(self, point: np.ndarray | None) -> bool:
        """Mark the picked vertex (None: no mark); True when the 3D scene changed (a render is due).

        A small sphere in the scene; on an input of :data:`OVERLAY_MARKER_POINTS` points or more a
        circle Qt draws over the pane instead (placed again after every frame), so that a pick costs
        no frame of the whole input.
        """
        changed = self._marker_actor is not None
        if changed:
            self.plotter.remove_actor(self._marker_actor, render=False)
            self._marker_actor = None
        self._marker_point = None if point is None else np.asarray(point, float).reshape(3)
        diameter = max(16, (self.point_size or 0) + 8)  # a fixed size in pixels: visible at any zoom
        if point is None or self.poly is None or self.poly.n_points < OVERLAY_MARKER_POINTS:
            self.marker_overlay.place(None, None, diameter=diameter, colour=self._marker_colour)
        if point is None:
            return changed
        if self.poly is not None and self.poly.n_points >= OVERLAY_MARKER_POINTS:
            self._place_overlay()
            return changed
        marker = pv.PolyData(self._marker_point.reshape(1, 3))  # in a colour the map lacks
        self._marker_actor = self.plotter.add_mesh(
            marker, color=tuple(c / 255 for c in self._marker_colour), point_size=diameter,
            render_points_as_spheres=True, render=False, reset_camera=False, pickable=False, lighting=False)
        return True

    def _place_overlay(self) -> None:
        """Put the Qt-drawn marker where the camera shows the picked vertex now."""
        point = self._marker_point
        if point is None or self.poly is None or self.poly.n_points < OVERLAY_MARKER_POINTS:
            return
        in_front = (self.camera_matrix() @ np.append(point, 1.0))[3] > 0
        x, y = self.display_position(point) if in_front else (None, None)
        self.marker_overlay.place(x, y, diameter=max(16, (self.point_size or 0) + 8), colour=self._marker_colour)

    def set_active(self, active: bool, *, difference: bool = False) -> None:
        """Frame in the pane's colour, thick when it is the active pane (the Inspect group matches)."""
        colour = PANE_COLOURS[-1] if difference else PANE_COLOURS[self.index % (len(PANE_COLOURS) - 1)]
        width = 3 if active else 1
        self.setStyleSheet(f"#viewport{self.index} {{ border: {width}px solid {colour}; }}")
        self.header.set_active(colour if active else None)

    def render(self) -> None:
        self._centre_bar()
        self.plotter.render()

    def render_if_stale(self) -> None:
        """Render unless the last frame still shows the scene (a paint may have drawn it since a
        render was asked for: a frame of a large input is not drawn twice)."""
        self._centre_bar()  # the pane's size may have changed: the bar's strip follows it
        if not self.plotter.frame_is_current():
            self.plotter.renderer.ResetCameraClippingRange()
            self.plotter.render()

    def _centre_bar(self) -> None:
        """Size the colour bar's strip under the mesh and centre the bar in it (its width is capped in
        pixels, so its left edge depends on the pane)."""
        w, h = max(self.plotter.width(), 1), max(self.plotter.height(), 1)
        strip = min(BAR_STRIP_PX, 0.22 * h) / h
        self._bar_renderer.SetViewport(0.0, 0.0, 1.0, strip)
        self.plotter.renderer.SetViewport(0.0, strip, 1.0, 1.0)
        frac = min(BAR_FRACTION, BAR_WIDTH_PX / w)
        self._bar.SetWidth(frac)
        self._bar.SetHeight(0.96)
        self._bar.SetPosition(0.5 * (1.0 - frac), 0.02)

    # -- picking --------------------------------------------------------------------------------
    def pick_display(self, x: float, y: float) -> int | None:
        """Pick the mesh vertex nearest the ray through widget position (x, y) (Qt pixels, top-left origin)."""
        if self.poly is None:
            return None
        ratio = self.plotter.devicePixelRatioF()
        height = self.plotter.height() * ratio
        if self.points_only:
            return self._pick_point(x * ratio, height - y * ratio - 1)
        if not self._picker.Pick(x * ratio, height - y * ratio - 1, 0, self.plotter.renderer):
            return None
        if self._picker.GetActor() is not self._mesh_actor or self._picker.GetCellId() < 0:
            return None
        cell = self.poly.GetCell(self._picker.GetCellId())
        ids = np.array([cell.GetPointId(k) for k in range(cell.GetNumberOfPoints())])
        pos = np.array(self._picker.GetPickPosition())
        pts = np.asarray(self.poly.points)[ids]
        return int(ids[np.argmin(((pts - pos) ** 2).sum(axis=1))])

    def pixel_length(self) -> float:
        """World length of one pixel at the camera's focal point."""
        cam = self.plotter.renderer.GetActiveCamera()
        height = max(self.plotter.renderer.GetSize()[1], 1)
        if cam.GetParallelProjection():
            return 2.0 * cam.GetParallelScale() / height
        return 2.0 * cam.GetDistance() * np.tan(np.radians(cam.GetViewAngle()) / 2.0) / height

    def camera_matrix(self) -> np.ndarray:
        """(4, 4) composite projection matrix of the camera (world to clip coordinates)."""
        renderer = self.plotter.renderer
        camera = renderer.GetActiveCamera()
        matrix = camera.GetCompositeProjectionTransformMatrix(renderer.GetTiledAspectRatio(), -1.0, 1.0)
        return np.array([[matrix.GetElement(r, c) for c in range(4)] for r in range(4)])

    def clip_coordinates(self) -> np.ndarray:
        """(n, 4) homogeneous clip coordinates of the drawn points through the camera (x, y, z in
        [-w, w] inside the view, z growing away from the viewer)."""
        return clip_coordinates(np.asarray(self.poly.points), self.camera_matrix())

    def point_pick(self, x: float, y: float) -> PointPick:
        """A click at display position (x, y) (device pixels, bottom-left origin) on the cloud as
        drawn now, for :func:`~app.views.picking.drawn_point_at`."""
        radius = 0.5 * max(self.point_size or DEFAULT_POINT_SIZE, 4.0) * self.plotter.devicePixelRatioF()
        return PointPick(np.asarray(self.poly.points), self.camera_matrix(), tuple(self.plotter.renderer.GetViewport()),
                         tuple(self.plotter.ren_win.GetSize()), float(x), float(y), float(radius))

    def _pick_point(self, x: float, y: float) -> int | None:
        """The point of the cloud drawn under display position (x, y) (device pixels, bottom-left
        origin): of the points whose sphere covers it, the nearest the viewer, as the depth test
        draws them."""
        return drawn_point_at(self.point_pick(x, y))

    def display_position(self, point) -> tuple[float, float]:
        """Widget position (Qt pixels) of a world point, the inverse of what picking uses."""
        ren = self.plotter.renderer
        ren.SetWorldPoint(*np.asarray(point, float), 1.0)
        ren.WorldToDisplay()
        dx, dy, _ = ren.GetDisplayPoint()
        ratio = self.plotter.devicePixelRatioF()
        return dx / ratio, (self.plotter.height() * ratio - dy - 1) / ratio

    def eventFilter(self, obj: QObject, event: QEvent) -> bool:  # noqa: N802 (Qt API)
        kind = event.type()
        if kind == QEvent.Type.MouseButtonPress and event.button() == Qt.MouseButton.LeftButton:
            self._press = event.position()
            self.activated.emit(self.index)
        elif kind == QEvent.Type.MouseButtonRelease and event.button() == Qt.MouseButton.LeftButton:
            start, self._press = self._press, None
            if start is not None and (event.position() - start).manhattanLength() <= 3:
                x, y = event.position().x(), event.position().y()
                if self.points_only and self.poly is not None and self.poly.n_points >= ASYNC_PICK_POINTS:
                    self._pick_later(x, y)
                else:
                    vid = self.pick_display(x, y)
                    if vid is not None:
                        self.vertex_picked.emit(vid)
        return False

    def _pick_later(self, x: float, y: float) -> None:
        """Find the point under the click (Qt pixels) in a worker and emit :attr:`vertex_picked` with it;
        a later click supersedes it."""
        ratio = self.plotter.devicePixelRatioF()
        pick = self.point_pick(x * ratio, self.plotter.height() * ratio - y * ratio - 1)
        self._picks += 1
        serial, poly = self._picks, self.poly

        def found(index):
            if index is not None and serial == self._picks and poly is self.poly:
                self.vertex_picked.emit(index)

        self.picking = True
        worker = create_worker(drawn_point_at, pick, _start_thread=False, _connect={
            "returned": found, "finished": lambda: setattr(self, "picking", serial != self._picks)})
        worker.start()

    def close_plotter(self) -> None:
        """Release the VTK render window (call before the widget goes away)."""
        self.plotter.removeEventFilter(self)
        self.plotter.close()


def grey_colours(n: int) -> np.ndarray:
    """(n, 4) uint8: every vertex in the grey of a pane without a result."""
    return np.tile(_GREY, (n, 1))
