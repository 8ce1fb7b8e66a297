"""A binary PLY of polygons on tiles (curv.tiles.polyply): read a block of bytes at a time in both
byte orders and every list type, tiled with its faces padded, and written back as polygons: the
same file as the whole call's for every estimator that runs on polygon meshes; bad files are the
whole reader's one-line errors and leave no output."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.core.errors import LoadError
from curv.estimators.registry import polygon_estimators
from curv.tiles import estimate_file
from curv.tiles.files import default_scratch
from curv.tiles.polyply import PolygonPlySource
from curv.tiles.sources import open_source

from meshes import torus_grid

_PLY_TYPES = {"u1": "uchar", "u2": "ushort", "u4": "uint", "i1": "char", "i2": "short", "i4": "int"}


def write_polygon_ply(path, vertices, faces, *, order="<", count="u1", index="i4", face_count=None):
    """A binary PLY of double vertices and ``faces`` (a list of corner lists) written by hand."""
    form = {"<": "binary_little_endian", ">": "binary_big_endian"}[order]
    head = (f"ply\nformat {form} 1.0\ncomment polygons\nelement vertex {len(vertices)}\nproperty double x\n"
            f"property double y\nproperty double z\nelement face {len(faces) if face_count is None else face_count}\n"
            f"property list {_PLY_TYPES[count]} {_PLY_TYPES[index]} vertex_indices\nend_header\n")
    with open(path, "wb") as fh:
        fh.write(head.encode("ascii"))
        fh.write(np.asarray(vertices, order + "f8").tobytes())
        fh.write(b"".join(np.array([len(f)], order + count).tobytes() + np.asarray(f, order + index).tobytes()
                          for f in faces))
    return path


def quad_torus(n_major=36, n_minor=16):
    mesh = torus_grid(n_major, n_minor, quads=True)[0]
    return mesh.vertices, [list(f) for f in mesh.faces]


def mixed_torus(n_major=36, n_minor=16):
    """Every other quad of a torus cut into two triangles: faces of 3 and 4 corners, interleaved."""
    vertices, quads = quad_torus(n_major, n_minor)
    faces = []
    for i, f in enumerate(quads):
        faces += [f] if i % 2 else [[f[0], f[1], f[2]], [f[0], f[2], f[3]]]
    return vertices, faces


def _ply(path):
    from plyfile import PlyData

    data = PlyData.read(str(path))
    return data["vertex"].data, list(data["face"].data["vertex_indices"]), data.comments


def _same_file_as_whole(tmp_path, source, method, range_=2, tile_size=150, **keywords):
    """The tiled run writes the whole call's PLY, bit for bit, and the input's polygons."""
    mesh = curv.load(source)
    curv.save_ply(tmp_path / "whole.ply", mesh, curv.estimate(mesh, method, range_, **keywords))
    run = estimate_file(source, tmp_path / "tiled.ply", method, range_, tile_size=tile_size, workers=1, **keywords)
    assert run.tiles >= 3 and run.budget is not None  # streamed and tiled, not read whole
    (a, fa, ca), (b, fb, cb) = _ply(tmp_path / "whole.ply"), _ply(tmp_path / "tiled.ply")
    assert a.dtype == b.dtype and ca == cb
    for name in a.dtype.names:
        assert np.array_equal(a[name], b[name], equal_nan=True), (method, name)
    assert len(fa) == len(fb) == mesh.n_faces
    assert all(np.array_equal(x, y) for x, y in zip(fa, fb))
    assert not default_scratch(tmp_path / "tiled.ply").exists()
    return run


@pytest.mark.parametrize("order", ["<", ">"])
def test_a_quad_mesh_is_read_a_block_at_a_time_as_the_whole_reader_reads_it(tmp_path, monkeypatch, order):
    from curv.tiles import polyply

    monkeypatch.setattr(polyply, "BLOCK_BYTES", 100)  # records cut across blocks, carried over
    monkeypatch.setattr(polyply, "MARK_EVERY", 7)
    vertices, faces = mixed_torus(12, 8)
    faces[5] = faces[5] + [faces[6][1]]  # a pentagon among them: the longest sets the width
    for count, index in (("u1", "i4"), ("u2", "u4"), ("i1", "i2"), ("u4", "i4")):
        path = write_polygon_ply(tmp_path / f"m{count}{index}.ply", vertices, faces, order=order, count=count,
                                 index=index)
        source = open_source(path)
        whole = curv.load(path)
        assert isinstance(source, polyply.PolygonPlySource) and source.face_width() == 5
        read = np.concatenate([f for _, f in source.face_chunks(size=11)])
        assert np.array_equal(read, whole.faces), (count, index)
        picked = [len(faces) - 1, 3, 0, 70, 3, 14]
        assert np.array_equal(source.faces_at(picked), whole.faces[picked])
        assert np.array_equal(np.concatenate([p for _, p, _ in source.chunks()]), whole.vertices)


def test_a_ply_of_triangles_still_takes_the_triangle_path(tmp_path):
    vertices, quads = quad_torus(12, 8)
    triangles = [t for f in quads for t in ([f[0], f[1], f[2]], [f[0], f[2], f[3]])]
    source = open_source(write_polygon_ply(tmp_path / "t.ply", vertices, triangles))
    assert type(source).__name__ == "PlySource" and source.face_width() == 3


@pytest.mark.parametrize("method", polygon_estimators())
def test_every_polygon_estimator_on_a_tiled_quad_mesh_writes_the_whole_calls_file(tmp_path, method):
    source = write_polygon_ply(tmp_path / "in.ply", *quad_torus())
    _same_file_as_whole(tmp_path, source, method)


def test_a_big_endian_quad_mesh_on_tiles_writes_the_whole_calls_file(tmp_path):
    source = write_polygon_ply(tmp_path / "in.ply", *quad_torus(), order=">", count="u2", index="u4")
    _same_file_as_whole(tmp_path, source, "mru")


@pytest.mark.parametrize("method", ["mru", "jet"])
def test_a_mesh_of_triangles_and_quads_on_tiles_writes_the_whole_calls_file(tmp_path, method):
    source = write_polygon_ply(tmp_path / "in.ply", *mixed_torus())
    _same_file_as_whole(tmp_path, source, method, range_=3)


def _bad_files(tmp_path):
    vertices, faces = mixed_torus(12, 8)
    good = write_polygon_ply(tmp_path / "good.ply", vertices, faces).read_bytes()
    out = {"truncated": good[:-7], "longer": good + bytes(13)}
    far = [list(f) for f in faces]
    far[9][2] = len(vertices) + 4
    out["beyond"] = write_polygon_ply(tmp_path / "x.ply", vertices, far).read_bytes()
    negative = [list(f) for f in faces]
    negative[9][1] = -3
    out["negative"] = write_polygon_ply(tmp_path / "x.ply", vertices, negative).read_bytes()
    short = [list(f) for f in faces]
    short[40] = short[40][:2]
    out["two corners"] = write_polygon_ply(tmp_path / "x.ply", vertices, short).read_bytes()
    short[9][1] = -3  # a negative corner before it: the whole reader names the short face first
    out["faults in order"] = write_polygon_ply(tmp_path / "x.ply", vertices, short).read_bytes()
    out["count low"] = write_polygon_ply(tmp_path / "x.ply", vertices, faces, face_count=len(faces) - 2).read_bytes()
    out["count high"] = write_polygon_ply(tmp_path / "x.ply", vertices, faces, face_count=len(faces) + 1).read_bytes()
    return out


@pytest.mark.parametrize("case", ["truncated", "longer", "beyond", "negative", "two corners", "faults in order",
                                  "count low", "count high"])
def test_a_bad_polygon_ply_is_the_whole_readers_one_line_and_no_output(tmp_path, monkeypatch, case):
    from curv.tiles import polyply

    monkeypatch.setattr(polyply, "BLOCK_BYTES", 256)  # the faults in different blocks
    path = tmp_path / "bad.ply"
    path.write_bytes(_bad_files(tmp_path)[case])
    with pytest.raises(Exception) as whole:
        curv.load(path)
    with pytest.raises(LoadError) as streamed:  # the block reader's own check, not the whole reader's
        source = open_source(path)
        assert isinstance(source, PolygonPlySource)
        source.face_width()
    with pytest.raises(LoadError) as tiled:
        estimate_file(path, tmp_path / "out.ply", "mru", 2, tile_size=100, workers=1)
    assert str(tiled.value) == str(streamed.value) == str(whole.value) and "\n" not in str(tiled.value)
    assert not (tmp_path / "out.ply").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


def test_a_preview_and_a_region_of_a_quad_mesh(tmp_path):
    """The viewer's decimated preview of a polygon file (its polygons cut into fans) and the Region
    dock's full resolution around a pick (the whole call's values)."""
    from curv.core.jit import run_to_end
    from curv.tiles.preview import read_preview
    from curv.tiles.regions import FileRegions

    source = write_polygon_ply(tmp_path / "in.ply", *quad_torus(120, 50))
    preview = read_preview(source, 1500)
    assert isinstance(preview.shape, curv.Mesh) and 800 < preview.shown <= 1.25 * 1500
    assert preview.words.endswith("vertices shown (clustered)") and "of 6,000" in preview.words
    assert preview.shape.report().components == 1
    regions = FileRegions(source, scratch=tmp_path / "regions")
    centre = preview.shape.vertices[len(preview.shape.vertices) // 3]
    around = run_to_end(regions.iter_around(centre, 0.4, [("mru", 2, {})]))
    assert around.ball.size > 20 and around.shape.n_vertices > around.ball.size
    assert not around.shape.is_triangular
    part = curv.estimate(around.shape, "mru", 2, vertices=around.ball)
    whole = curv.estimate(curv.load(source), "mru", 2)
    rows = around.ids[around.ball]
    assert np.array_equal(part.k1[around.ball], whole.k1[rows]) and np.array_equal(part.reason[around.ball],
                                                                                  whole.reason[rows])
    regions.close()
