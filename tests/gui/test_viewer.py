"""The real main window under Xvfb: sources, estimation through the workers, display, compare,
picking, export."""

from __future__ import annotations

import numpy as np
import pytest

TIMEOUT_MS = 30_000

pytestmark = pytest.mark.gui

import curv  # noqa: E402
from PySide6.QtCore import QMimeData, QPoint, QPointF, Qt, QUrl  # noqa: E402
from PySide6.QtGui import QDropEvent  # noqa: E402

from app.model import FileSource, Layer, Pane, Quantity, SurfaceSource, colormap, map_colours  # noqa: E402
from app.model.scalars import relative_error  # noqa: E402


def _shown(win, i=0):
    return np.array(win.grid.viewports[i].colours)


def test_default_scene_is_coloured_by_the_estimate(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    doc = window.doc
    res = doc.result(0)
    assert res is not None and res.method == "mru" and res.range == 2
    values, clim, cmap = doc.fields()[0]
    np.testing.assert_allclose(values, res.mean)
    assert clim[0] == -clim[1]                                     # signed: centred on 0
    np.testing.assert_array_equal(_shown(window), map_colours(res.mean, clim, colormap("coolwarm")))
    hi, lo = np.nanargmax(res.mean), np.nanargmin(res.mean)
    assert _shown(window)[hi, 0] > _shown(window)[hi, 2] and _shown(window)[lo, 2] > _shown(window)[lo, 0]
    img = window.grid.viewports[0].plotter.screenshot(return_img=True)
    assert len(np.unique(img.reshape(-1, img.shape[-1]), axis=0)) > 50  # a rendered, coloured mesh
    assert "Invalid vertices" in window.inspect.invalid.text()


@pytest.mark.parametrize("name", list(curv.surfaces.SURFACES))
def test_generate_each_synthetic_surface(qtbot, window, ui, name):
    closed = curv.surfaces.SURFACES[name].closed
    ui.open_surface(name, n_vertices=642 if closed else 217)
    doc = window.doc
    assert doc.truth is not None and doc.mesh.n_vertices == doc.truth.k1.shape[0]
    assert window.windowTitle().startswith("curvlab — ") and name in window.windowTitle()
    window.doc.display.update(layer=Layer.EXACT)
    np.testing.assert_allclose(doc.fields()[0][0], doc.truth.mean)
    assert window.source_panel.current_source().name == name


def test_source_panel_generates_on_edit(qtbot, window, ui):
    ui.open_surface("saddle")
    panel = window.source_panel
    panel.surface.setCurrentIndex(panel.surface.findData("quadratic"))
    qtbot.waitUntil(lambda: window.doc.source.name == "quadratic", timeout=TIMEOUT_MS)
    ui.wait_ready()
    panel.density.setEditText("217")  # debounced edit
    qtbot.waitUntil(lambda: window.doc.mesh.n_vertices == 217, timeout=TIMEOUT_MS)


def test_open_file_and_drop(qtbot, window, ui, tmp_path):
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=3, radius=2.0)
    path = tmp_path / "ball.ply"
    sphere.export(path)
    window.open_path(path)
    qtbot.waitUntil(lambda: isinstance(window.doc.source, FileSource), timeout=TIMEOUT_MS)
    ui.wait_ready()
    res = window.doc.result(0)
    assert window.doc.mesh.n_vertices == len(sphere.vertices) and window.doc.truth is None
    assert np.nanmedian(res.mean) == pytest.approx(0.5, rel=0.05)   # outward sphere of radius 2
    assert not window.inspect.layer.model().item(list(Layer).index(Layer.E_REL)).isEnabled()
    assert str(path.resolve()) in window._recent()
    # drag and drop another file onto the window
    path2 = tmp_path / "small.stl"
    trimesh.creation.icosphere(subdivisions=2).export(path2)
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(path2))])
    event = QDropEvent(QPointF(10, 10), Qt.DropAction.CopyAction, mime, Qt.MouseButton.NoButton,
                       Qt.KeyboardModifier.NoModifier)
    window.dropEvent(event)
    qtbot.waitUntil(lambda: window.doc.source.path == str(path2), timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert window.doc.mesh.n_vertices == 162


def test_bad_file_keeps_the_scene(qtbot, window, ui, tmp_path):
    ui.open_surface("saddle")
    mesh, result = window.doc.mesh, window.doc.result(0)
    bad = tmp_path / "broken.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 2\nend_header\n0 0\n")
    with qtbot.waitSignal(window.error_shown, timeout=TIMEOUT_MS) as blocker:
        window.open_path(bad)
    assert "broken.ply" in blocker.args[0] and "broken.ply" in window.status_label.text()
    assert window.doc.mesh is mesh and window.doc.result(0) is result
    np.testing.assert_array_equal(_shown(window), map_colours(*window.doc.fields()[0]))


def test_estimator_that_cannot_handle_quads_reports_and_reverts(qtbot, window, ui, tmp_path):
    quads = tmp_path / "grid.obj"
    n = 8
    xs, ys = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    zs = 0.3 * (xs**2 + ys**2)
    lines = [f"v {x} {y} {z}" for x, y, z in zip(xs.ravel(), ys.ravel(), zs.ravel())]
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j + 1
            lines.append(f"f {a} {a + 1} {a + n + 1} {a + n}")
    quads.write_text("\n".join(lines) + "\n")
    window.open_path(quads)
    qtbot.waitUntil(lambda: isinstance(window.doc.source, FileSource), timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert not window.doc.mesh.is_triangular and window.doc.result(0) is not None
    shown = _shown(window).copy()
    triangles_only = next(name for name, spec in curv.ESTIMATORS.items() if spec.triangles_only)
    index = window.inspect.method.findData(triangles_only)
    assert not window.inspect.method.model().item(index).isEnabled()   # greyed out, the reason as tooltip
    window.inspect.method.setCurrentIndex(index)                        # chosen anyway: refused, said why
    assert "triangle" in window.status_label.text() and not window.controller.busy
    assert window.doc.panes[0].method == "mru"                 # the estimate that works stays
    np.testing.assert_array_equal(_shown(window), shown)       # scene intact


def test_cancel_midway_and_supersede(qtbot, window, ui):
    ui.open_surface("saddle")
    before = window.doc.result(0)
    window.open_surface(SurfaceSource(name="torus", n_vertices=60000))
    qtbot.waitUntil(lambda: window.doc.source.name == "torus", timeout=TIMEOUT_MS)
    window.doc.set_pane(0, range=4)
    seen = []

    def cancel_midway(label, f):
        # press Cancel at the first report from inside the run: a fast kernel may finish before
        # a poll of the test loop would see it running
        if 0 < f < 1 and not seen:
            seen.append(window.cancel_button.isVisible())
            qtbot.mouseClick(window.cancel_button, Qt.MouseButton.LeftButton)

    window.controller.progress.connect(cancel_midway)
    qtbot.waitUntil(lambda: bool(seen), timeout=TIMEOUT_MS)
    assert seen == [True]
    qtbot.waitUntil(lambda: not window.controller.busy, timeout=5000)
    key = Pane("mru", 4).key
    assert key in window.doc.failures and "cancelled" in window.doc.failures[key]
    assert key not in window.doc.results and not window.cancel_button.isVisible()
    assert before is not None
    # a new request supersedes a running one: only the last source ends up in the document
    window.open_surface(SurfaceSource(name="torus", n_vertices=20000))
    window.open_surface(SurfaceSource(name="sphere", n_vertices=642))
    qtbot.waitUntil(lambda: window.doc.source.name == "sphere", timeout=TIMEOUT_MS)
    ui.wait_ready()
    qtbot.wait(300)
    assert window.doc.source.name == "sphere" and window.doc.mesh.n_vertices < 2000


def test_a_new_source_loads_beside_estimates_that_cannot_stop(qtbot, window, ui, monkeypatch):
    """Two estimates held where a cancel cannot reach them (as a kernel's first compile holds its
    thread until it ends) do not keep the next source from loading: the job pool has threads
    beside them, also on a 2-core machine, where Qt's default pool has two."""
    import threading

    import app.controller.jobs as jobs

    ui.open_surface("saddle")
    real, release, held = jobs.iter_estimate, threading.Event(), []

    def compiling(mesh, method, **kw):
        held.append(method)
        release.wait(300)  # no yield before it: nothing can stop this call
        return (yield from real(mesh, method, **kw))

    monkeypatch.setattr(jobs, "iter_estimate", compiling)
    try:
        window.doc.set_pane_count(2)
        window.doc.set_pane(0, method="qs")
        window.doc.set_pane(1, method="nc")
        qtbot.waitUntil(lambda: len(held) >= 2, timeout=TIMEOUT_MS)
        window.open_surface(SurfaceSource(name="sphere", n_vertices=642))
        qtbot.waitUntil(lambda: window.doc.source.name == "sphere", timeout=TIMEOUT_MS)
        assert not release.is_set() and window.doc.mesh.n_vertices == 642
    finally:
        release.set()
    ui.wait_ready()
    assert window.doc.result(0) is not None and window.doc.result(1) is not None


def test_switch_quantities_and_layers(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    res, truth = window.doc.result(0), window.doc.truth
    window.inspect.quantity.setCurrentEnum(Quantity.GAUSSIAN)
    values, clim, cmap = window.doc.fields()[0]
    np.testing.assert_allclose(values, res.gaussian)
    assert np.nanmax(values) <= 0 and cmap.kind == "sequential"           # K < 0 everywhere: one sign
    np.testing.assert_array_equal(_shown(window), map_colours(res.gaussian, clim, cmap))
    vp = window.grid.viewports[0]
    assert vp.field_title == "Gaussian K" and "Gaussian K" in vp.header_html()
    window.inspect.quantity.setCurrentEnum(Quantity.CURVEDNESS)           # unsigned: sequential map
    values, clim, cmap = window.doc.fields()[0]
    assert cmap.name == "viridis" and clim[0] >= 0
    window.inspect.layer.setCurrentEnum(Layer.E_REL)
    np.testing.assert_allclose(window.doc.fields()[0][0], relative_error(res, truth))
    window.inspect.layer.setCurrentEnum(Layer.ERROR)
    window.inspect.quantity.setCurrentEnum(Quantity.MEAN)
    np.testing.assert_allclose(window.doc.fields()[0][0], res.mean - truth.mean)
    # limits typed in, then dragged on the histogram
    window.inspect.lo_edit.setText("-0.01")
    window.inspect.hi_edit.setText("0.02")
    window.inspect.hi_edit.editingFinished.emit()
    assert window.doc.fields()[0][1] == (-0.01, 0.02)
    hist = window.inspect.histogram
    x = hist.x_of(0.02)
    y = hist.height() // 2
    qtbot.mousePress(hist, Qt.MouseButton.LeftButton, pos=QPoint(int(round(x)), y))
    qtbot.mouseMove(hist, QPoint(int(round(x)) - 20, y))
    qtbot.mouseRelease(hist, Qt.MouseButton.LeftButton, pos=QPoint(int(round(x)) - 20, y))
    lo, hi = window.doc.fields()[0][1]
    assert lo == -0.01 and hi < 0.02
    # directions: glyph lines drawn only where the curvatures differ
    window.inspect.directions.setChecked(True)
    glyphs = window.grid.viewports[0]._glyph_actors
    assert len(glyphs) == 2 and glyphs[0].mapper.dataset.n_cells > 10


def test_compare_two_panes_linked_cameras(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    first = window.doc.result(0)
    window.compare.count.setValue(2)
    ui.wait_ready()
    assert len(window.grid.viewports) == 2 and window.doc.panes[1] == Pane("nc", 2)
    window.doc.set_active(1)
    window.inspect.method.setCurrentIndex(window.inspect.method.findData("qs"))
    ui.wait_ready()
    assert window.doc.panes == [Pane("mru", 2), Pane("qs", 2)]
    assert window.doc.result(0) is first                         # only the switched pane recomputed
    fields = window.doc.fields()
    assert fields[0][1] == fields[1][1]                          # shared colour scale
    window.compare.difference.setChecked(True)
    assert len(window.grid.viewports) == 3
    np.testing.assert_allclose(window.doc.fields()[2][0], first.mean - window.doc.result(1).mean)

    vp0, vp1 = window.grid.viewports[:2]
    renders = []
    vp1.plotter.ren_win.AddObserver("EndEvent", lambda *a: renders.append(1))
    before = np.array(vp1.plotter.camera.position)
    _drag(vp0, dx=60, dy=10)
    qtbot.wait(50)
    after = np.array(vp1.plotter.camera.position)
    assert np.linalg.norm(after - before) > 1e-3 and renders          # moving A moved B and redrew it
    np.testing.assert_allclose(after, vp0.plotter.camera.position)
    window.compare.link.setChecked(False)
    _drag(vp0, dx=60, dy=0)
    assert not np.allclose(vp1.plotter.camera.position, vp0.plotter.camera.position)


def _drag(vp, *, dx, dy):
    """Rotate the camera with a left-button drag through the VTK interactor."""
    iren = vp.plotter.iren.interactor
    w, h = vp.plotter.ren_win.GetSize()
    x, y = w // 2, h // 2
    iren.SetEventInformation(x, y, 0, 0)
    iren.InvokeEvent("LeftButtonPressEvent")
    for k in range(1, 6):
        iren.SetEventInformation(x + dx * k // 5, y + dy * k // 5, 0, 0)
        iren.InvokeEvent("MouseMoveEvent")
    iren.InvokeEvent("LeftButtonReleaseEvent")


def test_pick_vertex_by_click_and_readout(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    window.compare.count.setValue(2)
    ui.wait_ready()
    doc, vp = window.doc, window.grid.viewports[0]
    target = int(np.argmin(np.linalg.norm(doc.mesh.vertices[:, :2], axis=1)))    # centre of the patch
    x, y = vp.display_position(doc.mesh.vertices[target])
    qtbot.mouseClick(vp.plotter, Qt.MouseButton.LeftButton, pos=QPoint(int(round(x)), int(round(y))))
    qtbot.waitUntil(lambda: doc.picked is not None, timeout=5000)
    picked = doc.picked
    assert np.linalg.norm(doc.mesh.vertices[picked] - doc.mesh.vertices[target]) <= doc.mesh.mean_edge_length
    text = window.readout.toPlainText()
    assert f"vertex {picked}" in text and "A: mru R2" in text and "B: nc R2" in text and "exact" in text
    assert f"{doc.result(1).k1[picked]:.5g}" in text and f"{doc.truth.k2[picked]:.5g}" in text
    assert vp._marker_actor is not None and window.grid.viewports[1]._marker_actor is not None


def test_export_ply_round_trip(qtbot, window, ui, tmp_path):
    import trimesh
    from plyfile import PlyData

    ui.open_surface("saddle", n_vertices=817)
    window.doc.display.update(quantity=Quantity.GAUSSIAN)
    out = window.export_ply(tmp_path / "out.ply")
    loaded = trimesh.load(out, process=False)
    np.testing.assert_array_equal(np.asarray(loaded.visual.vertex_colors), _shown(window))
    np.testing.assert_allclose(loaded.vertices, window.doc.mesh.vertices)
    vert = PlyData.read(str(out))["vertex"].data
    res, truth = window.doc.result(0), window.doc.truth
    np.testing.assert_allclose(vert["k1"], res.k1, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(vert["gaussian"], res.gaussian, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(vert["error_rel"], relative_error(res, truth), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(vert["exact_gaussian"], truth.gaussian, rtol=1e-5, atol=1e-6)
    png = window.export_png(tmp_path / "shot.png")
    assert png.stat().st_size > 1000


def test_close_during_computation_exits_cleanly(qtbot, window, ui):
    ui.open_surface("saddle")
    window.open_surface(SurfaceSource(name="torus", n_vertices=60000))
    qtbot.waitUntil(lambda: window.doc.source.name == "torus", timeout=TIMEOUT_MS)
    window.doc.set_pane(0, range=4)
    assert window.controller.busy
    window.close()
    assert not window.controller.busy


def test_settings_persist_colour_maps_recent_and_layout(qtbot, window, ui, tmp_path):
    from app.views.main_window import MainWindow

    ui.open_surface("saddle")
    window.inspect.cmap_div.setCurrentText("RdBu_r")
    assert window.doc.fields()[0][2].name == "RdBu_r"
    window.docks["readout"].hide()
    window.close()
    again = MainWindow(settings=window.settings)
    qtbot.addWidget(again)
    again.show()
    assert again.doc.display.diverging_cmap == "RdBu_r"
    assert again.inspect.cmap_div.currentText() == "RdBu_r"
    assert not again.docks["readout"].isVisible()
    again.close()
