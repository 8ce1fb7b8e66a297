"""Fixtures for the viewer tests: the real main window under Xvfb (pytest-xvfb), isolated settings."""

from __future__ import annotations

import gc

import pytest

pytest.importorskip("PySide6.QtWidgets", reason="the viewer tests need PySide6 (gui extra)")
pytest.importorskip("pyvistaqt", reason="the viewer tests need pyvistaqt (gui extra)")
pytest.importorskip("superqt", reason="the viewer tests need superqt (gui extra)")

from PySide6.QtCore import QEvent, QSettings, QThreadPool  # noqa: E402
from PySide6.QtWidgets import QApplication  # noqa: E402

from app.model import SurfaceSource  # noqa: E402

TIMEOUT_MS = 300_000
"""How long a wait for the viewer's work may take before the test fails: generous, since it bounds
a hang, not a speed (waits end as soon as their condition holds). In a fresh checkout the first
estimate of each estimator and the first mesh report compile their kernels (numba caches them),
which took over 30 s under load."""


@pytest.fixture
def window(qtbot, tmp_path):
    """A shown :class:`MainWindow` with settings in ``tmp_path``; closed (workers stopped) afterwards."""
    from app.views.main_window import MainWindow

    settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
    win = MainWindow(settings=settings)
    win.quiet = True  # failures go to the status bar only: no dialog waiting for a click
    win.resize(1200, 760)
    win.show()
    qtbot.waitExposed(win)
    yield win
    win.close()
    # work that cannot stop midway (a kernel's first compile, a report, the advisor) outlives the
    # window's 5 s shutdown wait: let it finish here, or it holds the pool's threads (two on a
    # 2-core machine) and the next test's jobs queue behind it
    assert QThreadPool.globalInstance().waitForDone(TIMEOUT_MS), "a worker still runs after the test"
    release(win)


def release(win) -> None:
    """Delete a closed window now. Its signals' connections to lambdas and bound methods hold it
    from Qt's side, where Python's collector cannot see them, so a window that is only closed keeps
    its document (meshes, results) and its panes' VTK objects for the rest of the run: the suite's
    memory grew by about 1 GB a viewer test file, on a CI of 24 GiB."""
    QApplication.processEvents()  # the finished workers' queued signals reach the window while it lives
    win.deleteLater()
    QApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
    gc.collect()


def wait_ready(qtbot, win, *, timeout: int = TIMEOUT_MS) -> None:
    """Wait until a mesh is shown and every pane has a result or a failure."""
    doc, ctl = win.doc, win.controller

    def done():
        assert doc.mesh is not None and not ctl.busy
        assert all(p.key in doc.results or p.key in doc.failures for p in doc.panes)

    qtbot.waitUntil(done, timeout=timeout)


def open_surface(qtbot, win, name: str = "saddle", *, n_vertices: int = 217, **kw) -> None:
    """Mesh an analytic surface through the controller and wait for every pane."""
    win.open_surface(SurfaceSource(name=name, n_vertices=n_vertices, **kw))
    qtbot.waitUntil(lambda: win.doc.source is not None and win.doc.source.name == name, timeout=TIMEOUT_MS)
    wait_ready(qtbot, win)


class Helpers:
    """Test helpers bound to one window, handed out by the ``ui`` fixture."""

    timeout = TIMEOUT_MS

    def __init__(self, qtbot, win) -> None:
        self.qtbot, self.win = qtbot, win

    def wait_ready(self, *, timeout: int = TIMEOUT_MS) -> None:
        wait_ready(self.qtbot, self.win, timeout=timeout)

    def open_surface(self, name: str = "saddle", **kw) -> None:
        open_surface(self.qtbot, self.win, name, **kw)


@pytest.fixture
def ui(qtbot, window):
    return Helpers(qtbot, window)
