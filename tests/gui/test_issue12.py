"""What a new user tripped over (issue 12): layout on a 1600 px screen, export contents and
permissions, colour limits, readout, source panel, ranges, progress messages, cancel and focus,
overlays, settings and help."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest
from PySide6.QtCore import QSettings, Qt
from PySide6.QtWidgets import QApplication

import curv
from curv.core.jit import Progress

from app.model import FileSource, Layer, LimitMode, Pane, Quantity, SurfaceSource
from tests.gui.conftest import TIMEOUT_MS

pytestmark = pytest.mark.gui


def _api_takes_real_range() -> bool:
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=1)
    try:
        curv.estimate(curv.Mesh(s.vertices, s.faces), "mru", range=2.5)
    except (curv.EstimatorError, TypeError):
        return False
    return True


def test_three_and_five_views_fit_a_1600_px_screen(qtbot, window, ui):
    window.resize(1600, 1000)
    ui.open_surface("saddle")
    window.compare.count.setValue(3)
    ui.wait_ready()
    QApplication.processEvents()
    assert window.minimumSizeHint().width() <= 1600 and window.width() <= 1600
    assert window.docks["inspect"].isVisible() and window.docks["inspect"].geometry().right() <= window.width()
    window.compare.count.setValue(4)
    window.compare.difference.setChecked(True)
    ui.wait_ready()
    QApplication.processEvents()
    assert window.grid.rows() == [3, 2]                         # no empty cell
    boxes = [vp.geometry() for vp in window.grid.viewports]
    assert len(boxes) == 5 and all(b.width() > 150 and b.height() > 150 for b in boxes)
    assert window.minimumSizeHint().width() <= 1600
    window.compare.difference.setChecked(False)
    QApplication.processEvents()
    assert window.grid.rows() == [2, 2]


def test_gui_exports_name_the_field_and_get_normal_permissions(qtbot, window, ui, tmp_path):
    from plyfile import PlyData

    ui.open_surface("saddle", n_vertices=817)
    window.doc.display.update(layer=Layer.E_REL)
    old = os.umask(0o022)
    try:
        ply = window.export_ply(tmp_path / "e.ply")
        vtu = window.export_vtu(tmp_path / "e.vtu")
    finally:
        os.umask(old)
    comment = PlyData.read(str(ply)).comments[0]
    _, clim, cmap = window.doc.fields()[0]
    assert "e_rel" in comment and "mru R2" in comment and cmap.name in comment and "mean" not in comment
    assert f"{clim[0]:.4g}" in comment and f"{clim[1]:.4g}" in comment
    assert stat.S_IMODE(ply.stat().st_mode) == 0o644 and stat.S_IMODE(vtu.stat().st_mode) == 0o644
    pv = pytest.importorskip("pyvista")
    grid = pv.read(vtu)
    res = window.doc.result(0)
    np.testing.assert_allclose(grid["k1"], res.k1)
    np.testing.assert_array_equal(grid["reason"], res.reason)
    np.testing.assert_allclose(grid["shown"], window.doc.fields()[0][0])
    np.testing.assert_array_equal(grid["rgba"], np.asarray(window.grid.viewports[0].colours))


def test_colour_limits_follow_the_data(qtbot, window, ui):
    ui.open_surface("torus", n_vertices=642)
    values, clim, cmap = window.doc.fields()[0]                  # H > 0 on the whole torus
    assert np.nanmin(values) > 0 and clim[0] > 0 and cmap.kind == "sequential"
    window.doc.display.update(quantity=Quantity.SHAPE_INDEX)
    assert window.doc.fields()[0][1] == (-1.0, 1.0)
    window.doc.display.update(quantity=Quantity.GAUSSIAN)        # K takes both signs: centred
    _, (lo, hi), cmap = window.doc.fields()[0]
    assert lo == -hi and cmap.kind == "diverging"
    window.inspect.lo_edit.setText("-0.5")
    window.inspect.hi_edit.setText("0.5")
    window.inspect.hi_edit.editingFinished.emit()
    assert window.doc.display.limit_mode is LimitMode.MANUAL
    ui.open_surface("sphere", n_vertices=642)                    # a new mesh: manual limits reset
    assert window.doc.display.limit_mode is LimitMode.PERCENTILE
    window.doc.display.update(limit_mode=LimitMode.MANUAL, manual=(-0.5, 0.5))
    window.inspect.lock.setChecked(True)
    ui.open_surface("torus", n_vertices=642)                     # ... unless locked
    assert window.doc.display.limit_mode is LimitMode.MANUAL and window.doc.fields()[0][1] == (-0.5, 0.5)


def test_readout_has_difference_column_reason_and_follows_panes(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    window.compare.count.setValue(2)
    window.compare.difference.setChecked(True)
    ui.wait_ready()
    doc = window.doc
    border = int(np.flatnonzero(doc.mesh.border_vertices)[0])
    doc.set_picked(border)
    text = window.readout.toPlainText()
    assert "A − B" in text and "border" in text.lower()
    a, b = doc.result(0), doc.result(1)
    inner = int(np.flatnonzero(a.valid & b.valid)[0])
    doc.set_picked(inner)
    assert f"{a.k1[inner] - b.k1[inner]:.5g}" in window.readout.toPlainText()
    doc.set_pane(1, method="qs")                                  # no new pick: the readout follows
    ui.wait_ready()
    assert "B: qs R2" in window.readout.toPlainText()
    assert f"{doc.result(1).k1[inner]:.5g}" in window.readout.toPlainText()


def test_source_panel_says_a_file_is_shown(qtbot, window, ui, tmp_path):
    import trimesh

    ui.open_surface("saddle")
    path = tmp_path / "ball.ply"
    trimesh.creation.icosphere(subdivisions=2).export(path)
    window.open_path(path)
    qtbot.waitUntil(lambda: isinstance(window.doc.source, FileSource), timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert "ball.ply" in window.source_panel.showing.text()
    assert "replaces the file" in window.source_panel.group.title()
    assert "ball.ply" in window.mesh_panel.text.text() and "closed" in window.mesh_panel.text.text()


def test_typed_vertex_count_snaps_to_the_hexagon(qtbot, window, ui):
    ui.open_surface("saddle")
    window.source_panel.density.setEditText("1000")
    qtbot.waitUntil(lambda: window.doc.mesh.n_vertices != 217, timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert window.doc.mesh.n_vertices == 1027 and not window.doc.failures     # 3 s (s + 1) + 1, s = 18
    assert window.source_panel.density.currentText() == "1027"
    assert window.source_panel.irregularity.singleStep() == 1.0


def test_integer_range_typed_and_radius(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    combo = window.inspect.range
    combo.setEditText("R3")
    combo.lineEdit().editingFinished.emit()
    assert window.doc.panes[0] == Pane("mru", 3)
    ui.wait_ready()
    assert window.doc.result(0) is not None and window.doc.result(0).range == 3
    combo.setEditText("R0.5")                                     # below mru's smallest: refused, said why
    combo.lineEdit().editingFinished.emit()
    assert window.doc.panes[0] == Pane("mru", 3) and "R2" in window.status_label.text()
    window.inspect.use_radius.setChecked(True)
    assert window.doc.panes[0].radius == pytest.approx(2 * window.doc.mesh.mean_edge_length, rel=1e-4)
    ui.wait_ready()
    assert window.doc.result(0) is not None or window.doc.failures   # computed, or the api's refusal shown


@pytest.mark.skipif(not _api_takes_real_range(), reason="curv.api does not accept a real-valued range yet "
                    "(the numba rewrite of curv.api brings range=2.5)")
def test_real_range_computes(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    window.inspect.range.setEditText("2.5")
    window.inspect.range.lineEdit().editingFinished.emit()
    assert window.doc.panes[0] == Pane("mru", 2.5)
    ui.wait_ready()
    assert window.doc.result(0) is not None and "R2.5" in window.grid.viewports[0].title.text()


def test_progress_message_shown_and_cancel_keeps_focus(qtbot, window, ui, monkeypatch):
    import time

    import app.controller.jobs as jobs

    ui.open_surface("saddle")
    real = jobs.iter_estimate

    def slow(mesh, method, **kw):
        for i in range(2000):  # a long first-run compile, then chunks
            time.sleep(0.01)
            yield Progress(i / 2000, "compiling curvature kernels (first run only)..." if i < 1000 else "")
        return (yield from real(mesh, method, **kw))

    monkeypatch.setattr(jobs, "iter_estimate", slow)
    window.activateWindow()
    qtbot.waitUntil(lambda: window.isActiveWindow(), timeout=5000)
    window.inspect.quantity.setFocus()
    qtbot.waitUntil(lambda: window.inspect.quantity.hasFocus(), timeout=5000)
    window.doc.set_pane(0, method="qs")
    qtbot.waitUntil(lambda: "compiling curvature kernels" in window.status_label.text(), timeout=TIMEOUT_MS)
    focused = QApplication.focusWidget()
    qtbot.mouseClick(window.cancel_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not window.controller.busy, timeout=2000)
    assert QApplication.focusWidget() is focused and window.inspect.quantity.hasFocus()
    assert "cancelled" in window.doc.failures[Pane("qs", 2).key] and window.doc.panes[0].method == "mru"


def test_overlays_and_glyph_colours(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    vp = window.grid.viewports[0]
    window.inspect.edges.setChecked(True)
    window.inspect.borders.setChecked(True)
    window.inspect.points.setChecked(True)
    ui.wait_ready()  # the border edges are found in a worker
    assert vp._mesh_actor.prop.show_edges
    assert vp._overlay_actors["borders"].mapper.dataset.n_cells == int(window.doc.mesh.border_edges.sum())
    assert vp._overlay_actors["points"].mapper.dataset.n_points == window.doc.mesh.n_vertices
    window.doc.display.update(quantity=Quantity.CURVEDNESS, show_directions=True)   # viridis: dark end
    table = window.doc.fields()[0][2].table.astype(float)
    for colour in vp.glyph_colours:
        assert np.min(np.linalg.norm(table - np.asarray(colour, float), axis=1)) > 60
    assert vp._glyph_actors


def test_settings_persist_panes_and_limits_and_help_menu(qtbot, window, ui):
    from app.views.main_window import MainWindow

    ui.open_surface("saddle")
    window.compare.count.setValue(2)
    window.doc.set_pane(1, method="qs", range=3)
    window.doc.display.update(limit_mode=LimitMode.MINMAX)
    menus = {a.text().replace("&", ""): a.menu() for a in window.menuBar().actions()}
    assert {"File", "View", "Estimate", "Help"} <= set(menus)
    help_items = [a.text().replace("&", "") for a in menus["Help"].actions()]
    assert any("About" in t for t in help_items) and any("Estimators" in t for t in help_items)
    shortcuts = {a.text().replace("&", ""): a.shortcut().toString() for m in menus.values() for a in m.actions()}
    assert shortcuts["Export coloured PLY…"] and shortcuts["Export screenshot (PNG)…"]
    assert shortcuts["Recompute active pane"] == "F5" and shortcuts["Reset camera"] == "R"
    window.close()
    again = MainWindow(settings=QSettings(window.settings.fileName(), QSettings.Format.IniFormat))
    qtbot.addWidget(again)
    assert again.doc.panes == [Pane("mru", 2), Pane("qs", 3)]
    assert again.doc.display.limit_mode is LimitMode.MINMAX
    again.close()


def test_sample_meshes_ship_in_resources(qtbot, window, ui):
    actions = {a.text(): a for a in window.sample_menu.actions()}
    assert "torus.ply" in actions
    actions["torus.ply"].trigger()
    qtbot.waitUntil(lambda: isinstance(window.doc.source, FileSource) and window.doc.source.label == "torus.ply",
                    timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert window.doc.mesh.n_vertices == 1000 and window.doc.result(0).valid.all()
