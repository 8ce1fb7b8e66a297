"""The CLI, export and conversion fixes of the second new-user trial (issue 20, items 3, 12, 13)."""

import subprocess
import sys

import meshio
import numpy as np
import plyfile
import pytest
import trimesh

import curv
from curv.cli import main
from curv.convert import as_mesh
from curv.core.quantities import EXPORTED, QUANTITIES
from tests.meshes import icosphere


@pytest.fixture(scope="module")
def sphere_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "sphere.ply"
    mesh = icosphere(2)
    curv.save_ply(path, mesh, curv.estimate(mesh, "qs"))
    return path


@pytest.mark.parametrize("args, words", [
    (["--cmap", "nosuch"], "unknown colour map 'nosuch'"),
    (["--clim", "5", "-5"], "LO < HI"),
    (["--clim", "1", "1"], "LO < HI"),
])
def test_bad_colours_are_one_line_errors_before_any_work(sphere_file, tmp_path, capsys, args, words):
    out = tmp_path / "out.ply"
    code = main(["estimate", str(sphere_file), "-m", "qs", "-o", str(out), *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and words in err and "internal error" not in err
    assert len(err.splitlines()) == 1
    assert not out.exists()  # nothing was estimated or written


def test_summary_times_the_write(sphere_file, tmp_path, capsys):
    assert main(["estimate", str(sphere_file), "-m", "qs", "-o", str(tmp_path / "o.vtu")]) == 0
    line = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("time:")][0]
    assert "load" in line and "estimate" in line and "write" in line


def test_jet_weights_flag_is_the_librarys_option(sphere_file, tmp_path, capsys):
    out = tmp_path / "smooth.ply"
    assert main(["estimate", str(sphere_file), "-m", "jet", "-r", "3", "--weights", "smooth", "-o", str(out), "-q"]) == 0
    k1 = plyfile.PlyData.read(str(out))["vertex"]["k1"]
    mesh = curv.load(sphere_file)
    np.testing.assert_allclose(k1, curv.estimate(mesh, "jet", 3, weights="smooth").k1, rtol=1e-6)
    assert not np.allclose(k1, curv.estimate(mesh, "jet", 3).k1, rtol=1e-9, atol=0)
    capsys.readouterr()
    assert main(["estimate", str(sphere_file), "-m", "qs", "--weights", "smooth", "-q"]) == 2
    assert "has no option 'weights'" in capsys.readouterr().err


def test_jet_width_flag_is_the_librarys_option(tmp_path, capsys):
    noisy = curv.surfaces.make_surface("sphere", n_vertices=642, noise=0.1, seed=3).mesh
    src, out = tmp_path / "noisy.ply", tmp_path / "adaptive.ply"
    curv.save_ply(src, noisy, curv.estimate(noisy, "qs"))
    assert main(["estimate", str(src), "-m", "jet", "-r", "4", "--width", "adaptive", "-o", str(out), "-q"]) == 0
    k1 = plyfile.PlyData.read(str(out))["vertex"]["k1"]
    mesh = curv.load(src)
    np.testing.assert_allclose(k1, curv.estimate(mesh, "jet", 4, width="adaptive").k1, rtol=1e-6, equal_nan=True)
    assert not np.allclose(k1, curv.estimate(mesh, "jet", 4).k1, rtol=1e-9, atol=0, equal_nan=True)
    capsys.readouterr()
    assert main(["estimate", str(src), "-m", "qs", "--width", "adaptive", "-q"]) == 2
    assert "has no option 'width'" in capsys.readouterr().err


def test_no_standard_errors_flag_keeps_the_curvatures_and_drops_the_errors(sphere_file, tmp_path):
    out, ref = tmp_path / "no_se.ply", tmp_path / "se.ply"
    assert main(["estimate", str(sphere_file), "-m", "an", "-r", "3", "--no-standard-errors", "-o", str(out), "-q"]) == 0
    assert main(["estimate", str(sphere_file), "-m", "an", "-r", "3", "-o", str(ref), "-q"]) == 0
    skipped, kept = plyfile.PlyData.read(str(out))["vertex"], plyfile.PlyData.read(str(ref))["vertex"]
    assert np.isnan(skipped["k1_se"]).all() and np.isnan(skipped["k2_se"]).all()
    assert np.isfinite(kept["k1_se"]).any()
    np.testing.assert_array_equal(skipped["k1"], kept["k1"])
    np.testing.assert_array_equal(skipped["k2"], kept["k2"])


def test_noise_model_flag_is_the_librarys_option(tmp_path):
    noisy = curv.surfaces.make_surface("sphere", n_vertices=642, noise=0.05, seed=3).mesh
    path, out = tmp_path / "noisy.ply", tmp_path / "mru.ply"
    curv.save_ply(path, noisy, curv.estimate(noisy, "qs"))
    assert main(["estimate", str(path), "-m", "mru", "-r", "2", "--noise-model", "normals", "-o", str(out), "-q"]) == 0
    se = plyfile.PlyData.read(str(out))["vertex"]["k1_se"]
    mesh = curv.load(path)
    modelled = curv.estimate(mesh, "mru", 2, noise_model="normals").k1_se
    np.testing.assert_allclose(se, modelled, rtol=1e-6)
    independent = curv.estimate(mesh, "mru", 2, noise_model="independent").k1_se
    assert not np.allclose(modelled, independent, rtol=0.05, equal_nan=True)


def test_ply_export_has_shown_and_named_reasons(sphere_file, tmp_path):
    out = tmp_path / "o.ply"
    assert main(["estimate", str(sphere_file), "-m", "qs", "-q", "--quantity", "gaussian", "-o", str(out)]) == 0
    ply = plyfile.PlyData.read(out)
    v = ply["vertex"].data
    res = curv.estimate(curv.load(sphere_file), "qs")
    np.testing.assert_allclose(v["shown"], res.gaussian, rtol=1e-6)
    assert "reason" in v.dtype.names and v["reason"].dtype == np.uint8
    legend = [c for c in ply.comments if c.startswith("reason codes")][0]
    assert all(f"{int(r)} {r.name}" in legend for r in curv.Reason)
    assert set(EXPORTED) <= set(v.dtype.names)


def test_vtu_export_names_the_reason_codes(sphere_file, tmp_path):
    out = tmp_path / "o.vtu"
    mesh = curv.load(sphere_file)
    curv.save_result(out, mesh, curv.estimate(mesh, "qs"))
    text = out.read_text(errors="replace")
    for r in curv.Reason:
        assert f'Name="reason_{r.name}"' in text
    grid = meshio.read(out)  # still a valid file for meshio
    assert "shown" in grid.point_data and grid.points.shape[0] == mesh.n_vertices


def test_list_says_which_estimators_are_invalid_at_borders(capsys):
    assert main(["list"]) == 0
    rows = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()[2:] if line[:1].isalpha()}
    for name, spec in curv.ESTIMATORS.items():
        assert ("invalid" in rows[name]) == spec.closed_ring


def _tet():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return v, f


def test_other_libraries_meshes_are_accepted():
    tm = trimesh.creation.icosphere(subdivisions=2)
    got = curv.estimate(tm, "qs")
    ref = curv.estimate(curv.Mesh(tm.vertices, tm.faces), "qs")
    np.testing.assert_array_equal(got.k1, ref.k1)
    v, f = _tet()
    mm = meshio.Mesh(v, [("triangle", f)])
    assert as_mesh(mm).n_faces == 4
    mixed = meshio.Mesh(v, [("triangle", f[:2]), ("quad", np.array([[0, 1, 2, 3]]))])
    assert sorted(as_mesh(mixed).face_sizes.tolist()) == [3, 3, 4]
    with pytest.raises(curv.MeshError, match="no surface faces"):
        as_mesh(meshio.Mesh(v, [("line", np.array([[0, 1]]))]))
    with pytest.raises(curv.MeshError, match=r"an array of points must have shape \(n, 3\); got \(3, 2\)"):
        curv.estimate(np.zeros((3, 2)))


def test_pyvista_polydata_is_accepted():
    pv = pytest.importorskip("pyvista")
    sphere = pv.Sphere(theta_resolution=16, phi_resolution=12)
    mesh = as_mesh(sphere)
    assert mesh.n_vertices == sphere.n_points and mesh.n_faces == sphere.n_cells
    v, _ = _tet()
    mixed = pv.PolyData(v, faces=[3, 0, 1, 2, 4, 0, 1, 2, 3])
    assert as_mesh(mixed).face_sizes.tolist() == [3, 4]
    with pytest.raises(curv.MeshError, match="needs a mesh's faces; got a point cloud"):
        as_mesh(pv.PolyData(v))  # points alone: a cloud (curv.convert.as_input)
    with pytest.raises(curv.MeshError, match="no polygon faces, only lines or strips"):
        as_mesh(pv.PolyData(v, lines=[2, 0, 1]))


def test_save_vtu_is_top_level_and_quantities_have_one_owner():
    assert curv.save_vtu is curv.io.save_vtu and curv.save_result is curv.io.save_result
    assert curv.QUANTITIES is QUANTITIES
    mesh = icosphere(1)
    res = curv.estimate(mesh, "qs")
    for name in ("mean", "gaussian", "shape_index", "curvedness"):
        np.testing.assert_array_equal(getattr(res, name), QUANTITIES[name].fn(res.k1, res.k2))


def test_package_data_is_declared_without_setuptools_warnings():
    text = open("pyproject.toml").read()
    assert 'license = "MIT"' in text
    assert '"curv.data"' in text and '"app.resources.samples"' in text
