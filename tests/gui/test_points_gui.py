"""Point clouds in the real main window under Xvfb: sampled surfaces and files shown as points,
colours, point size, the estimators a cloud rules out, the Nearest (knn) control, picking, compare
and difference panes, the truth overlay and the export."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui

import curv  # noqa: E402
from curv.estimators import ESTIMATORS, refusal  # noqa: E402
from PySide6.QtCore import QMimeData, QPoint, QPointF, Qt, QUrl  # noqa: E402
from PySide6.QtGui import QDropEvent  # noqa: E402

from app.model import FileSource, Layer, Pane, SurfaceSource, map_colours  # noqa: E402
from app.model.scalars import relative_error  # noqa: E402

TIMEOUT_MS = 300_000
"""Generous: in a fresh checkout the first point-cloud estimate compiles its kernels (numba caches them)."""
SPHERE_R = 2.0


def _shown(win, i=0):
    return np.array(win.grid.viewports[i].colours)


def _open_points(qtbot, win, ui, name="sphere", n=2000, sampling="uniform", **kw):
    win.open_surface(SurfaceSource(name=name, n_vertices=n, sampling=sampling, **kw))
    qtbot.waitUntil(lambda: win.doc.source is not None and getattr(win.doc.source, "sampling", None) == sampling
                    and win.doc.source.name == name, timeout=TIMEOUT_MS)
    ui.wait_ready(timeout=TIMEOUT_MS)


def _ink(img) -> int:
    """Pixels that are not the white background."""
    return int((img[..., :3] < 245).any(axis=-1).sum())


def test_sampled_torus_is_drawn_as_points_coloured_by_h(qtbot, window, ui):
    _open_points(qtbot, window, ui, "torus", n=3000)
    doc, vp = window.doc, window.grid.viewports[0]
    n = doc.mesh.n_points
    assert doc.is_points and isinstance(doc.mesh, curv.PointCloud) and abs(n - 3000) < 100
    assert doc.source.label == f"torus ({n} points, uniform random)"                # the count the cloud has
    assert vp.points_only and vp.poly.n_cells == vp.poly.n_verts == n and vp.poly.GetNumberOfPolys() == 0
    prop = vp._mesh_actor.prop
    assert prop.style == "Points" and prop.render_points_as_spheres
    res = doc.result(0)
    assert res.n == n and np.isfinite(res.mean[res.valid]).all()
    values, clim, cmap = doc.fields()[0]
    np.testing.assert_allclose(values, res.mean)
    np.testing.assert_array_equal(_shown(window), map_colours(res.mean, clim, cmap))
    # the outer equator bends the most in H: warmer than the inner one
    rho = np.hypot(doc.mesh.points[:, 0], doc.mesh.points[:, 1])
    outer, inner = rho > 1.3, rho < 0.7
    # outward torus (1, 0.4): H = 1.61 on the outer equator, 0.42 on the inner one
    assert np.nanmedian(res.mean[outer]) > np.nanmedian(res.mean[inner]) + 0.8
    assert (_shown(window)[outer, 0].astype(int) - _shown(window)[inner, 0].mean()).mean() > 40
    img = vp.plotter.screenshot(return_img=True)
    assert len(np.unique(img.reshape(-1, img.shape[-1]), axis=0)) > 50   # shaded, coloured spheres
    assert "Invalid points (magenta)" in window.inspect.invalid.text()
    assert window.docks["readout"].windowTitle() == "Picked point"
    assert window.docks["mesh"].windowTitle() == "Point cloud report"
    assert window.inspect.point_size.isEnabled() and not window.inspect.edges.isEnabled()
    assert not window.feature_control.isEnabled() and not window.action_advise.isEnabled()


def test_point_size_control_grows_the_drawn_points(qtbot, window, ui):
    _open_points(qtbot, window, ui, "sphere", n=1500)
    vp = window.grid.viewports[0]
    window.inspect.point_size.setValue(2)
    assert window.doc.display.state.point_size == 2 and vp._mesh_actor.prop.point_size == 2
    qtbot.waitUntil(lambda: not window.drawing.pending)  # the frame is drawn once the loop is free
    small = _ink(vp.plotter.screenshot(return_img=True))
    window.inspect.point_size.setValue(14)
    assert window.doc.display.state.point_size == 14 and vp._mesh_actor.prop.point_size == 14
    qtbot.waitUntil(lambda: not window.drawing.pending)
    big = _ink(vp.plotter.screenshot(return_img=True))
    assert big > 1.5 * small
    window.compare.count.setValue(2)       # a new pane draws its points at the same size
    ui.wait_ready(timeout=TIMEOUT_MS)
    assert window.grid.viewports[1]._mesh_actor.prop.point_size == 14


def test_face_based_estimators_are_greyed_out_with_the_library_reason(qtbot, window, ui):
    window.doc.set_pane(0, method="meyer", range=1)
    _open_points(qtbot, window, ui, "sphere", n=1500)
    doc, combo = window.doc, window.inspect.method
    assert refusal(ESTIMATORS[doc.panes[0].method], doc.mesh) is None   # the pane moved to one that runs
    refused = {name: refusal(spec, doc.mesh) for name, spec in ESTIMATORS.items()}
    assert any(refused.values()) and not all(refused.values())
    for name, why in refused.items():
        i = combo.findData(name)
        assert combo.model().item(i).isEnabled() == (why is None)
        if why is not None:
            assert why in combo.itemData(i, Qt.ItemDataRole.ToolTipRole)
    face_based = next(name for name, why in refused.items() if why)
    before = doc.panes[0]
    combo.setCurrentIndex(combo.findData(face_based))                  # chosen anyway: refused, said why
    assert refused[face_based] in window.status_label.text() and doc.panes[0] == before


def test_nearest_control_sets_a_knn_pane_validated_by_the_library(qtbot, window, ui):
    _open_points(qtbot, window, ui, "sphere", n=1500, params={"radius": SPHERE_R})
    ins, doc = window.inspect, window.doc
    assert ins.use_knn.isEnabled() and not ins.knn.isEnabled()
    ins.use_knn.setChecked(True)
    ui.wait_ready(timeout=TIMEOUT_MS)
    pane = doc.panes[0]
    assert pane.knn == ins.knn.value() and pane.radius is None
    assert pane.label == curv.core.ranges.resolve(ESTIMATORS[pane.method], knn=pane.knn).label
    assert pane.label in window.grid.viewports[0].title.text()
    res = doc.result(0)
    assert np.nanmedian(res.mean) == pytest.approx(1 / SPHERE_R, rel=0.05)   # outward sphere: +1/r
    assert not ins.range.isEnabled()
    with pytest.raises(curv.EstimatorError) as refused:
        curv.core.ranges.resolve(ESTIMATORS[pane.method], knn=1)
    ins.knn.setValue(1)                                   # a K the library refuses: its message, no estimate
    assert str(refused.value) in window.status_label.text() and doc.panes[0].knn == pane.knn
    ins.range.setEditText("R3")
    ins.range.lineEdit().editingFinished.emit()
    ui.wait_ready(timeout=TIMEOUT_MS)
    assert doc.panes[0].knn is None and doc.panes[0].range == 3


def test_pick_a_point_and_read_it_out(qtbot, window, ui):
    _open_points(qtbot, window, ui, "sphere", n=1500, params={"radius": SPHERE_R})
    window.compare.count.setValue(2)
    ui.wait_ready(timeout=TIMEOUT_MS)
    doc, vp = window.doc, window.grid.viewports[0]
    cam = np.array(vp.plotter.camera.position)
    pts = doc.mesh.points
    target = int(np.argmin(np.linalg.norm(pts - SPHERE_R * cam / np.linalg.norm(cam), axis=1)))  # faces the camera
    x, y = vp.display_position(pts[target])
    qtbot.mouseClick(vp.plotter, Qt.MouseButton.LeftButton, pos=QPoint(int(round(x)), int(round(y))))
    qtbot.waitUntil(lambda: doc.picked is not None, timeout=5000)
    picked = doc.picked
    spacing = np.sort(np.linalg.norm(pts - pts[target], axis=1))[6]
    assert np.linalg.norm(pts[picked] - pts[target]) <= 2 * spacing       # the point under the cursor, not behind
    assert pts[picked] @ cam > 0
    text = window.readout.toPlainText()
    assert f"point {picked}" in text and "exact" in text
    assert f"A: {doc.panes[0].title}" in text and f"B: {doc.panes[1].title}" in text
    assert f"{doc.result(1).k1[picked]:.5g}" in text and f"{doc.truth.k2[picked]:.5g}" in text
    assert vp._marker_actor is not None


def test_compare_difference_and_truth_overlay_on_points(qtbot, window, ui):
    _open_points(qtbot, window, ui, "ellipsoid_patch", n=3169, sampling="blue")
    doc = window.doc
    window.compare.count.setValue(2)
    ui.wait_ready(timeout=TIMEOUT_MS)
    a, b = doc.result(0), doc.result(1)
    assert a is not None and b is not None and doc.panes[0].method != doc.panes[1].method
    window.compare.difference.setChecked(True)
    assert len(window.grid.viewports) == 3
    np.testing.assert_allclose(doc.fields()[2][0], a.mean - b.mean)
    np.testing.assert_array_equal(_shown(window, 2), map_colours(*doc.fields()[2]))
    window.inspect.layer.setCurrentEnum(Layer.E_REL)
    np.testing.assert_allclose(doc.fields()[0][0], relative_error(a, doc.truth))
    np.testing.assert_array_equal(_shown(window, 0), map_colours(*doc.fields()[0]))
    interior = np.isfinite(doc.fields()[0][0])
    assert np.median(doc.fields()[0][0][interior]) < 0.2     # points estimate the patch, not noise


def test_export_ply_of_points_holds_the_points_and_the_estimate(qtbot, window, ui, tmp_path):
    from plyfile import PlyData

    _open_points(qtbot, window, ui, "torus", n=2000)
    out = window.export_ply(tmp_path / "cloud.ply")
    ply = PlyData.read(str(out))
    assert [e.name for e in ply.elements] == ["vertex"]                   # a point cloud: no faces
    vert = ply["vertex"].data
    doc, res = window.doc, window.doc.result(0)
    np.testing.assert_allclose(np.column_stack([vert["x"], vert["y"], vert["z"]]), doc.mesh.points, rtol=1e-6)
    np.testing.assert_allclose(vert["k1"], res.k1, rtol=1e-5, atol=1e-6, equal_nan=True)
    np.testing.assert_allclose(vert["exact_mean"], doc.truth.mean, rtol=1e-5, atol=1e-6)
    colours = np.column_stack([vert["red"], vert["green"], vert["blue"]])
    np.testing.assert_array_equal(colours, _shown(window)[:, :3])
    again = curv.load(out)
    assert isinstance(again, curv.PointCloud) and again.n_points == 2000


def test_export_vtu_of_points_reads_back_in_pyvista(qtbot, window, ui, tmp_path):
    import pyvista as pv

    _open_points(qtbot, window, ui, "sphere", n=1500)
    out = window.export_vtu(tmp_path / "cloud.vtu")
    grid = pv.read(out)
    assert grid.n_points == 1500
    np.testing.assert_allclose(grid.point_data["k2"], window.doc.result(0).k2, rtol=1e-5, atol=1e-6, equal_nan=True)


def test_open_point_files_by_path_and_drop(qtbot, window, ui, tmp_path):
    rng = np.random.default_rng(3)
    p = rng.normal(size=(1200, 3))
    p *= SPHERE_R / np.linalg.norm(p, axis=1, keepdims=True)
    path = tmp_path / "ball.xyz"
    np.savetxt(path, np.column_stack([p, p / SPHERE_R]))                # with outward normals
    window.open_path(path)
    qtbot.waitUntil(lambda: isinstance(window.doc.source, FileSource), timeout=TIMEOUT_MS)
    ui.wait_ready(timeout=TIMEOUT_MS)
    doc = window.doc
    assert doc.is_points and doc.mesh.n_points == 1200 and doc.truth is None
    np.testing.assert_allclose(doc.mesh.normals, p / SPHERE_R)
    assert "1,200 points" in window.mesh_panel.text.text() and "normals from the file" in window.mesh_panel.text.text() and not window.mesh_panel.reload.isEnabled()
    assert np.nanmedian(doc.result(0).mean) == pytest.approx(1 / SPHERE_R, rel=0.1)
    assert "nearest" not in doc.mesh.__dict__   # report and estimate shared one search, in grid order
    assert not window.inspect.layer.model().item(list(Layer).index(Layer.E_REL)).isEnabled()
    ply = tmp_path / "dots.ply"
    with open(ply, "w") as f:                                         # a vertex-only PLY is a point cloud too
        f.write("ply\nformat ascii 1.0\nelement vertex 600\nproperty float x\nproperty float y\n"
                "property float z\nend_header\n")
        np.savetxt(f, p[:600])
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(ply))])
    window.dropEvent(QDropEvent(QPointF(10, 10), Qt.DropAction.CopyAction, mime, Qt.MouseButton.NoButton,
                                Qt.KeyboardModifier.NoModifier))
    qtbot.waitUntil(lambda: window.doc.source.path == str(ply), timeout=TIMEOUT_MS)
    ui.wait_ready(timeout=TIMEOUT_MS)
    assert window.doc.is_points and window.doc.mesh.n_points == 600 and window.doc.mesh.normals is None


def test_a_mesh_after_points_drops_knn_and_draws_faces(qtbot, window, ui):
    _open_points(qtbot, window, ui, "sphere", n=1500)
    window.inspect.use_knn.setChecked(True)
    ui.wait_ready(timeout=TIMEOUT_MS)
    assert window.doc.panes[0].knn is not None
    ui.open_surface("saddle", n_vertices=217)
    doc, vp = window.doc, window.grid.viewports[0]
    assert not doc.is_points and doc.panes[0].knn is None and doc.result(0) is not None
    assert not vp.points_only and vp.poly.GetNumberOfPolys() > 0 and vp._mesh_actor.prop.style == "Surface"
    assert not window.inspect.use_knn.isEnabled() and window.inspect.edges.isEnabled()
    assert window.docks["readout"].windowTitle() == "Picked vertex" and window.action_advise.isEnabled()


def test_source_panel_samples_a_surface_as_points(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=217)
    panel = window.source_panel
    panel.sampling.setCurrentIndex(panel.sampling.findData("uniform"))
    qtbot.waitUntil(lambda: window.doc.is_points, timeout=TIMEOUT_MS)
    ui.wait_ready(timeout=TIMEOUT_MS)
    assert window.doc.source.sampling == "uniform" and window.doc.truth is not None
    assert window.doc.mesh.n_points == window.doc.truth.k1.shape[0]
    assert "Points" == panel.density_label.text() and not panel.irregularity.isEnabled()
    assert panel.noise.suffix() == " × spacing"
    panel.density.setEditText("500")                                  # any count: not snapped to a hexagon
    qtbot.waitUntil(lambda: window.doc.mesh.n_points == 500, timeout=TIMEOUT_MS)


def test_command_line_options_for_points(qtbot, window):
    from app.main import build_parser, configure

    args = build_parser().parse_args(["--surface", "torus", "--sample", "rows", "--vertices", "4000",
                                      "--method", "qs", "--knn", "24", "--point-size", "9"])
    source = configure(window, args)
    assert source == SurfaceSource(name="torus", n_vertices=4000, sampling="rows")
    assert window.doc.panes[0] == Pane("qs", 2, knn=24).validated() and window.doc.display.state.point_size == 9
    for bad in (["--sample", "nosuch"], ["--point-size", "500"], ["--knn", "1"]):
        with pytest.raises(ValueError):
            configure(window, build_parser().parse_args(["--surface", "sphere", *bad]))


def test_radius_directions_and_a_region_on_points(qtbot, window, ui):
    _open_points(qtbot, window, ui, "torus", n=3000)
    doc, ins, vp = window.doc, window.inspect, window.grid.viewports[0]
    spacing = float(np.median(curv.core.ranges.point_spacing(doc.mesh)))
    ins.use_radius.setChecked(True)                      # offered: two spacings, in mesh units
    ui.wait_ready(timeout=TIMEOUT_MS)
    assert doc.panes[0].radius == pytest.approx(2 * spacing, rel=1e-5) and doc.panes[0].knn is None
    assert doc.result(0) is not None and f"r={doc.panes[0].radius:g}" in vp.title.text()
    ins.directions.setChecked(True)
    d1, d2 = (a.mapper.dataset for a in vp._glyph_actors)
    assert d1.n_cells > 50 and d1.n_cells == d2.n_cells
    ends = np.asarray(d1.points).reshape(-1, 2, 3)
    centre = ends.mean(axis=1)
    nearest = np.argmin(((centre[:, None, :] - doc.mesh.points[None, :, :]) ** 2).sum(-1), axis=1)
    lift = np.linalg.norm(centre - doc.mesh.points[nearest], axis=1)
    assert np.all(lift > 0.5 * doc.display.state.point_size * vp.pixel_length())  # above the points' spheres
    doc.set_picked(0)
    window.region_panel.around.click()
    ui.wait_ready(timeout=TIMEOUT_MS)
    region = doc.panes[0].region
    assert region is not None and 0 < region.size < doc.mesh.n_points and 0 in region.vertices
    own = doc.results[doc.panes[0].key]                    # estimated only there
    outside = np.setdiff1d(np.arange(doc.mesh.n_points), region.vertices)
    assert np.all(own.reason[outside] == curv.Reason.NOT_COMPUTED)
    assert own.valid[region.vertices].mean() > 0.9


def test_panes_on_a_cloud_take_estimators_that_run_on_points():
    from app.model import Document

    order = ("mru", "meyer", "nc", "csm", "qs", "jet")                # face-based ones early
    defaults = tuple(Pane.default(m) for m in order)
    doc = Document(default_panes=defaults)
    doc.panes_asked = True  # panes the user named: only a refusal moves them (not the default per input kind)
    doc.set_pane_count(3)
    assert [p.method for p in doc.panes] == ["mru", "meyer", "nc"]
    cloud = curv.PointCloud(np.random.default_rng(0).normal(size=(200, 3)))
    doc.set_mesh(None, cloud)                                # meyer cannot run on points: replaced
    assert [p.method for p in doc.panes] == ["mru", "qs", "nc"]
    doc.set_pane_count(1)
    doc.set_pane_count(4)                                    # new panes: the defaults that run on points
    assert [p.method for p in doc.panes] == ["mru", "nc", "qs", "jet"]
    doc.set_mesh(None, curv.surfaces.make_surface("sphere", n_vertices=162).mesh)
    doc.set_pane_count(1)
    doc.set_pane_count(4)                                    # a mesh: the defaults in their order
    assert [p.method for p in doc.panes] == ["mru", "meyer", "nc", "csm"]
