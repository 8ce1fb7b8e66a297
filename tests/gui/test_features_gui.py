"""Sharp features and regions in the viewer (issue 18): the Feature angle control and the result key,
feature edges drawn with the borders, reasons in words, Estimate in region over the rest, the
persisted angle, the command line, and a screenshot of a box and a capped cylinder with features
off and on side by side."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QSettings

import curv
from curv.core.features import feature_edges
from curv.core.validity import Reason

from app.model import Pane, readout_rows
from app.model.colors import INVALID_RGBA
from app.model.readout import REASON_WORDS
from app.model.region import REST_COLOUR, ball_region

pytestmark = pytest.mark.gui


def _status(doc, index: int) -> list[str]:
    return dict(readout_rows(doc, index))["status"]


def _shown(window, i: int = 0) -> np.ndarray:
    return np.asarray(window.grid.viewports[i].colours)


def _features_on(window, angle: float = 30.0) -> None:
    control = window.feature_control
    control.angle.setValue(angle)
    control.enabled.setChecked(True)


# -- the Feature angle control and the result key -----------------------------------------------
def test_feature_angle_is_off_by_default_keys_the_result_and_names_creases_in_words(qtbot, window, ui):
    ui.open_surface("box", n_vertices=2000)
    doc = window.doc
    control = window.feature_control
    assert not control.enabled.isChecked() and doc.panes[0].features is None
    whole = doc.result(0)
    assert whole.info["features"] is None
    _features_on(window, 30.0)
    assert doc.panes[0].features == 30.0
    assert doc.panes[0].key != Pane(doc.panes[0].method, doc.panes[0].range).key
    ui.wait_ready()
    res = doc.result(0)
    assert res is not whole and res.info["features"] == 30.0
    crease = curv.core.features.feature_vertices(doc.mesh, feature_edges(doc.mesh, 30.0))
    assert crease.any()
    np.testing.assert_array_equal(res.reason == Reason.FEATURE, crease)   # every crease vertex, nothing else
    assert "features 30°" in window.grid.viewports[0].header_html()
    doc.set_picked(int(np.flatnonzero(crease)[0]))
    assert _status(doc, doc.picked) == ["on a crease (feature edge)", "exact"]
    doc.set_picked(int(np.flatnonzero(~crease & res.valid)[0]))
    assert _status(doc, doc.picked)[0] == "valid"
    assert (_shown(window)[crease] == INVALID_RGBA).all()
    control.enabled.setChecked(False)                            # back to the result already computed
    assert not window.controller.busy and doc.result(0) is whole


def test_borders_and_features_draws_the_feature_edges_of_each_pane(qtbot, window, ui):
    ui.open_surface("box", n_vertices=2000)
    doc = window.doc
    assert window.inspect.borders.text() == "Borders and features"
    doc.set_pane_count(2)
    doc.set_pane(1, method=doc.panes[0].method, range=doc.panes[0].range, features=40.0)
    ui.wait_ready()
    doc.display.update(show_borders=True)
    ui.wait_ready()  # the edges are found in a worker
    drawn = [vp._overlay_actors.get("features") for vp in window.grid.viewports[:2]]
    assert drawn[0] is None                                      # pane A has no feature angle
    lines = drawn[1].GetMapper().GetInput()
    assert lines.GetNumberOfLines() == int(feature_edges(doc.mesh, 40.0).sum()) > 0
    doc.display.update(show_borders=False)
    assert "features" not in window.grid.viewports[1]._overlay_actors


def test_every_invalid_reason_reads_in_words():
    assert set(REASON_WORDS) == set(Reason) - {Reason.OK}
    assert all("_" not in words and words.upper() != r.name for r, words in REASON_WORDS.items())
    assert "crease" in REASON_WORDS[Reason.FEATURE]


# -- estimate in region -------------------------------------------------------------------------
def test_region_around_the_picked_vertex_lies_over_the_whole_mesh_result(qtbot, window, ui):
    ui.open_surface("torus", n_vertices=4000)
    doc, panel = window.doc, window.region_panel
    whole = doc.result(0)
    before = _shown(window).copy()
    centre = int(np.argmax(doc.mesh.vertices[:, 0]))
    doc.set_picked(centre)
    radius = 6 * float(doc.mesh.mean_edge_length)
    panel.radius.setText(f"{radius:g}")
    panel.around.click()
    region = doc.panes[0].region
    assert region is not None and region.centre == centre and 0 < region.size < doc.mesh.n_vertices
    np.testing.assert_array_equal(region.vertices, ball_region(doc.mesh, centre, radius).vertices)
    assert window.controller.busy or doc.panes[0].key in doc.results
    ui.wait_ready()
    part = doc.results[doc.panes[0].key]                          # computed only in the region ...
    inside = np.zeros(doc.mesh.n_vertices, bool)
    inside[region.vertices] = True
    assert (part.reason[~inside] == Reason.NOT_COMPUTED).all() and part.info["region"] == region.size
    shown = doc.result(0)                                        # ... shown over the whole-mesh result
    np.testing.assert_array_equal(shown.k1, whole.k1)            # a region's values equal the full run's
    np.testing.assert_array_equal(_shown(window), before)
    assert "region" in window.grid.viewports[0].header_html()
    assert "Shown: region" in panel.status.text()
    panel.whole.click()
    assert doc.panes[0].region is None and doc.result(0) is whole and not window.controller.busy


def test_region_without_a_whole_mesh_result_is_grey_outside_and_reads_outside_the_region(qtbot, window, ui):
    ui.open_surface("box", n_vertices=2000)
    doc, panel = window.doc, window.region_panel
    doc.set_picked(0)
    panel.radius.setText(f"{5 * float(doc.mesh.mean_edge_length):g}")
    panel.around.click()
    ui.wait_ready()
    _features_on(window, 30.0)                                    # no whole-mesh result with features
    ui.wait_ready()
    pane = doc.panes[0]
    assert pane.region is not None and pane.features == 30.0 and pane.whole.key not in doc.results
    outside = np.ones(doc.mesh.n_vertices, bool)
    outside[pane.region.vertices] = False
    assert (_shown(window)[outside] == REST_COLOUR).all()        # neutral, not the invalid magenta
    assert _status(doc, int(np.flatnonzero(outside)[0]))[0] == "outside the region"
    assert "of 2" in window.inspect.invalid.text() and doc.result(0).valid[pane.region.vertices].any()
    n_invalid = int((~doc.result(0).valid[pane.region.vertices]).sum())
    assert " ".join(window.inspect.invalid.text().split()).startswith(f"Invalid vertices (magenta): {n_invalid} of")


def test_follow_picks_moves_the_region_and_a_new_mesh_drops_it(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    doc, panel = window.doc, window.region_panel
    doc.set_picked(10)
    panel.around.click()
    first = doc.panes[0].region
    doc.set_picked(400)
    assert doc.panes[0].region.centre == 400 and doc.panes[0].region != first
    ui.wait_ready()
    ui.open_surface("torus", n_vertices=1000)
    assert all(p.region is None for p in doc.panes) and "whole mesh" in panel.status.text()


def test_region_in_view_takes_the_vertices_inside_the_zoomed_camera(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=3169)
    doc, panel = window.doc, window.region_panel
    vp = window.grid.viewports[0]
    vp.plotter.camera.zoom(4.0)
    vp.render()
    panel.in_view.click()
    region = doc.panes[0].region
    assert region is not None and 0 < region.size < doc.mesh.n_vertices
    w, h = vp.plotter.width(), vp.plotter.height()
    _, bottom, _, top = vp.plotter.renderer.GetViewport()     # the mesh's part of the pane (bar strip below)

    def on_screen(points):
        xs, ys = np.array([vp.display_position(p) for p in points]).T
        return (xs >= -1) & (xs <= w + 1) & (ys >= (1 - top) * h - 1) & (ys <= (1 - bottom) * h + 1)  # 1 px: rounding

    assert on_screen(doc.mesh.vertices[region.vertices[::20]]).all()
    outside = np.setdiff1d(np.arange(doc.mesh.n_vertices), region.vertices)
    assert not on_screen(doc.mesh.vertices[outside[::20]]).any()
    ui.wait_ready()


def test_a_region_estimate_can_be_cancelled_like_any_other(qtbot, window, ui):
    ui.open_surface("torus", n_vertices=20000)
    doc, panel = window.doc, window.region_panel
    good = doc.panes[0]
    doc.set_picked(0)
    panel.radius.setText("100")                                   # the whole torus: long enough to cancel
    panel.around.click()
    assert window.controller.busy
    window.action_cancel.trigger()
    qtbot.waitUntil(lambda: not window.controller.busy, timeout=5000)
    assert doc.panes[0] == good and doc.result(0) is not None


# -- persistence and the command line -------------------------------------------------------------
def test_feature_angles_persist_with_the_panes_and_regions_do_not(qtbot, window, ui, tmp_path):
    from app.views.main_window import MainWindow

    ui.open_surface("box", n_vertices=1000)
    _features_on(window, 42.5)
    window.doc.set_picked(0)
    window.region_panel.around.click()
    ui.wait_ready()
    window.close()
    again = MainWindow(settings=QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat))
    try:
        assert again.doc.panes[0].features == 42.5 and again.doc.panes[0].region is None
        assert again.feature_control.enabled.isChecked() and again.feature_control.angle.value() == 42.5
    finally:
        again.close()


def test_curvlab_takes_a_feature_angle_for_pane_a_and_for_compared_panes(window):
    from app.main import build_parser, configure

    configure(window, build_parser().parse_args(
        ["--surface", "box", "--method", "mru", "--features", "30", "--compare", "qs:2:45", "--compare", "nc:2"]))
    assert [p.features for p in window.doc.panes] == [30.0, 45.0, None]
    with pytest.raises(ValueError, match="between 0 and 180"):
        configure(window, build_parser().parse_args(["--features", "200"]))


# -- what a person sees -------------------------------------------------------------------------
@pytest.mark.parametrize("surface", ["box", "capped_cylinder"])
def test_screenshot_features_off_and_on_side_by_side(qtbot, window, ui, tmp_path, surface):
    window.resize(1600, 1000)
    window.doc.set_pane_count(2)
    window.doc.set_pane(1, method=window.doc.panes[0].method, range=window.doc.panes[0].range, features=30.0)
    window.doc.display.update(show_borders=True)
    ui.open_surface(surface, n_vertices=2500)
    doc = window.doc
    crease = doc.result(1).reason == Reason.FEATURE
    assert crease.any() and not (doc.result(0).reason == Reason.FEATURE).any()
    assert (_shown(window, 1)[crease] == INVALID_RGBA).all()
    assert not (_shown(window, 0)[crease] == INVALID_RGBA).all(axis=1).any()
    assert window.grid.viewports[1]._overlay_actors["features"].GetMapper().GetInput().GetNumberOfLines() > 0
    both = doc.result(0).valid & doc.result(1).valid & np.isfinite(doc.truth.mean)
    worst = [np.abs(doc.result(i).mean[both] - doc.truth.mean[both]).max() for i in (0, 1)]
    assert worst[1] < 0.5 * worst[0]                          # supports that stop at the creases
    window.grid.render_all()
    path = tmp_path / f"features-{surface}.png"
    assert window.grab().save(str(path), "PNG") and path.stat().st_size > 10_000
