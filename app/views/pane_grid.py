"""The grid of viewports (compare mode) with linked cameras."""

from __future__ import annotations

import math

import pyvista as pv
from PySide6.QtCore import QTimer, Signal
from PySide6.QtWidgets import QGridLayout, QWidget

from app.model.camera import UpAxis, View, view_vectors
from app.model.inputs import DEFAULT_POINT_SIZE

from .viewport import Viewport

__all__ = ["PaneGrid"]


class PaneGrid(QWidget):
    """Holds 1-5 :class:`Viewport` s (4 panes + difference) laid out in a grid.

    With ``linked`` cameras every viewport renders through the first one's camera, and an
    interaction in any viewport re-renders the others.

    Signals
    -------
    activated(int), vertex_picked(int)
        Forwarded from the viewports.
    """

    activated = Signal(int)
    vertex_picked = Signal(int)

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.layout_ = QGridLayout(self)
        self.layout_.setContentsMargins(0, 0, 0, 0)
        self.layout_.setSpacing(3)
        self.viewports: list[Viewport] = []
        self.linked = True
        self._base: pv.PolyData | None = None
        self._points = False
        self._point_size = float(DEFAULT_POINT_SIZE)
        self._syncing = False
        self._synced_mtime = 0
        self._grey = None
        self._bounds = None
        self.view, self.up = View.ISOMETRIC, UpAxis.Z
        """The standard view the cameras were last set to, and its up axis."""
        self._render_timer = QTimer(self, singleShot=True, interval=0)
        self._render_timer.timeout.connect(self.render_all)
        self.set_count(1)

    # -- panes ----------------------------------------------------------------------------------
    def set_count(self, n: int) -> None:
        """Show ``n`` viewports, creating or closing them as needed."""
        while len(self.viewports) > n:
            vp = self.viewports.pop()
            self.layout_.removeWidget(vp)
            vp.close_plotter()
            vp.hide()  # deleteLater waits for the event loop: never leave its frame on screen meanwhile
            vp.setParent(None)
            vp.deleteLater()
        while len(self.viewports) < n:
            vp = Viewport(len(self.viewports), self)
            vp.fresh = True  # its own default camera: set_linked gives it the view of the others
            vp.activated.connect(self.activated)
            vp.vertex_picked.connect(self.vertex_picked)
            vp.plotter.ren_win.AddObserver("EndEvent", self._after_render)
            if self._base is not None:
                vp.set_geometry(self._base, points=self._points, point_size=self._point_size, grey=self._grey)
            self.viewports.append(vp)
        self._arrange()
        self.set_linked(self.linked)  # new viewports look through the shared camera (or a copy): the view stays

    def rows(self) -> list[int]:
        """Viewports per row: 1, 2, 3 side by side when the grid is wide (else 2 + 1), 2 x 2, 3 + 2."""
        n = len(self.viewports)
        wide = self.width() >= 1.9 * max(self.height(), 1)
        return {1: [1], 2: [2], 3: [3] if wide else [2, 1], 4: [2, 2], 5: [3, 2]}.get(n, [math.ceil(n / 2)] * 2)

    def _arrange(self) -> None:
        """Place the viewports row by row; each row shares the full width (no empty cells)."""
        for vp in self.viewports:
            self.layout_.removeWidget(vp)
        cols = 6  # a multiple of every row length
        i = 0
        for r, count in enumerate(self.rows()):
            span = cols // count
            for c in range(count):
                if i < len(self.viewports):
                    self.layout_.addWidget(self.viewports[i], r, c * span, 1, span)
                i += 1
        for c in range(cols):
            self.layout_.setColumnStretch(c, 1)
        self._arranged = tuple(self.rows())

    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt API)
        super().resizeEvent(event)
        if getattr(self, "_arranged", None) != tuple(self.rows()):
            self._arrange()
            self._refit_later()

    def _refit_later(self) -> None:
        """Reset the camera after the pending layout (VTK uses the panes' sizes at the time of the reset)."""
        if self._base is not None:
            QTimer.singleShot(0, lambda: self.reset_camera(render=True))

    def set_geometry(self, base: pv.PolyData, *, points: bool = False, grey=None, bounds=None) -> None:
        """Show a new mesh (or point cloud, drawn as points) in every viewport and frame it (drawn
        from the viewports' next colours on); ``grey``: its all-grey colours, shared by the viewports;
        ``bounds``: its bounds if known (VTK's are a pass over the points)."""
        self._base, self._points, self._grey = base, bool(points), grey
        self._bounds = bounds
        for vp in self.viewports:
            vp.set_geometry(base, points=self._points, point_size=self._point_size, grey=grey)
        self.reset_camera(render=False)
        self._refit_later()  # again once Qt has laid the panes out (VTK fits their sizes then)

    def set_point_size(self, pixels: float) -> None:
        """Draw a point cloud's points ``pixels`` wide in every viewport (kept for the next cloud)."""
        self._point_size = float(pixels)
        for vp in self.viewports:
            vp.set_point_size(self._point_size)

    def set_view(self, view: View, up: UpAxis, *, render: bool = True) -> None:
        """Look at the mesh from the standard ``view`` with ``up`` up, framed (every pane)."""
        self.view, self.up = View(view), UpAxis(up)
        self.reset_camera(render=render)

    def reset_camera(self, *, render: bool = True) -> None:
        """Frame the mesh from the current standard view (:meth:`set_view`)."""
        first = self.viewports[0].plotter
        position, view_up = view_vectors(self.view, self.up)
        first.view_vector(tuple(position), viewup=tuple(view_up), render=False)
        # the renderer's own reset: pyvista's Plotter.reset_camera renders even with render=False
        # (a whole extra frame: 1.7 s on a 1M mesh under Xvfb)
        # the mesh's own bounds: its actor is hidden until its first colours
        if self._base is not None and self._bounds is None:
            self._bounds = self._base.bounds
        first.renderer.reset_camera(render=False, bounds=self._bounds)
        # VTK fits the first pane (its aspect included); a linked camera must also fit a narrower pane
        aspects = [vp.plotter.width() / max(vp.plotter.height(), 1) for vp in self.viewports]
        narrow = min(aspects) / max(min(aspects[0], 1.0), 1e-3) if self.linked else 1.0
        first.camera.zoom(1.15 * min(1.0, max(narrow, 0.2)))
        if not self.linked:
            for vp in self.viewports[1:]:
                vp.plotter.renderer.camera = first.camera.copy()
        if render:
            self.render_all()

    # -- cameras --------------------------------------------------------------------------------
    def set_linked(self, linked: bool) -> None:
        """Share the first viewport's camera with all (True) or give each its own copy (False)."""
        self.linked = bool(linked)
        master = self.viewports[0].plotter.renderer.camera
        for vp in self.viewports[1:]:
            ren = vp.plotter.renderer
            if linked and ren.camera is not master:
                ren.camera = master
            elif not linked and (ren.camera is master or getattr(vp, "fresh", False)):
                ren.camera = master.copy()
            vp.fresh = False
            ren.ResetCameraClippingRange()
        self.render_all()

    def _after_render(self, window, event) -> None:
        """After any viewport renders with a moved shared camera, render the others to match."""
        if self._syncing or not self.linked or len(self.viewports) < 2:
            return
        camera = self.viewports[0].plotter.renderer.GetActiveCamera()
        if camera.GetMTime() <= self._synced_mtime:
            return
        self.render_all(skip=window)

    def request_render(self) -> None:
        """Render every viewport once the event loop is free (however many ask before then): a
        handler returns at once, and a frame of a large input (most of a second under software GL)
        is drawn once for all the changes that asked for it."""
        self._render_timer.start()

    @property
    def render_due(self) -> bool:
        """True while a requested render has not been drawn yet."""
        return self._render_timer.isActive()

    def render_all(self, *, skip=None) -> None:
        """Render every viewport (except the one whose window is ``skip``) now."""
        if skip is None:
            self._render_timer.stop()
        self._syncing = True
        try:
            for vp in self.viewports:
                if vp.plotter.ren_win is not skip:
                    vp.render_if_stale()
        finally:
            self._syncing = False
            self._synced_mtime = self.viewports[0].plotter.renderer.GetActiveCamera().GetMTime()

    def close_all(self) -> None:
        for vp in self.viewports:
            vp.close_plotter()
