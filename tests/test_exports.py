"""Exports (PLY, VTU) and the quantity registry: formats, permissions, header comment, values."""

from __future__ import annotations

import os
import stat
import subprocess
import sys

import numpy as np
import pytest

import curv
from curv.io import save_result
from curv.core.quantities import QUANTITIES, compute


@pytest.fixture
def sphere_result():
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=2, radius=2.0)
    mesh = curv.Mesh(s.vertices, s.faces)
    return mesh, curv.estimate(mesh, "mru", 2)


def test_quantity_registry_values_on_a_sphere_and_a_saddle():
    k1, k2 = np.array([0.5, 2.0]), np.array([0.5, -1.0])
    np.testing.assert_allclose(compute("absolute", k1, k2), [1.0, 3.0])
    np.testing.assert_allclose(compute("rms", k1, k2), np.sqrt(4 * compute("mean", k1, k2) ** 2
                                                               - 2 * compute("gaussian", k1, k2)))
    np.testing.assert_allclose(compute("shape_index", k1, k2)[0], 1.0)
    assert QUANTITIES["shape_index"].natural == (-1.0, 1.0) and not QUANTITIES["rms"].signed
    assert set(curv.QUANTITIES) == set(QUANTITIES)
    with pytest.raises(ValueError, match="absolute"):
        compute("nope", k1, k2)


@pytest.mark.parametrize("suffix", [".ply", ".vtu"])
def test_exports_get_the_permissions_of_a_plain_write(tmp_path, sphere_result, suffix):
    mesh, res = sphere_result
    old = os.umask(0o022)
    try:
        out = save_result(tmp_path / f"out{suffix}", mesh, res)
    finally:
        os.umask(old)
    assert stat.S_IMODE(out.stat().st_mode) == 0o644
    assert [p.name for p in tmp_path.iterdir()] == [out.name]  # no temporary left behind


def test_vtu_point_data_reads_back_in_pyvista(tmp_path, sphere_result):
    pv = pytest.importorskip("pyvista")
    mesh, res = sphere_result
    extra = {"error_rel": np.linspace(0, 1, mesh.n_vertices)}
    out = save_result(tmp_path / "out.vtu", mesh, res, extra=extra)
    grid = pv.read(out)
    assert grid.n_points == mesh.n_vertices and grid.n_cells == mesh.n_faces
    for name in ("k1", "k2", "mean", "gaussian"):
        np.testing.assert_allclose(grid[name], getattr(res, name))
    np.testing.assert_allclose(grid["d1"], res.d1)
    np.testing.assert_array_equal(grid["valid"], res.valid.astype(np.uint8))
    np.testing.assert_array_equal(grid["reason"], res.reason)
    np.testing.assert_allclose(grid["error_rel"], extra["error_rel"])


def test_ply_comment_names_field_estimator_range_map_and_limits(tmp_path, sphere_result):
    from plyfile import PlyData

    mesh, res = sphere_result
    out = curv.save_ply(tmp_path / "a.ply", mesh, res, quantity="gaussian", cmap="magma", clim=(0.1, 0.4))
    assert PlyData.read(str(out)).comments == [
        "curvlab: mru R2, colours show gaussian (magma, limits 0.1 .. 0.4); property 'shown' holds it",
        curv.core.validity.reason_legend()]


def test_cli_refuses_an_output_suffix_it_cannot_write_before_any_work(tmp_path, sphere_result):
    mesh, res = sphere_result
    src = save_result(tmp_path / "in.ply", mesh, res)
    proc = subprocess.run([sys.executable, "-m", "curv.cli", "estimate", str(src), "-q", "-o",
                           str(tmp_path / "out.stl")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.strip().count("\n") == 0 and ".ply, .vtu" in proc.stderr
    assert not (tmp_path / "out.stl").exists()
