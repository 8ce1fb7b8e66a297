"""The viewer as a new user found it (issue 20, second trial): the pane after Cancel, fitting 1366x768
and 1600x1000, the radius field, estimators a mesh rules out, manual limits, camera and keys,
what persists, the direction legend."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QSettings, Qt
from PySide6.QtWidgets import QApplication

import curv
from curv.estimators import refusal

from app.model import FileSource, Layer, LimitMode, Pane, Quantity, SurfaceSource, count_text
from tests.gui.conftest import TIMEOUT_MS

pytestmark = pytest.mark.gui


def _choose_method(window, name: str) -> None:
    """Pick ``name`` in the estimator list as a person does (the popup's ``activated``)."""
    combo = window.inspect.method
    index = combo.findData(name)
    combo.setCurrentIndex(index)
    combo.activated.emit(index)


def _header(window, i: int = 0) -> str:
    return window.grid.viewports[i].header_html()


def _shown(window, i: int = 0) -> np.ndarray:
    return np.asarray(window.grid.viewports[i].colours)


# -- 1. the pane after Cancel ------------------------------------------------------------------------
def test_cancel_reverts_header_selector_and_picture_together_and_reselecting_computes(qtbot, window, ui):
    ui.open_surface("torus", n_vertices=20000)
    doc = window.doc
    good = doc.panes[0]
    shown = _shown(window).copy()
    _choose_method(window, "icc")
    assert doc.panes[0].method == "icc" and window.controller.busy
    window.action_cancel.trigger()                           # before the result can arrive
    qtbot.waitUntil(lambda: not window.controller.busy, timeout=TIMEOUT_MS)
    assert doc.panes[0] == good                              # the pane shows its last result again ...
    assert window.inspect.method.currentData() == good.method          # ... the selector says so ...
    assert good.title in _header(window) and "cancelled" not in _header(window)   # ... and the header
    np.testing.assert_array_equal(_shown(window), shown)
    assert "icc" in window.status_label.text() and "cancelled" in window.status_label.text().lower()
    _choose_method(window, "icc")                            # choosing it again computes it
    assert window.controller.busy and ("icc", "R2") in window.controller.running_keys()
    ui.wait_ready()
    assert doc.panes[0].method == "icc" and doc.result(0) is not None


def test_cancel_with_nothing_to_go_back_to_says_so_and_reselecting_the_same_computes(qtbot, window, ui):
    window.open_surface(SurfaceSource(name="torus", n_vertices=20000))
    qtbot.waitUntil(lambda: window.doc.mesh is not None and window.doc.source.name == "torus", timeout=TIMEOUT_MS)
    window.action_cancel.trigger()                           # the first estimate on this mesh
    qtbot.waitUntil(lambda: not window.controller.busy, timeout=TIMEOUT_MS)  # the mesh's report still runs
    doc = window.doc
    method = doc.panes[0].method
    assert doc.result(0) is None and "cancelled" in _header(window)
    assert window.inspect.method.currentData() == method
    assert not window.grid.viewports[0]._bar.GetVisibility()          # no colours of another estimate
    assert (_shown(window)[:, :3] == 200).all()                       # grey: nothing computed
    _choose_method(window, method)                          # the same entry again: computed now
    ui.wait_ready()
    assert doc.result(0) is not None and "cancelled" not in _header(window)


# -- 4. radius field --------------------------------------------------------------------------------
@pytest.mark.parametrize("text", ["-1abc", "0", "-2", "abc"])
def test_bad_radius_is_refused_in_red_and_starts_nothing(qtbot, window, ui, text):
    ui.open_surface("saddle")
    before = window.doc.panes[0]
    window.inspect.use_radius.setChecked(True)
    ui.wait_ready()
    before = window.doc.panes[0]
    assert before.radius is not None
    window.inspect.radius.setText(text)
    window.inspect.radius.editingFinished.emit()
    assert window.doc.panes[0] == before and not window.controller.busy
    assert "radius must be a positive length" in window.status_label.text()
    assert "b00020" in window.status_label.styleSheet()              # red, like the range field's message
    assert window.inspect.radius.text() == f"{before.radius:g}"      # the field shows what applies


# -- 9. estimators the mesh rules out ----------------------------------------------------------------
def test_estimators_a_polygon_mesh_rules_out_are_greyed_with_the_reason(qtbot, window, ui, tmp_path):
    n = 8
    xs, ys = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    lines = [f"v {x} {y} {0.3 * (x * x + y * y)}" for x, y in zip(xs.ravel(), ys.ravel())]
    lines += [f"f {a} {a + 1} {a + n + 1} {a + n}" for i in range(n - 1) for a in range(i * n + 1, i * n + n)]
    path = tmp_path / "quads.obj"
    path.write_text("\n".join(lines) + "\n")
    window.open_path(path)
    qtbot.waitUntil(lambda: isinstance(window.doc.source, FileSource), timeout=TIMEOUT_MS)
    ui.wait_ready()
    combo, mesh = window.inspect.method, window.doc.mesh
    refused = [name for name, spec in curv.ESTIMATORS.items() if refusal(spec, mesh)]
    assert set(refused) >= {"meyer", "csm", "ru", "icc"}
    for i, (name, spec) in enumerate(curv.ESTIMATORS.items()):
        item = combo.model().item(i)
        tip = combo.itemData(i, Qt.ItemDataRole.ToolTipRole)
        assert item.isEnabled() == (name not in refused)
        assert (refusal(spec, mesh) in tip) if name in refused else ("Not available" not in tip)
    window.compare.count.setValue(2)                         # a new pane takes one that runs here
    ui.wait_ready()
    assert window.doc.panes[1].method not in refused and window.doc.result(1) is not None


# -- 6. manual limits --------------------------------------------------------------------------------
def test_manual_starts_from_the_limits_on_screen_and_refuses_min_above_max(qtbot, window, ui):
    window.doc.display.update(manual=(0.5, 1.5))             # stale values, e.g. from an earlier run
    ui.open_surface("saddle")
    _, clim, _ = window.doc.fields()[0]
    window.inspect.limit_mode.setCurrentEnum(LimitMode.MANUAL)
    assert window.doc.display.limit_mode is LimitMode.MANUAL
    assert window.doc.display.manual == pytest.approx(clim)
    assert window.doc.fields()[0][1] == pytest.approx(clim)
    window.inspect.lo_edit.setText("1")
    window.inspect.hi_edit.setText("-1")
    window.inspect.hi_edit.editingFinished.emit()
    assert window.doc.display.manual == pytest.approx(clim)          # not applied, and said why
    assert "min < max" in window.status_label.text()
    assert float(window.inspect.lo_edit.text()) == pytest.approx(clim[0], rel=1e-3)


def test_off_centre_manual_limits_say_where_the_diverging_middle_is(qtbot, window, ui):
    ui.open_surface("saddle")
    note = window.inspect.centre_note
    assert not note.isVisibleTo(window.inspect)
    window.inspect.histogram.limits_edited.emit(-0.2, 0.8)   # a histogram drag
    assert window.doc.fields()[0][2].kind == "diverging"
    assert note.isVisibleTo(window.inspect) and "0.3" in note.text() and "not 0" in note.text()
    window.inspect.histogram.limits_edited.emit(-0.5, 0.5)
    assert not note.isVisibleTo(window.inspect)


# -- 8. camera, keys, first-run docks ----------------------------------------------------------------
def test_difference_pane_keeps_the_camera(qtbot, window, ui):
    ui.open_surface("saddle")
    window.compare.count.setValue(2)
    ui.wait_ready()
    qtbot.wait(50)
    camera = window.grid.viewports[0].plotter.camera
    camera.azimuth += 60
    camera.zoom(1.7)
    seen = (camera.position, camera.focal_point)
    window.compare.difference.setChecked(True)
    ui.wait_ready()
    qtbot.wait(100)                                           # any deferred refit would have run
    assert len(window.grid.viewports) == 3
    for vp in window.grid.viewports:
        assert vp.plotter.camera.position == pytest.approx(seen[0])
    window.compare.difference.setChecked(False)
    qtbot.wait(100)
    assert window.grid.viewports[0].plotter.camera.position == pytest.approx(seen[0])


def test_r_resets_the_camera_from_the_range_field(qtbot, window, ui):
    ui.open_surface("saddle")
    window.activateWindow()
    qtbot.waitActive(window)
    camera = window.grid.viewports[0].plotter.camera
    window.grid.reset_camera()
    framed = camera.direction                                  # the view direction R gives
    camera.azimuth = 70
    assert camera.direction != pytest.approx(framed)
    window.inspect.range.setFocus()
    QApplication.processEvents()
    assert QApplication.focusWidget() in (window.inspect.range, window.inspect.range.lineEdit())
    qtbot.keyClick(QApplication.focusWidget(), Qt.Key.Key_R)
    assert camera.direction == pytest.approx(framed)
    assert window.inspect.range.currentText() == "R2"            # no stray R typed


def test_first_run_shows_the_mesh_report_in_front(qtbot, window):
    QApplication.processEvents()
    assert not window.docks["mesh"].visibleRegion().isEmpty()
    assert window.docks["compare"].visibleRegion().isEmpty()


def test_counts_say_vertex_for_one():
    assert count_text(1, "invalid vertex", "invalid vertices") == "1 invalid vertex"
    assert count_text(0, "invalid vertex", "invalid vertices") == "0 invalid vertices"


# -- 2. fits 1366x768 and 1600x1000 ------------------------------------------------------------------
@pytest.mark.parametrize("size", [(1600, 1000), (1366, 768)])
def test_inspect_histogram_readout_and_guide_fit(qtbot, window, ui, size):
    window.fit_to(*size)
    ui.open_surface("saddle", n_vertices=817)
    window.compare.count.setValue(4)
    window.compare.difference.setChecked(True)
    ui.wait_ready()
    QApplication.processEvents()
    scroll = window.docks["inspect"].widget()
    hist = window.inspect.histogram
    top = hist.mapTo(scroll.viewport(), hist.rect().topLeft()).y()
    assert top >= 0 and top + hist.height() <= scroll.viewport().height()   # no scrolling to see it
    window.doc.set_picked(int(np.argmin(np.linalg.norm(window.doc.mesh.vertices[:, :2], axis=1))))
    QApplication.processEvents()
    assert window.readout.horizontalScrollBar().maximum() == 0               # no sideways scrolling
    box = window.show_guide()
    QApplication.processEvents()
    assert box.height() <= 0.8 * window.screen().availableGeometry().height()
    box.close()
    for vp in window.grid.viewports:                        # the mesh is drawn above the colour bar
        mesh_vp, bar_vp = vp.plotter.renderer.GetViewport(), vp._bar_renderer.GetViewport()
        assert bar_vp[3] == pytest.approx(mesh_vp[1]) and mesh_vp[1] > 0
        assert vp._bar_renderer.HasViewProp(vp._bar) and not vp.plotter.renderer.HasViewProp(vp._bar)


def test_picking_still_hits_the_vertex_with_the_bar_strip(qtbot, window, ui):
    from PySide6.QtCore import QPoint

    ui.open_surface("saddle", n_vertices=817)
    doc, vp = window.doc, window.grid.viewports[0]
    target = int(np.argmin(np.linalg.norm(doc.mesh.vertices[:, :2] - 0.3, axis=1)))
    x, y = vp.display_position(doc.mesh.vertices[target])
    qtbot.mouseClick(vp.plotter, Qt.MouseButton.LeftButton, pos=QPoint(int(round(x)), int(round(y))))
    qtbot.waitUntil(lambda: doc.picked is not None, timeout=5000)
    assert np.linalg.norm(doc.mesh.vertices[doc.picked] - doc.mesh.vertices[target]) <= doc.mesh.mean_edge_length


# -- 7. what persists --------------------------------------------------------------------------------
def test_quantity_show_and_difference_pane_persist(qtbot, window, ui, tmp_path):
    from app.views.main_window import MainWindow

    ui.open_surface("saddle")
    window.compare.count.setValue(2)
    window.compare.difference.setChecked(True)
    window.doc.display.update(quantity=Quantity.GAUSSIAN, layer=Layer.E_REL)
    window._save_settings()
    again = MainWindow(settings=QSettings(window.settings.fileName(), QSettings.Format.IniFormat))
    try:
        st = again.doc.display.state
        assert st.quantity is Quantity.GAUSSIAN and st.layer is Layer.E_REL
        assert again.doc.difference and len(again.doc.panes) == 2
    finally:
        again.close()


# -- 10. direction legend ----------------------------------------------------------------------------
def test_direction_crosses_have_a_legend_in_their_colours(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    assert "d1" not in _header(window)
    window.inspect.directions.setChecked(True)
    vp = window.grid.viewports[0]
    (r1, g1, b1), (r2, g2, b2) = vp.glyph_colours
    text = _header(window)
    assert f"rgb({r1},{g1},{b1})" in text and "d1" in text and f"rgb({r2},{g2},{b2})" in text and "d2" in text
    window.inspect.directions.setChecked(False)
    assert "d1" not in _header(window)


def _header_fits(vp) -> bool:
    """The header's two parts are whole in their labels (the estimator part perhaps elided)."""
    title, rest = vp.title, vp.title_field
    return (title.fontMetrics().horizontalAdvance(title.text()) <= title.width()
            and rest.sizeHint().width() <= rest.width())


def test_pane_headers_keep_the_estimators_full_name_only_where_it_fits(qtbot, window, ui):
    window.resize(1800, 900)
    ui.open_surface("saddle", n_vertices=817)
    window.doc.set_pane(0, method="qs", range=2)
    ui.wait_ready()
    qtbot.waitUntil(lambda: "Quadratic" in _header(window), timeout=5000)  # one wide pane: the full name
    window.compare.count.setValue(3)
    window.inspect.directions.setChecked(True)
    window.resize(1366, 768)
    ui.wait_ready()
    for vp in window.grid.viewports[:window.doc.view_count]:
        qtbot.waitUntil(lambda vp=vp: _header_fits(vp), timeout=5000)
        assert "d1" in vp.header_html()  # the legend and the field stay; the long name went
        assert " — " in vp.title.toolTip()  # ... to the tooltip
    assert "Quadratic" not in _header(window, 0) and "Quadratic" in window.grid.viewports[0].title.toolTip()


def test_pane_default_comes_from_the_registry_and_ranges():
    from curv.core import ranges
    from curv.estimators import DEFAULT_ESTIMATOR, ESTIMATORS

    pane = Pane.default()
    assert pane.method == DEFAULT_ESTIMATOR and pane.range == ranges.default_range(ESTIMATORS[DEFAULT_ESTIMATOR])
