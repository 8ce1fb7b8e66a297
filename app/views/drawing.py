"""Drawing the document in the pane grid: colours from a :class:`~app.model.picture.Picture`, then the
cheap decorations (frames, headers, glyphs, overlays, the picked-vertex marker) and one render.

The colours of a large input are painted in a worker (:class:`~app.controller.painter.Painter`): the
GUI thread only hands the finished arrays to VTK, and a frame is rendered once per turn of the event
loop however many changes asked for one, so that a click is answered while a big cloud is drawn.
"""

from __future__ import annotations

import numpy as np
from curv.estimators import ESTIMATORS
from PySide6.QtCore import QObject, QTimer, Signal

from app.controller.painter import Painter
from app.model import Document, colormap
from app.model.picture import Picture, paint, scene_of

from .geometry import direction_glyphs, edge_lines, glyph_subsample

__all__ = ["Drawing", "GLYPH_PIXELS", "GREY_FRAME_DELAY_MS", "ASYNC_PAINT_VALUES"]

GLYPH_PIXELS = 900
"""One direction glyph per this many pixels of a pane at most, so glyphs never bury the colours."""
GREY_FRAME_DELAY_MS = 1000
"""A new mesh is first drawn grey only if its estimates have not arrived this long after it: a
frame of a large mesh takes seconds of the GUI thread under software GL, and the coloured frame
replaces it anyway."""
ASYNC_PAINT_VALUES = 1_000_000
"""Views times vertices from which the colours are painted in a worker: below it painting takes a few
tens of milliseconds and is done at once (the picture is on screen when the change returns)."""


class Drawing(QObject):
    """Keeps the pane grid showing the document.

    Parameters
    ----------
    doc : Document
    grid : PaneGrid
    controller : Controller
        Asked for overlay edges and which estimates run (pane headers).
    inspect : InspectPanel
        Shown the active view's histogram, limits and invalid count.

    Signals
    -------
    drawn()
        A picture of the current scene was put on screen.
    """

    drawn = Signal()

    def __init__(self, doc: Document, grid, controller, inspect, parent=None) -> None:
        super().__init__(parent)
        self.doc, self.grid, self.controller, self.inspect = doc, grid, controller, inspect
        self.geometry = None
        self.grey_frames = True
        """Whether a new mesh is drawn grey while its estimates run (after GREY_FRAME_DELAY_MS);
        a scripted snapshot needs only the coloured frame."""
        self.first_frame_due = False
        self.grey_timer = QTimer(self, singleShot=True, interval=GREY_FRAME_DELAY_MS)
        self.grey_timer.timeout.connect(self._grey_frame)
        self._painted = None  # the key of the scene whose colours are on screen
        self._wanted = None  # the key of the scene asked of the painter
        self._picture: Picture | None = None
        self._lines: dict = {}  # overlay key -> lines of the shown mesh
        self.painter = Painter(self)
        self.painter.painted.connect(self._show_picture)
        doc.edges_changed.connect(self._on_edges)

    # -- state ----------------------------------------------------------------------------------
    @property
    def pending(self) -> bool:
        """True while the colours of the current scene are being painted or a render is due."""
        return self.painter.busy or self.grid.render_due or self._wanted != self._painted

    def new_mesh(self, geometry) -> None:
        """A new input: its geometry in every viewport, grey until its colours come."""
        self.geometry = geometry
        self.grid.set_point_size(self.doc.display.state.point_size)
        self.grid.set_geometry(geometry.base, points=geometry.points_only, grey=geometry.grey, bounds=geometry.bounds)
        self._painted = self._wanted = None
        self._picture = None
        self._lines = {}
        self.first_frame_due = True

    def forget_drawn(self) -> None:
        """The viewports changed (count, geometry): the next :meth:`redraw` recolours them."""
        self._painted = self._wanted = None

    # -- drawing --------------------------------------------------------------------------------
    def redraw(self, *, force: bool = False) -> None:
        """Bring every viewport up to the document: colours (painted now on a small input, in a worker
        on a large one) and then the decorations, and render.

        Colours already on screen are not painted again: cancelling an estimate reverts the pane to
        the result it still shows, and must not stall the GUI on a large input.
        """
        doc = self.doc
        if doc.mesh is None:
            return
        if self.first_frame_due and not force and self.controller.running_keys() \
                and all(doc.result(i) is None for i in range(len(doc.panes))):
            # a new mesh whose estimates run: the coloured frame is its first, unless they take long
            if self.grey_frames and not self.grey_timer.isActive():
                self.grey_timer.start()
            self.update_titles()
            return
        self.first_frame_due = False
        self.grey_timer.stop()
        scene = scene_of(doc)
        key = (scene.key, len(self.grid.viewports))
        if force or key != self._painted:
            if force or key != self._wanted:
                self._wanted = key
                if scene.n * scene.view_count >= ASYNC_PAINT_VALUES:
                    self.painter.paint(scene, key)
                else:
                    self._show_picture(paint(scene), key)
                    return
            self.update_titles()  # the colours and decorations follow with the picture
            return
        self.decorate()

    def _show_picture(self, picture: Picture, key) -> None:
        """Put ``picture`` on screen if it is still the scene wanted."""
        if key != self._wanted or self.doc.mesh is None or picture.scene.n != self.doc.mesh.n_vertices:
            return
        self._picture, self._painted = picture, key
        state = picture.scene.state
        for i, vp in enumerate(self.grid.viewports):
            view = picture.views[i] if i < len(picture.views) else None
            if view is None:
                vp.set_colours(None)
            else:
                vp.set_colours(view.rgba, clim=view.clim, cmap=view.cmap,
                               title=state.field_title(difference=picture.scene.is_difference(i)))
        self.decorate()
        active = picture.views[picture.scene.active] if picture.views else None
        table = (active.cmap if active else colormap(
            state.diverging_cmap if state.signed else state.sequential_cmap)).table
        self.inspect.show_values(None if active is None else (active.clim, active.cmap), table=table,
                                 histogram=picture.histogram, n_invalid=picture.n_invalid,
                                 n_vertices=picture.scene.n)
        self.drawn.emit()

    def decorate(self) -> None:
        """Frames, headers, direction glyphs, overlays and the marker of every viewport (cheap: a
        glyph subsample, the edges found off the GUI thread), then one render."""
        doc = self.doc
        state = doc.display.state
        picture = self._picture
        for i, vp in enumerate(self.grid.viewports[:doc.view_count]):
            vp.set_active(i == doc.active and len(doc.panes) > 1, difference=doc.is_difference(i))
            res = picture.scene.results[i] if picture is not None and i < len(picture.scene.results) else None
            vp.set_glyphs(self._glyphs(vp, res) if state.show_directions and res is not None else None)
            mesh = not doc.is_points  # a point cloud has no edges, and is drawn as points already
            vp.set_overlays(edges=state.show_edges and mesh, points=state.show_points and mesh,
                            borders=self.lines("borders") if state.show_borders else None,
                            features=self.feature_lines(i) if state.show_borders else None)
        self.show_marker()
        self.grid.request_render()
        self.update_titles()

    def show_marker(self) -> None:
        """The picked vertex's marker in every viewport, and a render if the scene changed (a large
        input's marker is drawn by Qt over the pane: no frame)."""
        doc = self.doc
        point = None if doc.picked is None or doc.mesh is None else doc.mesh.vertices[doc.picked]
        if any([vp.set_marker(point) for vp in self.grid.viewports]):
            self.grid.request_render()

    def _glyphs(self, vp, res):
        doc, state = self.doc, self.doc.display.state
        w, h = vp.plotter.width(), vp.plotter.height()
        n = doc.mesh.n_vertices
        count = int(min(1500, max(n // 6, 1), max(w * h // GLYPH_PIXELS, 50)))
        length, lift = 1.6 * self.geometry.edge_length, None
        if doc.is_points:  # glyphs as long as their own spacing, floating above the points' spheres
            length = 0.8 * self.geometry.edge_length * np.sqrt(n / count)
            lift = (0.5 * state.point_size + 1.0) * vp.pixel_length()
        return direction_glyphs(doc.mesh.vertices, res, length=length, lift=lift,
                                index=glyph_subsample(n, count=count))

    def _grey_frame(self) -> None:
        if self.first_frame_due:
            self.first_frame_due = False
            self.redraw()

    # -- overlays -------------------------------------------------------------------------------
    def lines(self, key):
        """The overlay edges ``key`` (``"borders"`` or a feature angle) as lines, or None until the
        controller has found them (asked here; they are drawn when they arrive)."""
        doc = self.doc
        if doc.mesh is None or doc.is_points:
            return None
        if key not in self._lines:
            edges = doc.edges.get(key)
            if edges is None:
                self.controller.request_edges(key)
                return None
            self._lines[key] = edge_lines(doc.mesh, edges)
        return self._lines[key]

    def feature_lines(self, i: int):
        """The feature edges of view ``i``'s feature angle as lines, or None (no angle, difference pane,
        not found yet)."""
        angle = None if self.doc.is_difference(i) else self.doc.panes[i].features
        return None if angle is None else self.lines(angle)

    def _on_edges(self, key) -> None:
        if self.doc.display.state.show_borders:
            self.decorate()

    # -- headers --------------------------------------------------------------------------------
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
