"""save_ply round trips (trimesh for the colours, plyfile for every property), polygons through
PLY/OBJ/OFF, atomic writes, and repair counts."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from plyfile import PlyData

import curv
from curv.formats import plywrite
from curv.io import peek_counts, save_ply
from curv.geometry.repair import repair
from tests.corpus import _torus_polygons, _write_obj, _write_off, _write_ply


@pytest.fixture(scope="module")
def sphere_result():
    tm = trimesh.creation.icosphere(subdivisions=2)
    mesh = curv.Mesh(tm.vertices, tm.faces)
    return mesh, curv.estimate(mesh, "mru", 2)


@pytest.fixture(scope="module")
def open_result():
    """A sphere with a hole: csm marks border vertices invalid, so NaN and valid=0 are written."""
    tm = trimesh.creation.icosphere(subdivisions=2)
    mesh = curv.Mesh(tm.vertices, np.asarray(tm.faces)[10:])
    closed_ring = next(name for name, spec in curv.ESTIMATORS.items() if spec.closed_ring and 1 in spec.ranges)
    return mesh, curv.estimate(mesh, closed_ring, 1)


def test_save_ply_every_property_round_trips(tmp_path, open_result):
    mesh, res = open_result
    assert not res.valid.all() and res.valid.any()
    path = save_ply(tmp_path / "out.ply", mesh, res, quantity="gaussian", extra={"error_rel": res.k1 * 0 + 0.25})
    vert = PlyData.read(str(path))["vertex"].data
    np.testing.assert_allclose(np.stack([vert[c] for c in "xyz"], axis=1), mesh.vertices)
    for name, values in (("k1", res.k1), ("k2", res.k2), ("mean", res.mean), ("gaussian", res.gaussian)):
        np.testing.assert_allclose(vert[name], values.astype(np.float32), rtol=1e-6, equal_nan=True)
    for i, c in enumerate("xyz"):
        np.testing.assert_allclose(vert[f"d1{c}"], res.d1[:, i].astype(np.float32), equal_nan=True)
        np.testing.assert_allclose(vert[f"d2{c}"], res.d2[:, i].astype(np.float32), equal_nan=True)
    assert np.array_equal(vert["valid"].astype(bool), res.valid)
    assert np.all(np.isnan(vert["k1"][~res.valid]))
    np.testing.assert_allclose(vert["error_rel"][res.valid], 0.25)
    faces = np.stack(PlyData.read(str(path))["face"].data["vertex_indices"])
    assert np.array_equal(faces, mesh.faces)


def test_save_ply_colours_read_by_trimesh(tmp_path, sphere_result):
    mesh, res = sphere_result
    colors = np.zeros((mesh.n_vertices, 4), np.uint8)
    colors[:, 0] = np.arange(mesh.n_vertices) % 256
    colors[:, 3] = 255
    save_ply(tmp_path / "c.ply", mesh, res, colors=colors)
    tm = trimesh.load(tmp_path / "c.ply", process=False)
    assert np.array_equal(np.asarray(tm.visual.vertex_colors), colors)
    assert np.array_equal(np.asarray(tm.faces), mesh.faces)
    # default colours: a diverging map, invalid vertices in a neutral colour, all opaque
    save_ply(tmp_path / "d.ply", mesh, res)
    vc = np.asarray(trimesh.load(tmp_path / "d.ply", process=False).visual.vertex_colors)
    assert vc.shape == (mesh.n_vertices, 4) and np.all(vc[:, 3] == 255)


@pytest.mark.parametrize("writer, suffix", [(_write_ply, "ply"), (_write_obj, "obj"), (_write_off, "off")])
def test_polygons_preserved_on_load(tmp_path, writer, suffix):
    v, faces = _torus_polygons()
    mesh = curv.load(writer(tmp_path / f"m.{suffix}", v, faces))
    assert sorted(map(tuple, (tuple(f) for f in faces))) == sorted(
        tuple(mesh.face_indices[a:b]) for a, b in zip(mesh.face_offsets[:-1], mesh.face_offsets[1:]))
    assert mesh.report().polygon_kinds == {3: 12, 4: 136, 5: 12}


def test_polygons_preserved_through_save_ply(tmp_path):
    v, faces = _torus_polygons()
    mesh = curv.Mesh(v, faces)
    res = curv.estimate(mesh, "mru", 2)
    back = curv.load(save_ply(tmp_path / "p.ply", mesh, res))
    assert np.array_equal(back.face_indices, mesh.face_indices)
    assert np.array_equal(back.face_offsets, mesh.face_offsets)


def test_save_ply_is_atomic_on_failure(tmp_path, sphere_result, monkeypatch):
    mesh, res = sphere_result
    target = tmp_path / "out.ply"
    target.write_bytes(b"old")

    def fail_after_header_and_vertices(fh, mesh):
        # by now the header and the vertex records are in the temporary file
        raise KeyboardInterrupt

    monkeypatch.setattr(plywrite, "_write_face_lists", fail_after_header_and_vertices)
    with pytest.raises(KeyboardInterrupt):
        save_ply(target, mesh, res)
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.ply"]


def test_save_ply_rejects_wrong_sizes_without_writing(tmp_path, sphere_result):
    mesh, res = sphere_result
    other = curv.Mesh(mesh.vertices[:-1], mesh.faces[np.all(mesh.faces < mesh.n_vertices - 1, axis=1)])
    with pytest.raises(curv.MeshError, match="values but the mesh has"):
        save_ply(tmp_path / "x.ply", other, res)
    assert list(tmp_path.iterdir()) == []


def test_fast_triangle_path_and_generic_path_agree(tmp_path, sphere_result):
    mesh, _ = sphere_result
    tri = curv.load(_write_ply(tmp_path / "t.ply", mesh.vertices, mesh.faces))
    mixed_faces = [*mesh.faces.tolist(), [0, 1, 2, 3]]   # one quad forces the generic reader
    mixed = curv.load(_write_ply(tmp_path / "m.ply", mesh.vertices, mixed_faces))
    assert np.array_equal(tri.faces, mesh.faces)
    assert np.array_equal(mixed.face_indices[:-4], mesh.face_indices)
    assert peek_counts(tmp_path / "t.ply") == (mesh.n_vertices, mesh.n_faces)


def test_repairs_report_their_counts():
    tm = trimesh.creation.icosphere(subdivisions=1)
    v, f = np.asarray(tm.vertices), np.asarray(tm.faces)
    soup = curv.Mesh(v[f.reshape(-1)], np.arange(f.size).reshape(-1, 3))
    fixed, lines = repair(soup, merge_vertices=True)
    assert lines == [f"merged {f.size - len(v)} duplicate vertices"]
    assert fixed.n_vertices == len(v) and fixed.report().border_edges == 0
    extra = curv.Mesh(np.vstack([v, [[5, 5, 5]]]), [*f[::-1].tolist(), [0, 0, 1], [1, 2, 2]])
    flipped = np.asarray(extra.faces)[:len(f)]
    flipped[::3] = flipped[::3, ::-1]
    bad = curv.Mesh(extra.vertices, [*flipped.tolist(), [0, 0, 1], [1, 2, 2]])
    fixed, lines = repair(bad, remove_degenerate=True, remove_unreferenced=True, orient=True)
    assert lines[:2] == ["removed 2 degenerate faces", "removed 1 unreferenced vertices"]
    assert lines[2].startswith("flipped ") and lines[2].endswith(" faces to a consistent orientation")
    assert fixed.report().inconsistent_edges == 0
    assert np.sum(fixed.face_vector_areas * fixed.vertices[fixed.faces].mean(1)) > 0   # outward
    assert repair(fixed, merge_vertices=True, remove_degenerate=True, orient=True)[1] == []


def test_save_ply_written_in_blocks_is_the_same_file(tmp_path, sphere_result, monkeypatch):
    mesh, res = sphere_result
    polygons = curv.Mesh(mesh.vertices, [list(f) for f in mesh.faces[:-2]] + [[*mesh.faces[-2], mesh.faces[-1][2]]])
    for m in (mesh, polygons):
        r = curv.estimate(m, "mru", 2)
        whole = save_ply(tmp_path / "whole.ply", m, r, extra={"e": np.arange(m.n_vertices) * 0.5})
        monkeypatch.setattr(plywrite, "_WRITE_BLOCK", 7)  # many blocks, the last one short
        blocks = save_ply(tmp_path / "blocks.ply", m, r, extra={"e": np.arange(m.n_vertices) * 0.5})
        monkeypatch.undo()
        assert blocks.read_bytes() == whole.read_bytes()
        back = PlyData.read(str(blocks))
        assert np.array_equal(back["vertex"]["e"], np.arange(m.n_vertices) * np.float32(0.5))


def _quad_grid(n: int = 6) -> tuple[np.ndarray, np.ndarray]:
    u, v = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float), indexing="ij")
    vertices = np.c_[u.ravel(), v.ravel(), 0.1 * (u * v).ravel()]
    idx = np.arange(n * n).reshape(n, n)
    quads = np.c_[idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    return vertices, quads


def _write_binary_ply(path, vertices, faces, *, byte_order="<", length_type="u1"):
    from plyfile import PlyElement

    vert = np.zeros(len(vertices), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("intensity", "u2")])
    for i, c in enumerate("xyz"):
        vert[c] = vertices[:, i]
    if isinstance(faces, np.ndarray):
        face = np.empty(len(faces), dtype=[("vertex_indices", "i4", (faces.shape[1],))])
    else:
        face = np.empty(len(faces), dtype=[("vertex_indices", object)])
        faces = [np.asarray(f, np.int32) for f in faces]
    face["vertex_indices"] = faces
    elements = [PlyElement.describe(vert, "vertex"),
                PlyElement.describe(face, "face", len_types={"vertex_indices": length_type})]
    PlyData(elements, byte_order=byte_order).write(str(path))
    return path


@pytest.mark.parametrize("byte_order, length_type", [("<", "u1"), (">", "u1"), ("<", "i4"), (">", "u2")])
def test_a_binary_ply_of_quads_is_memory_mapped_whole(tmp_path, monkeypatch, byte_order, length_type):
    from curv.formats import meshread

    vertices, quads = _quad_grid()
    path = _write_binary_ply(tmp_path / "quads.ply", vertices, quads, byte_order=byte_order, length_type=length_type)
    reads = []
    real_read = PlyData.read
    monkeypatch.setattr(PlyData, "read", staticmethod(lambda *a, **kw: reads.append(kw) or real_read(*a, **kw)))
    got_vertices, got_faces = meshread.read_arrays(path)
    assert reads == [{"known_list_len": {"face": {"vertex_indices": 4}}}]  # one read, every face a (4,) row
    assert isinstance(got_faces, np.ndarray) and np.array_equal(got_faces, quads)
    np.testing.assert_allclose(got_vertices, vertices.astype(np.float32))
    assert curv.load(path).report().polygon_kinds == {4: len(quads)}


def test_a_binary_ply_whose_first_face_is_a_quad_but_not_the_rest_is_read_face_by_face(tmp_path):
    from curv.formats import meshread

    vertices, quads = _quad_grid()
    faces = [quads[0].tolist()] + [[a, b, c] for a, b, c, _ in quads[1:].tolist()]
    path = _write_binary_ply(tmp_path / "mixed.ply", vertices, faces)
    got = meshread.read_arrays(path)[1]
    assert [list(f) for f in got] == faces
    assert curv.load(path).report().polygon_kinds == {4: 1, 3: len(quads) - 1}


def test_an_all_quad_mesh_is_written_as_packed_records_and_reads_back(tmp_path):
    vertices, quads = _quad_grid(7)
    mesh = curv.Mesh(vertices, quads)
    path = save_ply(tmp_path / "q.ply", mesh, curv.estimate(mesh, "mru", 2))
    faces = PlyData.read(str(path))["face"].data["vertex_indices"]
    assert np.array_equal(np.stack(faces), quads)
    # a uchar count and four int32 indices a face: 17 bytes each, then nothing
    records = np.c_[np.full((len(quads), 1), 4, np.uint8), quads.astype("<i4").view(np.uint8).reshape(-1, 16)]
    assert path.read_bytes().endswith(records.tobytes())
