"""Meshes as users bring them: unreferenced vertices (airplane.obj), range scans, the sample meshes
of the pymeshlab wheel (when installed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import curv

from tests.gui.conftest import TIMEOUT_MS

pytestmark = pytest.mark.gui

ALL_FIT_METHODS = ["mru", "qs", "nc", "an"]


def _sample_meshes() -> Path | None:
    try:
        import pymeshlab
    except ImportError:
        return None
    folder = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
    return folder if folder.is_dir() else None


def _sphere_with_unreferenced(tmp_path, n_extra: int = 2500) -> Path:
    """An icosphere followed by ``n_extra`` vertices no face uses (like airplane.obj's 1617)."""
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=3, radius=1.5)
    extra = np.random.default_rng(0).normal(size=(n_extra, 3)) * 3
    lines = [f"v {x} {y} {z}" for x, y, z in np.vstack([s.vertices, extra])]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in s.faces]
    path = tmp_path / "sphere_unreferenced.obj"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("method", ALL_FIT_METHODS)
def test_unreferenced_vertices_estimate_in_the_viewer(qtbot, window, ui, tmp_path, method):
    path = _sphere_with_unreferenced(tmp_path)
    window.doc.set_pane(0, method=method, range=2)
    window.open_path(path)
    qtbot.waitUntil(lambda: window.doc.mesh is not None and window.doc.mesh.n_vertices == 642 + 2500,
                    timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert not window.doc.failures, window.doc.failures
    res = window.doc.result(0)
    isolated = window.doc.mesh.isolated_vertices
    assert not res.valid[isolated].any() and np.all(res.reason[isolated] != curv.Reason.OK)
    assert np.nanmedian(res.mean[~isolated]) == pytest.approx(1 / 1.5, rel=0.05)


def test_isolated_block_through_the_api():
    """The reproduction of the bug report: a block made only of isolated vertices."""
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=2)
    verts = np.vstack([s.vertices, np.random.default_rng(1).normal(size=(2500, 3))])
    mesh = curv.Mesh(verts, s.faces)
    gen = curv.iter_estimate(mesh, "mru", 2, block_size=2000)
    try:
        while True:
            next(gen)
    except StopIteration as stop:
        res = stop.value
    assert res.valid[:s.vertices.shape[0]].all() and not res.valid[s.vertices.shape[0]:].any()


@pytest.mark.skipif(_sample_meshes() is None, reason="pymeshlab (its sample meshes) is not installed")
@pytest.mark.parametrize("name", ["airplane.obj", "cube.obj", "bone.ply", "rangemaps/face000.ply"])
def test_sample_meshes_open_and_estimate(qtbot, window, ui, name):
    window.open_path(_sample_meshes() / name)
    qtbot.waitUntil(lambda: window.doc.source is not None and getattr(window.doc.source, "path", "").endswith(
        Path(name).name), timeout=TIMEOUT_MS)
    ui.wait_ready(timeout=60_000)
    assert not window.doc.failures, window.doc.failures
    assert window.doc.result(0).valid.any()


def test_mesh_report_dock_reloads_with_a_repair(qtbot, window, ui, tmp_path):
    path = _sphere_with_unreferenced(tmp_path, n_extra=30)
    window.open_path(path)
    qtbot.waitUntil(lambda: window.doc.mesh is not None and window.doc.mesh.n_vertices == 672, timeout=TIMEOUT_MS)
    ui.wait_ready()
    panel = window.mesh_panel
    assert "30 isolated vertices" in panel.text.text() and panel.reload.isEnabled()
    panel.repairs["remove_unreferenced"].setChecked(True)
    panel.reload.click()
    qtbot.waitUntil(lambda: window.doc.mesh.n_vertices == 642, timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert window.doc.source.repairs == ("remove_unreferenced",)
    assert "repair:" in panel.text.text() and panel.repairs["remove_unreferenced"].isChecked()
