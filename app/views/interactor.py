"""The 3D widget of a pane: pyvistaqt's ``QtInteractor`` that draws no frame it need not draw."""

from __future__ import annotations

import ctypes
import sys

from PySide6.QtCore import Qt
from pyvistaqt import QtInteractor
from vtkmodules.vtkCommonCore import vtkObject

__all__ = ["Interactor"]


def _pin_none(references: int = 2_000_000) -> None:
    """Give None ``references`` references that are never released (CPython before 3.12 only).

    Each VTK render and make-current through pyvistaqt 0.13 / VTK 9.7 / PySide6 6.12 drops None's
    reference count by one more than it takes (measured: -1 per ``ren_win.Render()``, -1 per
    ``makeCurrent()``, about -4 per frame, with a plain ``QtInteractor`` too), so after some ten
    thousand frames None would be freed and the interpreter abort ("none_dealloc"; the whole GUI
    test run did at exit). A list of Nones does not help: finalisation frees it first. From
    Python 3.12 None is immortal and nothing is needed.
    """
    if sys.version_info < (3, 12) and sys.implementation.name == "cpython":
        ctypes.c_ssize_t.from_address(id(None)).value += references  # ob_refcnt is None's first field


_pin_none()


class Interactor(QtInteractor):
    """A ``QtInteractor`` whose paints show VTK's last frame again when nothing drawn changed since.

    pyvistaqt's widget renders the whole scene on every paint, and every render schedules a paint:
    each ``render()`` drew the scene twice, and grabbing the window a third time (at 10M
    triangles each frame took 10-30 s of the GUI thread under software GL). Here a paint only blits
    the last frame while the window size and the scene's modification time (renderers, cameras,
    lights, props and the props' data) are what they were when that frame ended.
    """

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.frames = 0
        """Frames VTK rendered in this widget (for tests and benchmarks)."""
        self.frame_done = None
        """Called after every frame (the view places what Qt draws over it)."""
        self._stamp = vtkObject()  # Modified() at the end of each frame: its MTime is the frame's time
        self._frame_size = None
        # listed with pyvistaqt's own observers: removed when the widget closes (VTK pins the method)
        self._vtk_observers.append((self.ren_win, self.ren_win.AddObserver("EndEvent", self._frame_ended)))

    def _frame_ended(self, *_):
        self.frames += 1
        self._stamp.Modified()
        self._frame_size = tuple(self.ren_win.GetSize())
        if self.frame_done is not None:
            self.frame_done()

    def _scene_time(self) -> int:
        stamp = 0
        renderers = self.ren_win.GetRenderers()
        renderers.InitTraversal()
        for _ in range(renderers.GetNumberOfItems()):
            ren = renderers.GetNextItem()
            stamp = max(stamp, ren.GetMTime(), ren.GetActiveCamera().GetMTime())
            lights = ren.GetLights()
            lights.InitTraversal()
            for _ in range(lights.GetNumberOfItems()):
                stamp = max(stamp, lights.GetNextItem().GetMTime())
            props = ren.GetViewProps()
            props.InitTraversal()
            for _ in range(props.GetNumberOfItems()):
                stamp = max(stamp, props.GetNextProp().GetRedrawMTime())
        return stamp

    def frame_is_current(self) -> bool:
        """True when the last frame still shows the scene (same size, nothing modified since)."""
        return (self._frame_size is not None and self._frame_size == tuple(self.ren_win.GetSize())
                and self._scene_time() < self._stamp.GetMTime())

    # A click that does not drag moves no camera, but VTK's interactor style renders a full frame when
    # the button comes up (the end of a rotation): at 5M points most of a second of the GUI thread for
    # nothing. Renders are off from the press until the mouse moves with the button down.
    def mousePressEvent(self, event) -> None:  # noqa: N802 (Qt API)
        self._interactor_renders(False)
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event) -> None:  # noqa: N802 (Qt API)
        if event.buttons() != Qt.MouseButton.NoButton:
            self._interactor_renders(True)
        super().mouseMoveEvent(event)

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802 (Qt API)
        try:
            super().mouseReleaseEvent(event)
        finally:
            self._interactor_renders(True)

    def _interactor_renders(self, on: bool) -> None:
        setter = getattr(self._Iren, "SetEnableRender", None)  # a closed widget holds a stand-in
        if setter is not None:
            setter(bool(on))

    def paintGL(self) -> None:  # noqa: N802 (Qt API)
        if self._in_paint or not self.frame_is_current():
            super().paintGL()
            return
        self._in_paint = True  # pyvistaqt's paintGL then blits the last frame without rendering
        try:
            super().paintGL()
        finally:
            self._in_paint = False
