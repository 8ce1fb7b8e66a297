"""A tiled run's .vtu / .vtp (curv.tiles.vtkout): the arrays, cells and field data of the in-memory
file (curv.save_result), written a block at a time; VTK itself reads it; a failed write leaves
nothing."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.cli import main
from curv.core.errors import CurvError
from curv.tiles import estimate_file
from curv.tiles.files import check_output, default_scratch

from meshes import torus_grid
from test_tiles_files import _write_ply, leftovers
from test_tiles_polygons import mixed_torus, quad_torus, write_polygon_ply

meshio = pytest.importorskip("meshio")

ROWS_IN_FLOAT32 = ("d1", "d2", "normals", "k1_se", "k2_se")
"""Arrays a tile's rows keep in float32 (curv.tiles.scratch.ROW_DTYPE): equal to the in-memory file's
at float32, the precision the tiled PLY test demands of them; every other array bit for bit."""


def _same_arrays(whole: dict, tiled: dict, *, rtol: float = 0.0):
    assert list(whole) == list(tiled)  # the same names in the same order
    for name, a in whole.items():
        b = tiled[name]
        assert a.dtype == b.dtype and a.shape == b.shape, name
        if name in ROWS_IN_FLOAT32:
            a, b = a.astype(np.float32), b.astype(np.float32)
        if rtol and a.dtype.kind == "f":
            np.testing.assert_allclose(a, b, rtol=rtol, atol=1e-6, err_msg=name)
        else:
            assert np.array_equal(a, b, equal_nan=True), name


def _same_vtu(whole, tiled, *, rtol: float = 0.0):
    a, b = meshio.read(whole), meshio.read(tiled)
    assert np.array_equal(a.points, b.points)
    assert [c.type for c in a.cells] == [c.type for c in b.cells]
    assert all(np.array_equal(x.data, y.data) for x, y in zip(a.cells, b.cells))
    _same_arrays(a.point_data, b.point_data, rtol=rtol)
    assert a.field_data.keys() == b.field_data.keys()
    assert all(np.array_equal(a.field_data[k], b.field_data[k]) for k in a.field_data)


def _same_vtp(whole, tiled, *, points: bool, rtol: float = 0.0):
    pv = pytest.importorskip("pyvista")
    a, b = pv.read(whole), pv.read(tiled)
    assert isinstance(b, pv.PolyData) and np.array_equal(a.points, b.points)
    cells = "verts" if points else "faces"
    assert np.array_equal(getattr(a, cells), getattr(b, cells))
    _same_arrays({k: a.point_data[k] for k in a.point_data.keys()},
                 {k: b.point_data[k] for k in b.point_data.keys()}, rtol=rtol)
    assert sorted(a.field_data.keys()) == sorted(b.field_data.keys())
    assert all(np.array_equal(a.field_data[k], b.field_data[k]) for k in a.field_data.keys())


def _vtk_reads(path, n_points: int, n_cells: int):
    """VTK's own reader (through pyvista) takes the streamed file."""
    pv = pytest.importorskip("pyvista")
    data = pv.read(path)
    assert data.n_points == n_points and data.n_cells == n_cells


def _both_suffixes(tmp_path, source, method, range_, *, tile_size, points=False, rtol=0.0, **keywords):
    shape = curv.load(source)
    res = curv.estimate(shape, method, range_, **keywords)
    n_cells = shape.n_vertices if points else shape.n_faces
    for suffix in (".vtu", ".vtp"):
        curv.save_result(tmp_path / f"whole{suffix}", shape, res)
        run = estimate_file(source, tmp_path / f"tiled{suffix}", method, range_, tile_size=tile_size, workers=1,
                            **keywords)
        assert run.tiles >= 3 and run.budget is not None  # streamed and tiled, not read whole
        _vtk_reads(tmp_path / f"tiled{suffix}", shape.n_vertices, n_cells)
        assert not default_scratch(tmp_path / f"tiled{suffix}").exists()
    _same_vtu(tmp_path / "whole.vtu", tmp_path / "tiled.vtu", rtol=rtol)
    _same_vtp(tmp_path / "whole.vtp", tmp_path / "tiled.vtp", points=points, rtol=rtol)
    assert leftovers(tmp_path) == []


def test_a_tiled_triangle_mesh_writes_the_whole_calls_vtu_and_vtp(tmp_path):
    mesh = torus_grid(60, 30)[0]
    _write_ply(tmp_path / "in.ply", mesh.vertices, mesh.face_indices.reshape(-1, 3), dtype="f8")
    _both_suffixes(tmp_path, tmp_path / "in.ply", "csm", 3, tile_size=600)


def test_a_tiled_quad_mesh_writes_the_whole_calls_vtu_and_vtp(tmp_path):
    source = write_polygon_ply(tmp_path / "in.ply", *quad_torus())
    _both_suffixes(tmp_path, source, "mru", 2, tile_size=150)


def test_a_tiled_mesh_of_triangles_quads_and_a_pentagon_keeps_save_vtus_cell_groups(tmp_path, monkeypatch):
    from curv.tiles import polyply

    monkeypatch.setattr(polyply, "BLOCK_BYTES", 1000)  # many face blocks: each group filled across them
    vertices, faces = mixed_torus()
    faces[5] = faces[5] + [faces[6][1]]  # a pentagon among them
    source = write_polygon_ply(tmp_path / "in.ply", vertices, faces)
    _both_suffixes(tmp_path, source, "qs", 2, tile_size=150)
    types = [c.type for c in meshio.read(tmp_path / "tiled.vtu").cells]
    assert types == ["triangle", "quad", "polygon"]


def test_a_tiled_point_cloud_writes_the_whole_calls_vtu_and_vtp(tmp_path):
    from curv.surfaces import Torus, sample_points

    pts = sample_points(Torus(), 8000, sampling="uniform", rng=5).cloud.points
    _write_ply(tmp_path / "in.ply", pts)
    # the tolerance of the tiled PLY test of the same cloud (test_tiles_files)
    _both_suffixes(tmp_path, tmp_path / "in.ply", "jet", None, tile_size=2000, points=True, rtol=1e-5,
                   orient=(0, 0, 10))


def test_a_tiled_las_cloud_writes_vtu_from_the_command(tmp_path, capsys):
    from laspy_samples import laspy_sample

    pytest.importorskip("laspy")
    source = laspy_sample("vegetation_1_3.las")
    out = tmp_path / "tiled.vtu"
    assert main(["estimate", str(source), "-m", "qs", "-r", "2", "-o", str(out), "--tile-size", "3000"]) == 0
    cloud = curv.load(source)
    data = meshio.read(out)
    assert data.points.shape == (cloud.n_points, 3) and [c.type for c in data.cells] == ["vertex"]
    assert np.array_equal(data.points, cloud.points)
    assert {"k1", "normals", "rgba", "shown", "valid", "reason"} <= set(data.point_data)
    assert "reason_BORDER" in data.field_data


def test_a_failed_write_leaves_no_vtu(tmp_path, monkeypatch):
    from curv.tiles import vtkout

    mesh = torus_grid(40, 20)[0]
    _write_ply(tmp_path / "in.ply", mesh.vertices, mesh.face_indices.reshape(-1, 3), dtype="f8")
    monkeypatch.setattr(vtkout, "_BLOCK", 100)  # several blocks: the failure comes half way

    calls = []

    def failing(*args, **keywords):
        calls.append(1)
        if len(calls) == 3:
            raise OSError(28, "No space left on device")
        return columns(*args, **keywords)

    columns = vtkout._block_columns
    monkeypatch.setattr(vtkout, "_block_columns", failing)
    for suffix in (".vtu", ".vtp"):
        calls.clear()
        with pytest.raises(OSError):
            estimate_file(tmp_path / "in.ply", tmp_path / f"out{suffix}", "csm", 3, tile_size=300, workers=1)
        assert not (tmp_path / f"out{suffix}").exists()
        assert leftovers(tmp_path) == []


def test_a_tiled_run_takes_vtu_and_vtp_and_says_what_it_writes(tmp_path):
    for suffix in (".vtu", ".vtp", ".VTU"):
        assert check_output(tmp_path / "in.ply", tmp_path / f"o{suffix}") == suffix.lower()
    with pytest.raises(CurvError, match=r"a tiled run writes \.ply, \.las, \.laz, \.vtu, \.vtp; got \.obj"):
        check_output(tmp_path / "in.ply", tmp_path / "o.obj")


def test_the_outputs_a_tiled_run_offers_put_the_inputs_own_kind_first():
    """One rule for the command's check and the viewer's "Whole file to..." dialog."""
    from app.model.large import whole_file_suffixes
    from curv.tiles import output_suffixes

    assert output_suffixes("scan.LAZ") == [".laz", ".las", ".ply", ".vtu", ".vtp"]
    assert output_suffixes("mesh.ply") == [".ply", ".vtu", ".vtp"]
    assert whole_file_suffixes("scan.las") == output_suffixes("scan.las")
