"""One VTK viewport (pyvistaqt ``QtInteractor``) drawing a pane: coloured mesh, colour bar,
direction glyphs, picked-vertex marker. Colours are updated in place, never by re-adding the mesh.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, QObject, Qt, Signal
from PySide6.QtWidgets import QFrame, QLabel, QVBoxLayout
from pyvistaqt import QtInteractor
from vtkmodules.vtkCommonCore import vtkLookupTable
from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor
from vtkmodules.vtkRenderingCore import vtkCellPicker

__all__ = ["Viewport"]

_GREY = np.array([200, 200, 200, 255], dtype=np.uint8)


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
        self.title = QLabel(self)
        self.title.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.plotter = QtInteractor(self, auto_update=False)
        self.plotter.setAcceptDrops(False)  # the main window handles dropped files
        self.plotter.set_background("white")
        lay = QVBoxLayout(self)
        lay.setContentsMargins(1, 1, 1, 1)
        lay.setSpacing(0)
        lay.addWidget(self.title)
        lay.addWidget(self.plotter, 1)
        self.poly: pv.PolyData | None = None
        self.colours: np.ndarray | None = None
        self._mesh_actor = None
        self._glyph_actors: list = []
        self._marker_actor = None
        self._edge = 1.0
        self._lut = vtkLookupTable()
        self._bar = _scalar_bar(self._lut)
        self.plotter.renderer.AddViewProp(self._bar)
        self._bar.SetVisibility(False)
        self._press = None
        self._picker = vtkCellPicker()
        self._picker.SetTolerance(0.002)
        self.plotter.installEventFilter(self)
        self.set_active(False)

    # -- geometry -------------------------------------------------------------------------------
    def set_geometry(self, base: pv.PolyData, *, edge_length: float) -> None:
        """Show ``base`` (shared points and cells) with a fresh colour array, all grey."""
        if self._mesh_actor is not None:
            self.plotter.remove_actor(self._mesh_actor, render=False)
        self.clear_glyphs()
        self.poly = base.copy(deep=False)
        self.colours = np.tile(_GREY, (base.n_points, 1))
        self.poly.point_data.set_array(self.colours, "rgba")
        self.colours = self.poly.point_data["rgba"]  # the VTK-backed array, written in place later
        self._mesh_actor = self.plotter.add_mesh(
            self.poly, scalars="rgba", rgb=True, show_scalar_bar=False, reset_camera=False,
            render=False, name="mesh", pickable=True)
        self._mesh_actor.prop.interpolation = "gouraud"
        self._edge = float(edge_length)
        self.set_marker(None)

    def set_colours(self, rgba: np.ndarray | None, *, clim=None, cmap=None, title: str = "") -> None:
        """Write ``rgba`` (n, 4) uint8 into the mesh colours (grey if None) and update the colour bar."""
        if self.colours is None:
            return
        if rgba is None:
            self.colours[:] = _GREY
            self._bar.SetVisibility(False)
        else:
            self.colours[:] = rgba
            self._set_bar(clim, cmap, title)
        self.poly.GetPointData().GetArray("rgba").Modified()

    def _set_bar(self, clim, cmap, title: str) -> None:
        table = cmap.table
        self._lut.SetNumberOfTableValues(table.shape[0])
        for i, (r, g, b) in enumerate(table / 255.0):
            self._lut.SetTableValue(i, r, g, b, 1.0)
        self._lut.SetRange(*clim)
        self._lut.Build()
        self._bar.SetTitle(title)
        self._bar.SetVisibility(True)
        self._bar.Modified()

    def set_title(self, text: str, *, status: str = "") -> None:
        """The pane's header: what it shows, and its status (computing, failed) in red."""
        extra = f" &nbsp;<span style='color:#b00020'>{status}</span>" if status else ""
        self.title.setText(f"{text}{extra}")

    # -- overlays -------------------------------------------------------------------------------
    def clear_glyphs(self) -> None:
        for actor in self._glyph_actors:
            self.plotter.remove_actor(actor, render=False)
        self._glyph_actors = []

    def set_glyphs(self, lines: tuple[pv.PolyData, pv.PolyData] | None) -> None:
        """Draw (d1, d2) line glyphs, or remove them."""
        self.clear_glyphs()
        if lines is None:
            return
        for poly, colour in zip(lines, ("#202020", "#1f5fbf")):
            if poly.n_points:
                self._glyph_actors.append(self.plotter.add_mesh(
                    poly, color=colour, line_width=2, render=False, reset_camera=False,
                    pickable=False, lighting=False))

    def set_marker(self, point: np.ndarray | None) -> None:
        """Mark the picked vertex with a small sphere (None hides it)."""
        if self._marker_actor is not None:
            self.plotter.remove_actor(self._marker_actor, render=False)
            self._marker_actor = None
        if point is not None:
            sphere = pv.Sphere(radius=0.6 * self._edge, center=np.asarray(point, float))
            self._marker_actor = self.plotter.add_mesh(
                sphere, color="#ffd000", render=False, reset_camera=False, pickable=False)

    def set_active(self, active: bool) -> None:
        """Highlight the active pane's frame."""
        self.setStyleSheet(f"#viewport{self.index} {{ border: 2px solid {'#2a7ae2' if active else '#c8c8c8'}; }}")

    def render(self) -> None:
        self.plotter.render()

    # -- picking --------------------------------------------------------------------------------
    def pick_display(self, x: float, y: float) -> int | None:
        """Pick the mesh vertex nearest the ray through widget position (x, y) (Qt pixels, top-left origin)."""
        if self.poly is None:
            return None
        ratio = self.plotter.devicePixelRatioF()
        height = self.plotter.height() * ratio
        if not self._picker.Pick(x * ratio, height - y * ratio - 1, 0, self.plotter.renderer):
            return None
        if self._picker.GetActor() is not self._mesh_actor or self._picker.GetCellId() < 0:
            return None
        cell = self.poly.GetCell(self._picker.GetCellId())
        ids = np.array([cell.GetPointId(k) for k in range(cell.GetNumberOfPoints())])
        pos = np.array(self._picker.GetPickPosition())
        pts = np.asarray(self.poly.points)[ids]
        return int(ids[np.argmin(((pts - pos) ** 2).sum(axis=1))])

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
                vid = self.pick_display(event.position().x(), event.position().y())
                if vid is not None:
                    self.vertex_picked.emit(vid)
        return False

    def close_plotter(self) -> None:
        """Release the VTK render window (call before the widget goes away)."""
        self.plotter.removeEventFilter(self)
        self.plotter.close()


def _scalar_bar(lut: vtkLookupTable) -> vtkScalarBarActor:
    bar = vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetOrientationToHorizontal()
    bar.SetPosition(0.1, 0.02)
    bar.SetWidth(0.8)
    bar.SetHeight(0.14)
    bar.SetMaximumHeightInPixels(70)
    bar.SetMaximumWidthInPixels(420)
    bar.SetNumberOfLabels(3)
    bar.SetBarRatio(0.3)
    bar.SetTextPositionToPrecedeScalarBar()  # labels under the bar, title above: no overlap
    bar.SetLabelFormat("%-#6.3g")
    bar.UnconstrainedFontSizeOn()
    for prop in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        prop.SetColor(0.1, 0.1, 0.1)
        prop.ShadowOff()
        prop.ItalicOff()
        prop.BoldOff()
        prop.SetFontSize(12)
    return bar
