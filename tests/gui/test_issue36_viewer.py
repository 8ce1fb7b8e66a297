"""The viewer as a new user found it on big clouds and small screens (issue 36, items 3, 7, 8, 9 and 12):
the shown result survives Recompute and Cancel, the work of a big input leaves the GUI thread, the
layouts hold at 1366x768 with four panes, the window fits its screen, a first view that looks at
the model from the front (or a scan from above), and exports that suggest a name."""

from __future__ import annotations

import shutil
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt
from PySide6.QtGui import QTextCursor
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QApplication, QFileDialog

from app.model import Quantity, SurfaceSource
from tests.gui.conftest import TIMEOUT_MS

pytestmark = pytest.mark.gui

ROOT = Path(__file__).resolve().parents[2]


def _camera(win):
    """(unit direction from the focal point to the camera, unit view-up) of pane A."""
    cam = win.grid.viewports[0].plotter.renderer.GetActiveCamera()
    d = np.subtract(cam.GetPosition(), cam.GetFocalPoint())
    return d / np.linalg.norm(d), np.asarray(cam.GetViewUp()) / np.linalg.norm(cam.GetViewUp())


# -- item 3: the shown result stays through Recompute and Cancel ------------------------------------
def test_recompute_keeps_the_shown_result_until_the_new_one_and_cancel_restores_it(qtbot, window, ui):
    ui.open_surface("torus", n_vertices=4000)
    doc, ctl = window.doc, window.controller
    key, first = doc.panes[0].key, doc.result(0)
    shown = np.array(window.grid.viewports[0].colours)
    gate = threading.Event()  # holds the new estimate at its first step, as a long one on a big cloud
    import app.controller.jobs as jobs

    real = jobs.iter_estimate

    def slow(*args, **kwargs):
        gate.wait(60)
        return (yield from real(*args, **kwargs))

    jobs.iter_estimate = slow
    try:
        window.inspect.recompute.click()
        assert ctl.running_keys() == [key]
        assert doc.result(0) is first and key not in doc.failures  # still shown while it runs
        np.testing.assert_array_equal(window.grid.viewports[0].colours, shown)
        window.cancel_button.click()
    finally:
        gate.set()
        jobs.iter_estimate = real
    ui.wait_ready()
    assert doc.result(0) is first and key not in doc.failures and doc.panes[0].key == key
    np.testing.assert_array_equal(window.grid.viewports[0].colours, shown)  # not a grey pane
    assert "earlier result stays" in window.status_label.text()
    window.inspect.recompute.click()  # and a recompute that finishes replaces it
    ui.wait_ready()
    assert doc.result(0) is not first and doc.results[key] is doc.result(0)


# -- item 3: the work of a big input runs off the GUI thread ---------------------------------------
def test_a_big_inputs_colours_are_painted_in_a_worker(qtbot, window, ui, monkeypatch):
    import app.model.picture as picture
    import app.views.drawing as drawing

    ui.open_surface("torus", n_vertices=4000)
    monkeypatch.setattr(drawing, "ASYNC_PAINT_VALUES", 1)  # every input counts as big
    threads, real = [], picture.map_colours

    def spy(*args, **kwargs):
        threads.append(threading.current_thread() is threading.main_thread())
        return real(*args, **kwargs)

    monkeypatch.setattr(picture, "map_colours", spy)
    before = np.array(window.grid.viewports[0].colours)
    window.inspect.quantity.setCurrentEnum(Quantity.GAUSSIAN)
    assert window.drawing.pending  # the change returned before its colours were painted
    qtbot.waitUntil(lambda: not window.drawing.pending, timeout=TIMEOUT_MS)
    assert threads and not any(threads)  # painted in a worker only
    res = window.doc.result(0)
    values, clim, cmap = window.doc.fields()[0]
    np.testing.assert_allclose(values, res.gaussian)
    np.testing.assert_array_equal(window.grid.viewports[0].colours, real(values, clim, cmap))
    assert not np.array_equal(window.grid.viewports[0].colours, before)
    assert window.inspect.histogram.counts.sum() > 0


def test_a_pick_on_a_big_cloud_is_found_in_a_worker_and_the_readout_reads_one_vertex(qtbot, window, ui,
                                                                                      monkeypatch):
    import app.views.picking as picking
    import app.views.viewport as viewport

    ui.open_surface("sphere", n_vertices=3000, sampling="uniform")
    doc = window.doc
    monkeypatch.setattr(viewport, "ASYNC_PICK_POINTS", 1)  # every cloud counts as big
    threads, real = [], picking.drawn_point_at
    monkeypatch.setattr(viewport, "drawn_point_at", lambda pick: threads.append(
        threading.current_thread() is threading.main_thread()) or real(pick))
    monkeypatch.setattr(type(doc), "values", lambda self, i: pytest.fail("the readout computed a whole field"))
    vp = window.grid.viewports[0]
    target = int(np.argmax(doc.mesh.vertices[:, 2]))  # the top of the sphere faces the camera from above
    vp.plotter.view_vector((0, 0, 1), viewup=(0, 1, 0), render=False)
    vp.plotter.renderer.reset_camera()
    vp.render()
    x, y = vp.display_position(doc.mesh.vertices[target])
    QTest.mouseClick(vp.plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, QPoint(int(x), int(y)))
    assert doc.picked is None  # not yet: the worker looks for it
    qtbot.waitUntil(lambda: doc.picked is not None, timeout=TIMEOUT_MS)
    assert threads == [False]
    assert np.linalg.norm(doc.mesh.vertices[doc.picked] - doc.mesh.vertices[target]) < 0.2
    assert f"point {doc.picked}" in window.readout.toPlainText()


def test_the_readout_reads_one_vertex_and_computes_no_whole_field(qtbot, window, ui, monkeypatch):
    import curv

    ui.open_surface("torus", n_vertices=2000)
    doc = window.doc
    doc.set_pane_count(2)
    doc.set_difference(True)
    ui.wait_ready()
    whole = []
    original = curv.Curvature.quantity

    def counted(self, name):
        whole.append(name)  # a result's quantity is every vertex's (5M values on a big cloud)
        return original(self, name)

    monkeypatch.setattr(curv.Curvature, "quantity", counted)
    from app.model import readout_rows

    v = 100
    rows = dict(readout_rows(doc, v))
    assert whole == []
    res = doc.result(0)
    monkeypatch.setattr(curv.Curvature, "quantity", original)
    from app.model.readout import fmt

    assert rows["H"][0] == fmt(res.mean[v]) and rows["K"][0] == fmt(res.gaussian[v])
    assert rows["H"][2] == fmt(res.mean[v] - doc.result(1).mean[v])  # A - B
    assert rows["H"][3] == fmt(doc.truth.mean[v])  # exact


def test_a_pick_on_a_big_input_moves_a_marker_drawn_by_qt_and_renders_no_frame(qtbot, window, ui, monkeypatch):
    import app.views.viewport as viewport

    ui.open_surface("sphere", n_vertices=3000, sampling="uniform")
    monkeypatch.setattr(viewport, "OVERLAY_MARKER_POINTS", 1)  # every input counts as big
    vp, doc = window.grid.viewports[0], window.doc
    qtbot.wait(300)
    frames = vp.plotter.frames
    target = int(np.argmax(doc.mesh.vertices[:, 2]))
    doc.set_picked(target)
    qtbot.wait(300)
    assert vp.plotter.frames == frames  # the marker moved without a frame of the input
    overlay = vp.marker_overlay
    assert overlay.isVisible() and vp._marker_actor is None
    x, y = vp.display_position(doc.mesh.vertices[target])
    assert abs(overlay.centre.x() - x) < 1 and abs(overlay.centre.y() - y) < 1
    vp.plotter.renderer.GetActiveCamera().Azimuth(40)  # the camera turns: the marker follows the vertex
    window.grid.render_all()
    x, y = vp.display_position(doc.mesh.vertices[target])
    assert abs(overlay.centre.x() - x) < 1 and abs(overlay.centre.y() - y) < 1
    doc.set_picked(None)
    assert not overlay.isVisible()


def test_a_click_that_does_not_drag_draws_no_frame_and_a_drag_still_turns_the_camera(qtbot, window, ui):
    from PySide6.QtCore import QEvent, QPointF
    from PySide6.QtGui import QMouseEvent

    ui.open_surface("sphere", n_vertices=642)
    plotter = window.grid.viewports[0].plotter
    qtbot.wait(300)  # the frames asked for so far are drawn
    frames = plotter.frames
    corner = QPoint(3, 3)  # the background: nothing to pick
    QTest.mouseClick(plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, corner)
    qtbot.wait(100)
    assert plotter.frames == frames and window.doc.picked is None
    camera = plotter.renderer.GetActiveCamera()
    before = np.array(camera.GetPosition())
    left, none = Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier

    def send(kind, x, y, button, buttons):
        pos = QPointF(x, y)
        QApplication.sendEvent(plotter, QMouseEvent(kind, pos, plotter.mapToGlobal(pos), button, buttons, none))

    send(QEvent.Type.MouseButtonPress, 100, 100, left, left)
    for x in range(104, 180, 4):
        send(QEvent.Type.MouseMove, x, 100, Qt.MouseButton.NoButton, left)
    send(QEvent.Type.MouseButtonRelease, 180, 100, left, Qt.MouseButton.NoButton)
    qtbot.wait(100)
    assert plotter.frames > frames and not np.allclose(camera.GetPosition(), before)


# -- item 7: layouts at 1366x768 with four panes and A - B ------------------------------------------
@pytest.fixture
def compare_four(qtbot, window, ui):
    """Four panes and A - B on a point cloud at 1366x768, a vertex picked, every pane in a region."""
    window.fit_to(1366, 768)
    ui.open_surface("torus", n_vertices=20000, sampling="uniform")  # counts long enough to need a line's width
    doc = window.doc
    doc.set_pane_count(4)
    doc.set_difference(True)
    ui.wait_ready()
    doc.set_picked(1234)
    window.region_panel.radius.setText("0.3")
    window.region_panel.estimate_around()
    ui.wait_ready()
    window.resizeDocks([window.docks["inspect"]], [300], Qt.Orientation.Horizontal)  # as narrow as it gets
    qtbot.wait(50)
    return window


def test_pane_headers_elide_the_setting_and_keep_the_quantity_in_view(qtbot, compare_four):
    win = compare_four
    for i, vp in enumerate(win.grid.viewports[:win.doc.view_count]):
        title, rest = vp.title, vp.title_field
        assert title.fontMetrics().horizontalAdvance(title.text()) <= title.width(), (i, title.text())
        assert rest.sizeHint().width() <= rest.width(), (i, rest.text())
        assert rest.geometry().right() <= vp.header.contentsRect().right() + 1
        assert "Mean H" in rest.text()  # the quantity is never pushed out of view
        assert title.text().endswith("…") and "region" in vp.header.toolTip()  # elided, whole in the tooltip


def _table_lines(browser):
    """Per cell of the readout's table: (text, number of laid-out lines, explicit line breaks)."""
    doc = browser.document()
    out = []
    cursor = QTextCursor(doc)
    table = None
    block = doc.begin()
    while block.isValid():
        cursor.setPosition(block.position())
        if cursor.currentTable() is not None:
            table = cursor.currentTable()
            out.append((block.text(), block.layout().lineCount(), block.text().count("\u2028") + 1))
        block = block.next()
    assert table is not None
    return out


def test_the_readout_never_wraps_inside_a_number(qtbot, compare_four):
    win = compare_four
    win.readout.refresh()
    qtbot.wait(20)
    cells = _table_lines(win.readout)
    assert sum(any(c.isdigit() for c in text) for text, _, _ in cells) >= 20
    wrapped = [text for text, lines, breaks in cells if lines != breaks]
    assert not wrapped, wrapped
    assert win.readout.horizontalScrollBar().maximum() == 0  # and nothing to scroll sideways for
    text = win.readout.toPlainText()
    assert all(head in text for head in ("A", "B", "C", "D", "A − B"))  # every column is there


def test_the_invalid_count_fits_its_row_and_never_overlaps_the_next(qtbot, compare_four):
    ins = compare_four.inspect
    label = ins.invalid
    need = label.heightForWidth(label.width())  # a wrapping label needs this height at its width
    assert label.height() >= (need if need > 0 else label.sizeHint().height()), "its text spills over the next row"
    assert not label.geometry().intersects(ins.lock.geometry())
    assert all(label.fontMetrics().horizontalAdvance(line) <= label.width() for line in label.text().splitlines())
    assert "magenta" in label.toolTip() and "of 20000" in label.text()


def test_screenshots_of_four_panes_at_two_screen_sizes(qtbot, window, ui, tmp_path):
    for w, h in ((1600, 1000), (1366, 768)):
        window.fit_to(w, h)
        ui.open_surface("torus", n_vertices=6000)
        window.doc.set_pane_count(4)
        window.doc.set_difference(True)
        ui.wait_ready()
        window.doc.set_picked(100)
        qtbot.wait(50)
        path = tmp_path / f"four-{w}x{h}.png"
        image = window.grab()
        assert image.width() <= w and image.height() <= h
        assert image.save(str(path), "PNG") and path.stat().st_size > 10_000


# -- item 8: the window fits its screen ------------------------------------------------------------
def test_the_window_never_grows_past_its_screens_available_area(qtbot, window):
    avail = window.screen().availableGeometry()
    window.fit_to(avail.width() + 500, avail.height() + 400)
    assert window.width() <= avail.width() and window.height() <= avail.height()


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="needs xvfb-run for a screen of its own")
def test_a_snapshot_on_a_small_screen_fits_it(tmp_path):
    out = tmp_path / "small.png"
    proc = subprocess.run(
        ["xvfb-run", "-a", "-s", "-screen 0 1366x768x24", sys.executable, "-m", "app.main", "--surface", "sphere",
         "--vertices", "642", "--screenshot", str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=600, env={**_env(), "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 0, proc.stderr
    from PySide6.QtGui import QImage

    image = QImage(str(out))
    assert 0 < image.width() <= 1366 and 0 < image.height() <= 768


def _env():
    import os

    env = dict(os.environ)
    env.pop("DISPLAY", None)
    return env


# -- item 9: the first view, standard views, the up axis -------------------------------------------
def _bunny() -> Path | None:
    try:
        import pymeshlab
    except ImportError:
        return None
    path = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "bunny.obj"
    return path if path.is_file() else None


@pytest.mark.skipif(_bunny() is None, reason="pymeshlab (its sample meshes) is not installed")
def test_the_bunny_opens_from_the_front_with_y_up(qtbot, window, ui):
    window.open_path(_bunny())
    qtbot.waitUntil(lambda: window.doc.source is not None and window.doc.mesh is not None, timeout=TIMEOUT_MS)
    ui.wait_ready()
    direction, up = _camera(window)
    np.testing.assert_allclose(direction, [0, 0, 1], atol=1e-6)  # in front of its face (+z) ...
    np.testing.assert_allclose(up, [0, 1, 0], atol=1e-6)  # ... ears up (+y)
    from app.model.camera import UpAxis

    assert window.up_actions[UpAxis.Y].isChecked()


def test_a_georeferenced_cloud_opens_from_above(qtbot, window, ui, tmp_path):
    rng = np.random.default_rng(1)
    n = 4000
    xy = rng.uniform(0, 300, (n, 2)) + (512_000.0, 5_403_000.0)  # UTM metres, a wide flat scan
    z = 120 + 2 * np.sin(xy[:, 0] / 20)
    path = tmp_path / "scan.xyz"
    np.savetxt(path, np.column_stack([xy, z]), fmt="%.3f")
    window.open_path(path)
    qtbot.waitUntil(lambda: window.doc.mesh is not None and window.doc.is_points, timeout=TIMEOUT_MS)
    ui.wait_ready()
    direction, up = _camera(window)
    np.testing.assert_allclose(direction, [0, 0, 1], atol=1e-6)  # from above ...
    np.testing.assert_allclose(up, [0, 1, 0], atol=1e-6)  # ... north up, as a map


def test_standard_views_and_a_remembered_up_axis(qtbot, window, ui):
    from app.model.camera import UpAxis, View, view_vectors

    ui.open_surface("sphere", n_vertices=642)
    window.up_actions[UpAxis.Z].trigger()
    for view in View:
        window.view_actions[view].trigger()
        direction, up = _camera(window)
        want_dir, want_up = view_vectors(view, UpAxis.Z)
        np.testing.assert_allclose(direction, want_dir, atol=1e-6, err_msg=view.value)
        np.testing.assert_allclose(up, want_up, atol=1e-6, err_msg=view.value)
    from app.views.main_window import MainWindow

    again = MainWindow(settings=window.settings)  # the next session: +z is still chosen
    try:
        assert again.up_axis() is UpAxis.Z and again.up_actions[UpAxis.Z].isChecked()
    finally:
        again.close()


# -- item 12: export names and shortcuts -----------------------------------------------------------
def test_export_dialogs_suggest_input_method_and_range(qtbot, window, ui, monkeypatch, tmp_path):
    asked = []
    monkeypatch.setattr(QFileDialog, "getSaveFileName", staticmethod(
        lambda parent, title, path, filt: (asked.append(Path(path).name), ("", ""))[1]))
    ui.open_surface("torus", n_vertices=2000)
    window.doc.set_pane(0, method="qs", range=2.5)
    ui.wait_ready()
    window.action_export_ply.trigger()
    window.action_export_vtu.trigger()
    window.action_export_png.trigger()
    assert asked == ["torus-qs-R2.5.ply", "torus-qs-R2.5.vtu", "torus-qs-R2.5.png"]


def test_the_export_shortcuts_fire_wherever_the_focus_is(qtbot, window, ui, monkeypatch):
    asked = []
    monkeypatch.setattr(QFileDialog, "getSaveFileName", staticmethod(
        lambda parent, title, path, filt: (asked.append(title), ("", ""))[1]))
    ui.open_surface("saddle")
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)  # shortcuts go to the active window
    ctrl, shift = Qt.KeyboardModifier.ControlModifier, Qt.KeyboardModifier.ShiftModifier
    keys = [(Qt.Key.Key_E, ctrl, "Export coloured PLY"), (Qt.Key.Key_E, ctrl | shift, "Export VTK unstructured grid"),
            (Qt.Key.Key_S, ctrl | shift, "Export screenshot")]
    for widget in (window.grid.viewports[0].plotter, window.inspect.quantity, window.inspect.lo_edit,
                   window.inspect.range.lineEdit(), window.readout):
        widget.setFocus()
        qtbot.wait(30)
        focused = QApplication.focusWidget()
        assert focused is widget or focused.isAncestorOf(widget) or widget.isAncestorOf(focused), \
            (type(widget).__name__, type(focused).__name__)
        for key, mods, title in keys:
            asked.clear()
            QTest.keyClick(focused, key, mods)
            assert asked == [title], (type(focused).__name__, title)


# -- item 34.6: the model's events -----------------------------------------------------------------
def test_model_events_disconnect_and_hold_views_weakly():
    import gc

    from app.model import Document

    doc = Document()
    seen = []

    class View_:
        def on_picked(self, index):
            seen.append(index)

    view = View_()
    doc.picked_changed.connect(view.on_picked)
    doc.mesh = type("M", (), {"n_vertices": 10})()
    doc.set_picked(3)
    del view
    gc.collect()
    doc.set_picked(4)  # the view is gone: nothing calls it
    callback = seen.append
    doc.picked_changed.connect(callback)
    doc.picked_changed.disconnect(callback)
    doc.set_picked(5)
    assert seen == [3]


def test_the_viewer_asks_the_librarys_public_api_and_stays_small():
    app_sources = {p: p.read_text() for p in (ROOT / "app").rglob("*.py")}
    for p, text in app_sources.items():
        for internal in ("cached_max_normals", "grid_ordered", "curv.api", "curv.point_normals"):
            assert internal not in text, f"{p.relative_to(ROOT)} reaches into {internal}"
        assert text.count("\n") < 500, f"{p.relative_to(ROOT)} has {text.count(chr(10))} lines"
    window = (ROOT / "app" / "views" / "main_window.py").read_text()
    for computes in ("feature_edges", "save_ply", "save_vtu", "map_colours"):
        assert computes not in window
