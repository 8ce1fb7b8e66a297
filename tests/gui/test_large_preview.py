"""A file too large to draw whole, in the real window under Xvfb: a preview that says what it shows, the
Region dock at full resolution around a pick, and the whole file to an output file with progress and
cancel (app.model.large, app.views.large_panel). The preview limit is lowered so that small files
stand in for large ones."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.gui

import curv  # noqa: E402

from app.model import large  # noqa: E402
from app.model.large import FullResolutionSource, PreviewSource  # noqa: E402

TIMEOUT_MS = 300_000
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def terrain(tmp_path_factory):
    """A 60,000-point aerial-scan-like LAZ (benchmarks/make_terrain_laz.py)."""
    pytest.importorskip("laspy")
    path = tmp_path_factory.mktemp("large") / "terrain.laz"
    subprocess.run([sys.executable, str(ROOT / "benchmarks" / "make_terrain_laz.py"), "60000", str(path)], check=True,
                   env={"PYTHONPATH": str(ROOT)}, capture_output=True)
    return path


@pytest.fixture
def small_limit(monkeypatch):
    monkeypatch.setattr(large, "PREVIEW_LIMIT", 15000)


def _open_preview(qtbot, win, ui, path):
    win.open_path(str(path))
    qtbot.waitUntil(lambda: isinstance(win.doc.source, PreviewSource), timeout=TIMEOUT_MS)
    ui.wait_ready(timeout=TIMEOUT_MS)


def test_a_large_file_opens_as_a_preview_that_says_so(qtbot, window, ui, terrain, small_limit):
    _open_preview(qtbot, window, ui, terrain)
    doc = window.doc
    assert doc.mesh.n_points == 15000  # every 4th of the 60,000
    panel = window.large_panel
    assert "15,000 of 60,000 points shown (every 4th)" in panel.shown.text()
    assert doc.source.label == "terrain.laz (preview)"
    assert panel.whole.isEnabled() and not panel.around.isEnabled()  # nothing picked yet
    window.grab().save(str(terrain.parent / "preview.png"))


def test_the_region_dock_reads_full_resolution_around_a_pick(qtbot, window, ui, terrain, small_limit):
    _open_preview(qtbot, window, ui, terrain)
    doc = window.doc
    centre_index = int(np.argmin(np.linalg.norm(doc.mesh.points[:, :2] - doc.mesh.points[:, :2].mean(axis=0), axis=1)))
    doc.set_picked(centre_index)
    window.region_panel.radius.setText("6")
    window.region_panel.around.click()  # the Region dock's own button
    qtbot.waitUntil(lambda: isinstance(doc.source, FullResolutionSource), timeout=TIMEOUT_MS)
    qtbot.waitUntil(lambda: doc.panes[0].region is not None, timeout=TIMEOUT_MS)
    ui.wait_ready(timeout=TIMEOUT_MS)
    source = doc.source
    ball = source.ball
    centre = np.array(source.centre)
    inside = np.linalg.norm(doc.mesh.points - centre, axis=1) <= 6.0
    assert np.array_equal(np.flatnonzero(inside), ball) and ball.size > 100
    res = doc.result(0)
    whole = curv.estimate(curv.load(terrain), doc.panes[0].method, **{k: v for k, v in doc.panes[0].estimate_kwargs().items()
                                                                        if k != "vertices"})
    # the file's points inside the ball, matched by position: the region's values are the whole file's
    file_points = curv.load(terrain).points
    order = np.lexsort(file_points.T[::-1])
    keys = file_points[order]
    rows = order[np.searchsorted(np.ascontiguousarray(keys).view([("a", "f8"), ("b", "f8"), ("c", "f8")]).ravel(),
                                 np.ascontiguousarray(doc.mesh.points[ball]).view([("a", "f8"), ("b", "f8"),
                                                                                  ("c", "f8")]).ravel())]
    np.testing.assert_allclose(res.k1[ball], whole.k1[rows], rtol=1e-9, atol=1e-12)
    assert np.array_equal(res.reason[ball], whole.reason[rows])
    assert window.large_panel.back.isEnabled()
    window.grab().save(str(terrain.parent / "full_resolution.png"))
    window.large_panel.back.click()
    qtbot.waitUntil(lambda: isinstance(doc.source, PreviewSource), timeout=TIMEOUT_MS)


def test_the_whole_file_runs_to_an_output_with_progress_and_cancel(qtbot, window, ui, terrain, small_limit, tmp_path):
    import laspy

    _open_preview(qtbot, window, ui, terrain)
    panel = window.large_panel
    fractions = []
    panel.job.progress.connect(lambda text, f: fractions.append(f))
    # cancelled at its first progress: no output, the run's finished tiles kept
    out = tmp_path / "cancelled.laz"
    panel.job.progress.connect(lambda text, f: panel.job.cancel() if panel.job.busy and not out.exists() else None)
    panel.start_whole_file(out)
    qtbot.waitUntil(lambda: not panel.job.busy, timeout=TIMEOUT_MS)
    assert "Cancelled" in panel.status.text() and not out.exists()
    panel.job.progress.disconnect()
    panel.job.progress.connect(lambda text, f: fractions.append(f))
    panel.job.progress.connect(panel._progress)
    out = tmp_path / "whole.laz"
    with qtbot.waitSignal(panel.job.done, timeout=TIMEOUT_MS):
        panel.start_whole_file(out)
    assert out.exists() and "Wrote whole.laz: 60,000 points" in panel.status.text()
    assert fractions and max(fractions) > 0.5
    written = laspy.read(out)
    assert len(written.points) == 60000 and "k1" in written.point_format.extra_dimension_names
