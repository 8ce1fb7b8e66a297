"""The viewer's Advise action and Advice panel (issue 11): the advisor runs off the GUI thread on the
shown mesh, the panel shows what it measured and its ranking, Apply puts a row into the active pane
and computes it, failures give one message, and advice for an earlier mesh is never shown as current."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QKeySequence

import curv

from app.model import FileSource, Pane, SurfaceSource
from app.views.advice_panel import COLUMN, RECOMMENDED_BACKGROUND
from tests.gui.conftest import TIMEOUT_MS

pytestmark = pytest.mark.gui


def _advise(qtbot, window):
    """Trigger the Advise action and wait until the panel holds advice for the shown mesh."""
    window.action_advise.trigger()
    qtbot.waitUntil(lambda: window.doc.advice_current and not window.controller.busy, timeout=TIMEOUT_MS)
    return window.doc.advice.advice


def _write_obj(path, vertices, faces):
    lines = [f"v {x} {y} {z}" for x, y, z in vertices] + ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def _open_file(qtbot, window, ui, path):
    window.open_path(path)
    qtbot.waitUntil(lambda: isinstance(window.doc.source, FileSource) and window.doc.source.path == str(path),
                    timeout=TIMEOUT_MS)
    ui.wait_ready()


def test_advise_runs_in_the_background_and_fills_the_panel(qtbot, window, ui):
    ui.open_surface("quadratic", n_vertices=817, irregularity=12.0, noise=0.05, seed=3)
    panel, ctl = window.advice_panel, window.controller
    assert window.action_advise.shortcut() == QKeySequence("Ctrl+Shift+A")
    assert window.action_advise in window.menuBar().actions()[2].menu().actions()   # Estimate menu
    assert window.inspect.advise_button.defaultAction() is window.action_advise
    assert "noise" in window.action_advise.toolTip() and "irregularity" in window.action_advise.toolTip()

    window.action_advise.trigger()
    # started, not finished: the GUI thread went on, with a busy indicator and Cancel
    assert ctl.advising_now and ctl.busy and window.doc.advice is None
    assert window.progress.isVisible() and window.progress.maximum() == 0 and window.cancel_button.isVisible()
    assert window.status_label.text().startswith("Advising on quadratic")
    assert "Advising on" in panel.status.text()
    qtbot.waitUntil(lambda: window.doc.advice_current and not ctl.busy, timeout=TIMEOUT_MS)
    assert not window.progress.isVisible() and "Advising on" not in panel.status.text()

    expected = curv.advise(window.doc.mesh)              # deterministic: the same answer as the worker's
    assert window.docks["advice"].isVisible() and not window.docks["advice"].visibleRegion().isEmpty()
    assert panel.why.text() == expected.why and panel.why.isVisible()
    assert "quadratic (817 vertices)" in panel.status.text()
    f = expected.features
    values = {name: label.text() for name, label in panel.feature_values.items()}
    assert values["Irregularity"].startswith(f"{f.irregularity_deg:.1f}°")
    assert values["Noise"].startswith(f"{f.noise:.2g} × mean edge")
    assert f"{100 * f.noise_level:.0f} % of the paper's level" in values["Noise"]
    assert 0.2 < f.noise_level < 1.0                      # the surface's 0.05 × edge is about half the level
    assert values["Density"].startswith(f"{f.density:.2g}")
    assert values["Border"].endswith("% of the vertices") and 0.05 < f.border_share < 0.3
    assert float(values["Border"].split()[0]) == pytest.approx(100 * f.border_share, abs=0.5)
    assert values["Polygons"] == f"{f.polygon_kinds[3]} triangles"
    assert values["Vertices"].startswith("817 ")
    assert values["Valence spread"] == f"{f.valence_sd:.2f}" and values["Curvature spread"] == f"{f.curvature_spread:.2f}"
    assert values["Anisotropy"] == f"{f.anisotropy:.2f}"
    assert values["Model residual"].startswith(f"{f.residual_ratio:.2g} ") and 0.2 < f.residual_ratio < 1.5  # noisy
    shown = [name for name, label in panel.feature_values.items() if label.text()]   # a mesh's, not a cloud's
    assert all(panel.feature_values[name].toolTip() for name in shown)
    assert all(panel.feature_labels[name].toolTip() for name in shown)

    table = panel.table
    assert table.rowCount() == len(expected.ranking) > 5
    shown = [{title: table.item(r, c).text() for title, c in COLUMN.items()} for r in range(table.rowCount())]
    assert [(c.method, f"R{c.range}") for c in expected.ranking] == [(s["Estimator"], s["Range"]) for s in shown]
    assert [row.options_short for row in panel.rows] == [s["Options"] for s in shown]
    assert [dict(row.options) for row in panel.rows] == [c.options for c in expected.ranking]
    assert {"deg 4", "fit R4", ""} <= {s["Options"] for s in shown}
    errors = [float(s["Predicted"]) for s in shown]
    shares = [float(s["Valid"].rstrip(" %")) / 100 for s in shown]
    np.testing.assert_allclose(shares, [c.valid_share for c in expected.ranking], atol=0.006)
    # checked: the measured calls first, by their measured error (shown with its spread over the copies)
    assert expected.checked and panel.check.text().startswith("checked ")
    assert "mesh's smooth twin" in panel.check.text() and "&#" not in panel.check.text()
    # the whole panel fits the dock at its narrowest: nothing cut off at the right (the ranking's title
    # once made the panel 383 px wide in a 358 px dock); the measured error is a column a person sees
    scroll = window.docks["advice"].widget()
    assert panel.minimumSizeHint().width() <= 360 - 20
    assert panel.width() <= scroll.viewport().width()
    assert table.columnViewportPosition(COLUMN["Measured"]) < table.viewport().width() // 2
    measured = [c for c in expected.ranking if c.measured is not None and c.measured.ok]
    assert len(measured) >= 3 and expected.ranking[: len(measured)] == measured
    # by measured error, the table's first choice kept first where the copies cannot tell them apart
    assert [c.measured.erel for c in measured[1:]] == sorted(c.measured.erel for c in measured[1:])
    assert measured[0].measured.erel == min(c.measured.erel for c in measured) or measured[1].within_noise
    shown_measured = [table.item(r, COLUMN["Measured"]).text() for r in range(len(measured))]
    assert [t.split()[0] for t in shown_measured] == [f"{c.measured.erel:.3g}" for c in measured]
    assert all(f"×{c.measured.spread:.2f}" in t for c, t in zip(measured, shown_measured))
    assert all(table.item(r, COLUMN["Measured"]).text() == "" for r in range(len(measured), table.rowCount()))
    np.testing.assert_allclose(errors, [c.expected_erel for c in expected.ranking], rtol=5e-3)
    assert (shown[0]["Estimator"], shown[0]["Range"]) == (expected.method, f"R{expected.range}")               # the recommendation on top
    assert table.item(0, 0).font().bold() and not table.item(1, 0).font().bold()
    assert table.item(0, 1).background().color() == QColor(RECOMMENDED_BACKGROUND)
    assert "★" in table.verticalHeaderItem(0).text() and "★" not in table.verticalHeaderItem(1).text()
    assert panel.selected_row() == 0
    assert panel.apply_button.isEnabled()
    assert panel.apply_button.text() == f"Apply {expected.label} to pane A"
    assert "Advice for quadratic" in window.status_label.text()


def test_apply_puts_the_selected_row_into_the_active_pane_and_computes_it(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817, noise=0.02, seed=1)
    advice = _advise(qtbot, window)
    panel, doc = window.advice_panel, window.doc
    assert (doc.panes[0].method, doc.panes[0].range) != (advice.method, advice.range)   # Apply must change it
    qtbot.mouseClick(panel.apply_button, Qt.MouseButton.LeftButton)
    assert doc.panes[0] == Pane(advice.method, advice.range, options=tuple(advice.options.items())).validated()
    ui.wait_ready()
    res = doc.result(0)
    assert res is not None and (res.method, res.range) == (advice.method, advice.range)
    assert window.grid.viewports[0].title.text().startswith(f"A: {advice.label}")

    # another row, in another pane: only the active pane changes
    window.compare.count.setValue(2)
    ui.wait_ready()
    doc.set_active(1)
    before_a = doc.panes[0]
    row = next(r for r, entry in enumerate(panel.rows) if entry.method not in (advice.method, doc.panes[1].method))
    chosen = panel.rows[row]
    panel.select_row(row)
    assert panel.apply_button.text() == f"Apply {chosen.label} to pane B"
    qtbot.mouseClick(panel.apply_button, Qt.MouseButton.LeftButton)
    ui.wait_ready()
    assert doc.panes[0] == before_a
    res = doc.result(1)
    assert (doc.panes[1].method, res.method, res.range) == (chosen.method, chosen.method, chosen.range)

    # double-clicking a row applies that row
    row = next(r for r, entry in enumerate(panel.rows) if entry.method not in (chosen.method, advice.method))
    target = panel.rows[row]
    panel.table.scrollToItem(panel.table.item(row, 0))
    rect = panel.table.visualItemRect(panel.table.item(row, 0))
    # as a person double-clicks: a click (press, release), then the double click
    qtbot.mouseClick(panel.table.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())
    assert panel.selected_row() == row and doc.result(1).method != target.method      # a click only selects
    qtbot.mouseDClick(panel.table.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())
    ui.wait_ready()
    res = doc.result(1)
    assert (res.method, res.range) == (target.method, target.range)


def test_apply_retries_a_pair_that_was_cancelled(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=217)
    advice = _advise(qtbot, window)
    doc = window.doc
    key = Pane(advice.method, advice.range, options=tuple(advice.options.items())).validated().key
    doc.set_failure(key, f"{key[0]} {key[1]} cancelled")   # as the controller records a cancel
    qtbot.mouseClick(window.advice_panel.apply_button, Qt.MouseButton.LeftButton)
    ui.wait_ready()
    assert key in doc.results and key not in doc.failures
    assert (doc.result(0).method, doc.result(0).range) == (advice.method, advice.range)


def test_advise_and_apply_on_a_loaded_file(qtbot, window, ui, tmp_path):
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=3, radius=2.0)
    rng = np.random.default_rng(0)
    edge = float(np.mean(sphere.edges_unique_length))
    vertices = sphere.vertices + rng.normal(scale=0.03 * edge, size=sphere.vertices.shape)
    path = _write_obj(tmp_path / "ball.obj", vertices, sphere.faces)
    _open_file(qtbot, window, ui, path)
    advice = _advise(qtbot, window)
    panel = window.advice_panel
    assert "ball.obj" in panel.status.text() and window.doc.truth is None
    assert panel.feature_values["Border"].text().startswith("0.0 %")              # a closed surface
    assert panel.rows[0].method == advice.method and panel.rows[0].recommended
    qtbot.mouseClick(panel.apply_button, Qt.MouseButton.LeftButton)
    ui.wait_ready()
    res = window.doc.result(0)
    assert (res.method, res.range) == (advice.method, advice.range)
    assert np.nanmedian(res.mean) == pytest.approx(0.5, rel=0.1)                  # outward sphere of radius 2


def test_a_mesh_the_advisor_cannot_measure_gives_one_message_and_keeps_the_viewer(qtbot, window, ui, tmp_path):
    tiny = _write_obj(tmp_path / "tiny.obj", [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0.2)], [(0, 1, 2), (1, 3, 2)])
    with pytest.raises(curv.MeshError, match="cannot advise"):
        curv.advise(curv.load(tiny))
    _open_file(qtbot, window, ui, tiny)
    mesh, result = window.doc.mesh, window.doc.result(0)
    messages = []
    window.error_shown.connect(messages.append)
    with qtbot.waitSignal(window.error_shown, timeout=TIMEOUT_MS) as blocker:
        window.action_advise.trigger()
    text = blocker.args[0]
    assert "tiny.obj" in text and "cannot advise" in text and "\n" not in text and "Traceback" not in text
    assert text in window.status_label.text() and "b00020" in window.status_label.styleSheet()
    qtbot.waitUntil(lambda: not window.controller.busy, timeout=TIMEOUT_MS)
    qtbot.wait(100)
    assert messages == [text]                                                  # one message
    panel = window.advice_panel
    assert "No advice" in panel.status.text() and "cannot advise" in panel.status.text()
    assert not panel.apply_button.isEnabled() and not panel.ranking_box.isVisible()
    assert window.doc.mesh is mesh and window.doc.result(0) is result             # nothing lost
    # the viewer goes on: another mesh advises and applies
    window.open_surface(SurfaceSource(name="saddle", n_vertices=217))
    qtbot.waitUntil(lambda: isinstance(window.doc.source, SurfaceSource), timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert "No advice for saddle" in panel.status.text()                          # the failure was tiny.obj's
    advice = _advise(qtbot, window)
    assert panel.rows[0].method == advice.method and panel.apply_button.isEnabled()


def test_advice_for_an_earlier_mesh_is_stale_and_cannot_be_applied(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=217)
    first = _advise(qtbot, window)
    panel, doc = window.advice_panel, window.doc
    assert not panel.is_stale and panel.table.isEnabled()
    ui.open_surface("torus", n_vertices=642)
    assert panel.is_stale and not doc.advice_current
    status = panel.status.text()
    assert "Stale" in status and "saddle (217 vertices)" in status and "torus (640 vertices)" in status
    assert not panel.apply_button.isEnabled() and not panel.table.isEnabled() and not panel.features_box.isEnabled()
    assert "earlier mesh" in panel.features_box.title()
    pane = doc.panes[0]
    panel.apply_row(0)                                                 # ignored, even when called directly
    qtbot.mouseClick(panel.apply_button, Qt.MouseButton.LeftButton)
    assert doc.panes[0] == pane
    second = _advise(qtbot, window)
    assert not panel.is_stale and panel.table.isEnabled() and panel.apply_button.isEnabled()
    assert "Advice for <b>torus (640 vertices)</b>" in panel.status.text()
    n = doc.mesh.n_vertices
    assert panel.why.text() == second.why and second.features.n_vertices == n != first.features.n_vertices
    assert panel.feature_values["Vertices"].text().startswith(f"{n} ")


def test_a_new_mesh_or_cancel_drops_the_running_advice(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=217)
    panel, doc, ctl = window.advice_panel, window.doc, window.controller
    window.action_advise.trigger()
    assert ctl.advising_now
    window.open_surface(SurfaceSource(name="sphere", n_vertices=642))     # supersedes the advisor
    assert not ctl.advising_now
    qtbot.waitUntil(lambda: doc.source.name == "sphere", timeout=TIMEOUT_MS)
    ui.wait_ready()
    qtbot.wait(500)                                                      # the old worker's answer is dropped
    assert doc.advice is None and "No advice for sphere" in panel.status.text()

    window.action_advise.trigger()
    assert ctl.advising_now and window.action_cancel.isEnabled()
    window.action_cancel.trigger()
    assert not ctl.advising_now and not ctl.busy and window.status_label.text() == "Cancelled"
    qtbot.wait(500)
    assert doc.advice is None and "Advising" not in panel.status.text()


def test_advise_while_a_mesh_loads_advises_that_mesh(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=217)
    window.open_surface(SurfaceSource(name="quadratic", n_vertices=817))
    window.action_advise.trigger()                                     # queued until quadratic is there
    assert "once quadratic (817 vertices) has loaded" in window.status_label.text()
    qtbot.waitUntil(lambda: window.doc.advice_current and not window.controller.busy, timeout=TIMEOUT_MS)
    assert window.doc.advice.source_label == "quadratic (817 vertices)"
    assert window.doc.advice.advice.features.n_vertices == 817


def test_polygon_mesh_ranks_only_estimators_that_take_polygons(qtbot, window, ui, tmp_path):
    n = 16
    xs, ys = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    vertices = np.column_stack([xs.ravel(), ys.ravel(), 0.3 * (xs**2 - ys**2).ravel()])
    quads = [(i * n + j, i * n + j + 1, i * n + j + n + 1, i * n + j + n) for i in range(n - 1) for j in range(n - 1)]
    _open_file(qtbot, window, ui, _write_obj(tmp_path / "grid.obj", vertices, quads))
    advice = _advise(qtbot, window)
    panel = window.advice_panel
    assert panel.feature_values["Polygons"].text() == f"{(n - 1) ** 2} quads"
    methods = {row.method for row in panel.rows}
    assert methods and not any(curv.ESTIMATORS[m].triangles_only for m in methods)
    qtbot.mouseClick(panel.apply_button, Qt.MouseButton.LeftButton)
    ui.wait_ready()
    res = window.doc.result(0)
    assert (res.method, res.range) == (advice.method, advice.range) and res.valid.any()


def test_apply_with_options_sets_them_in_the_pane_and_computes_that_call(qtbot, window, ui):
    ui.open_surface("quadratic", n_vertices=1801, noise=0.05, seed=2)
    advice = _advise(qtbot, window)
    panel, doc = window.advice_panel, window.doc
    jet = next(r for r, row in enumerate(panel.rows) if ("degree", 4) in row.options)
    fit = next(r for r, row in enumerate(panel.rows) if ("normals", "fit") in row.options)
    for r in (jet, fit):
        row, candidate = panel.rows[r], advice.ranking[r]
        panel.select_row(r)
        assert panel.apply_button.text() == f"Apply {row.label} to pane A" and row.options_text in row.label
        qtbot.mouseClick(panel.apply_button, Qt.MouseButton.LeftButton)
        ui.wait_ready()
        assert dict(doc.panes[0].options) == candidate.options
        assert window.grid.viewports[0].title.text().startswith(f"A: {candidate.label}")
        res = doc.result(0)
        expected = curv.estimate(doc.mesh, **candidate.kwargs)                 # the whole call, options included
        np.testing.assert_array_equal(res.valid, expected.valid)
        np.testing.assert_allclose(res.k1[res.valid], expected.k1[expected.valid], rtol=1e-12)
        default = curv.estimate(doc.mesh, method=candidate.method, range=candidate.range)
        assert not np.allclose(res.k1[res.valid], default.k1[res.valid])       # the options changed the result
    # the pane's options outlive the session
    from PySide6.QtCore import QSettings

    from app.views.main_window import MainWindow
    from app.views.session import save_session

    applied = doc.panes[0]
    save_session(window.settings, doc)                                  # what closing the window does
    window.settings.sync()
    again = MainWindow(settings=QSettings(window.settings.fileName(), QSettings.Format.IniFormat))
    qtbot.addWidget(again)
    assert again.doc.panes[0] == applied and applied.options
    again.close()
    # another estimator from the inspector starts from its defaults
    window.inspect.method.setCurrentIndex(window.inspect.method.findData("mru"))
    window.inspect.method.activated.emit(window.inspect.method.currentIndex())
    ui.wait_ready()
    assert doc.panes[0].method == "mru" and doc.panes[0].options == ()


def test_ranking_rows_mark_exactly_the_recommendation():
    from app.model import FEATURE_LABELS, feature_rows, ranking_rows

    sampled = curv.surfaces.make_surface("saddle", n_vertices=217)
    checked = ranking_rows(curv.advise(sampled.mesh))
    assert [r.recommended for r in checked] == [True] + [False] * (len(checked) - 1) and checked[0].measured_text
    advice = curv.advise(sampled.mesh, check=False)   # the table's order: by predicted error
    rows = ranking_rows(advice)
    assert [r.recommended for r in rows] == [True] + [False] * (len(rows) - 1)
    assert (rows[0].method, rows[0].range, rows[0].range_label) == (advice.method, advice.range, f"R{advice.range}")
    first = [r.expected_erel for r in rows if r.valid_share >= rows[0].valid_share - 0.02]
    assert [r.expected_erel for r in rows[: len(first)]] == sorted(first)
    labels = [f.label for f in feature_rows(advice.features)]
    assert labels == list(FEATURE_LABELS) == ["Irregularity", "Noise", "Density", "Model residual", "Valence spread",
                                               "Curvature spread", "Anisotropy", "Border", "Polygons", "Vertices"]
    assert all(f.text and f.tooltip for f in feature_rows(advice.features))
    # the tooltips say which measures the packaged table predicts with, as the table has it
    from curv.advice.advisor import kernel_axes, load_table

    axes = {column for column, _how, _scale in kernel_axes(load_table())}
    tips = {f.label: f.tooltip for f in feature_rows(advice.features)}
    for label, column in (("Model residual", "residual_ratio"), ("Valence spread", "valence_sd"),
                          ("Curvature spread", "curvature_spread"), ("Anisotropy", "anisotropy"),
                          ("Border", "border_share")):
        assert ("One of the table's axes" in tips[label]) == (column in axes), label


def test_snapshot_with_advise_waits_for_the_advice(qtbot, window, ui, tmp_path):
    from app.main import build_parser
    from app.snapshot import Snapshot

    assert build_parser().parse_args(["--advise"]).advise
    snapshot = Snapshot(window, tmp_path / "shot.png", wait_for_advice=True)
    ui.open_surface("saddle", n_vertices=217)
    assert not snapshot.ready()                        # every pane is there, the advice is not
    _advise(qtbot, window)
    assert snapshot.ready()
    ui.open_surface("torus", n_vertices=642)
    assert not snapshot.ready()                        # stale advice does not count
