"""Inputs of the tile engine: a COPC file's region read through its octree, ASCII PLY files read a
chunk at a time, and whether a command tiles by itself (a decision that must not depend on the
memory other processes hold at that moment)."""

from __future__ import annotations

from argparse import Namespace

import numpy as np
import pytest

import curv
from curv.core.jit import run_to_end

from laspy_samples import laspy_sample

# ---------------------------------------------------------------------------------------------
# when a command tiles by itself


def test_whether_a_command_tiles_does_not_depend_on_the_memory_free_now(monkeypatch):
    import curv.memory
    from curv.tiles.command import wants_tiles

    monkeypatch.setattr(curv.memory, "total_bytes", lambda: 16 * 2**30, raising=False)  # 8 GiB budget
    args = Namespace(tile_size=None, scheduler=None, memory=None, memory_check=True, method="qs")
    answers = []
    for free in (200 * 2**20, 2 * 2**30, 15 * 2**30):  # other processes holding most of it, or none
        monkeypatch.setattr(curv.memory, "available_bytes", lambda free=free: free)
        answers.append((wants_tiles(args, (5_000_000, 0), points=True), wants_tiles(args, (20_000_000, 0), points=True)))
    assert answers == [(False, True)] * 3  # about 5 GB whole fits 8 GiB; 20 GB does not


def test_the_default_budget_is_half_the_machines_memory(monkeypatch):
    import curv.memory
    from curv.tiles.budget import UNKNOWN_TOTAL, default_budget

    monkeypatch.setattr(curv.memory, "available_bytes", lambda: 10**6)
    monkeypatch.setattr(curv.memory, "total_bytes", lambda: 24 * 2**30)
    assert default_budget() == 12 * 2**30
    monkeypatch.setattr(curv.memory, "total_bytes", lambda: None)
    assert default_budget() == UNKNOWN_TOTAL // 2


def test_the_machines_total_memory_is_capped_by_a_cgroup_limit():
    from curv.memory import available_bytes, total_bytes

    total = total_bytes()
    assert total is not None and total >= available_bytes() * 0.99


# ---------------------------------------------------------------------------------------------
# COPC: a region read by bounds


@pytest.fixture(scope="module", params=["simple.copc.laz", "simple_with_page.copc.laz", "made in code"])
def copc_file(request, tmp_path_factory):
    """laspy's two real COPC samples (1,065 points of Autzen, 65 nodes; the second with a child
    hierarchy page) and one written here: 20,000 points of a wavy terrain on a millimetre grid, their
    normals as extra bytes, in 400-odd nodes over five levels."""
    pytest.importorskip("lazrs")
    if request.param != "made in code":
        return laspy_sample(request.param)
    from copc_files import write_copc

    rng = np.random.default_rng(7)
    x, y = rng.uniform(0, 100, 20_000), rng.uniform(0, 100, 20_000)
    z = 3.0 * np.sin(x / 10.0) + 0.02 * y
    normals = np.column_stack([-0.3 * np.cos(x / 10.0), np.full_like(x, -0.02), np.ones_like(x)])
    path = tmp_path_factory.mktemp("copc") / "terrain.copc.laz"
    write_copc(path, np.column_stack([x, y, z]), normals / np.linalg.norm(normals, axis=1)[:, None])
    return path


def test_a_copc_region_by_bounds_is_the_whole_files_points_there(copc_file):
    from curv.tiles.copc import CopcInput, is_copc
    from curv.tiles.plan import Region

    assert is_copc(copc_file) and not is_copc(laspy_sample("simple.laz"))
    cloud = curv.load(copc_file)
    points = cloud.points
    lo, hi = points.min(axis=0), points.max(axis=0)
    copc = CopcInput(copc_file)
    for a, b in ((0.3, 0.5), (0.0, 0.25), (0.6, 1.0), (0.0, 1.0)):
        region = Region.around(lo + a * (hi - lo), lo + b * (hi - lo), 0.0, (lo, hi))
        piece = copc.fetch(region)
        rows = np.flatnonzero(region.contains(points))
        assert np.array_equal(piece.ids, rows) and np.array_equal(piece.points, points[rows])
        assert (piece.normals is None) == (cloud.normals is None)
        if piece.normals is not None:
            assert np.array_equal(piece.normals, cloud.normals[rows])
        if b - a < 1.0:
            assert copc.nodes_read < copc.n_nodes  # only the nodes the box meets were decompressed
    assert copc.nodes_read == copc.n_nodes


def test_a_copc_preview_is_its_coarse_octree_levels_as_laspy_reads_them(copc_file):
    from laspy.copc import CopcReader

    from curv.tiles.preview import read_preview

    whole = curv.load(copc_file)
    with CopcReader.open(copc_file) as reader:
        by_level = [len(reader.query(level=range(0, k + 1))) for k in range(8)]
        coarse = reader.query(level=range(0, 3))
        expected = np.column_stack([np.asarray(coarse[c], np.float64) for c in "xyz"])
    assert by_level[1] < by_level[2] < whole.n_vertices
    rows = {tuple(p): i for i, p in enumerate(whole.vertices)}
    # the count between the second level's total and the third's: levels 0-2, every 2nd or 3rd point
    for cap in (by_level[2], (by_level[1] + by_level[2]) // 2):
        preview = read_preview(copc_file, cap)
        stride = -(-by_level[2] // cap)
        assert preview.levels == 2 and preview.stride == stride and preview.total == whole.n_vertices
        assert preview.shown == -(-by_level[2] // stride) <= cap
        how = "octree levels 0-2" + (f", every {stride}{'nd' if stride == 2 else 'rd' if stride == 3 else 'th'}"
                                     if stride > 1 else "")
        assert preview.words == f"{preview.shown:,} of {whole.n_vertices:,} points shown ({how})"
        # laspy's level query's points, in the file's order, every stride-th, the file's own normals
        at = np.array([rows[tuple(p)] for p in expected])
        at = np.sort(at)[::stride]
        assert np.array_equal(preview.shape.points, whole.vertices[at])
        if whole.normals is not None:
            assert np.array_equal(preview.shape.normals, whole.normals[at])
    everything = read_preview(copc_file, whole.n_vertices)
    assert everything.shown == whole.n_vertices and everything.words.endswith("(all)")


def test_the_estimate_around_a_pick_on_a_copc_file_is_the_whole_calls(copc_file, tmp_path):
    from curv.tiles.regions import FileRegions

    whole_cloud = curv.load(copc_file)
    whole = curv.estimate(whole_cloud, "qs", 2)
    regions = FileRegions(copc_file, scratch=tmp_path / "regions")
    centre = whole_cloud.points[np.argsort(whole_cloud.points[:, 0])[whole_cloud.n_points // 2]]
    radius = 0.18 * float(np.ptp(whole_cloud.points[:, 0]))
    around = run_to_end(regions.iter_around(centre, radius, [("qs", 2, {})]))
    assert regions._input.nodes_read < regions._input.n_nodes  # read by bounds, not the whole file
    assert not (tmp_path / "regions").exists()  # nothing sorted into tiles
    assert around.ball.size > 50 and around.shape.n_points > around.ball.size
    part = curv.estimate(around.shape, "qs", 2, vertices=around.ball)
    rows = around.ids[around.ball]
    assert np.array_equal(part.reason[around.ball], whole.reason[rows])
    np.testing.assert_allclose(part.k1[around.ball], whole.k1[rows], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(part.k2[around.ball], whole.k2[rows], rtol=1e-12, atol=1e-15)
    regions.close()


# ---------------------------------------------------------------------------------------------
# ASCII PLY read a chunk at a time


def _write_ascii_ply(path, vertices, faces=None, *, dtype="f4", normals=None, text_faces=None):
    """An ASCII PLY written by plyfile (``faces`` (m, k) or a list of polygons)."""
    from plyfile import PlyData, PlyElement

    names = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals is not None else [])
    v = np.zeros(len(vertices), dtype=[(c, dtype) for c in names] + [("red", "u1")])
    v["x"], v["y"], v["z"] = np.asarray(vertices).T
    if normals is not None:
        v["nx"], v["ny"], v["nz"] = np.asarray(normals).T
    elements = [PlyElement.describe(v, "vertex")]
    if faces is not None:
        f = np.empty(len(faces), dtype=[("vertex_indices", object)])
        f["vertex_indices"] = [np.asarray(p, np.int32) for p in faces]
        elements.append(PlyElement.describe(f, "face", len_types={"vertex_indices": "u1"},
                                            val_types={"vertex_indices": "i4"}))
    PlyData(elements, text=True).write(str(path))


def test_an_ascii_ply_is_read_a_chunk_at_a_time_as_the_whole_reader_reads_it(tmp_path, monkeypatch):
    from curv.surfaces import Torus, sample_points
    from curv.tiles import asciiply
    from curv.tiles.sources import open_source, reopen

    from meshes import torus_grid

    monkeypatch.setattr(asciiply, "_BLOCK", 997)  # blocks cut inside numbers and lines
    mesh = torus_grid(30, 20)[0]
    rng = np.random.default_rng(3)
    vertices = mesh.vertices * 1.2345678901 + rng.normal(0, 1e-3, mesh.vertices.shape)
    _write_ascii_ply(tmp_path / "mesh.ply", vertices, mesh.face_indices.reshape(-1, 3))
    cloud = sample_points(Torus(), 3000, sampling="uniform", rng=5).cloud
    _write_ascii_ply(tmp_path / "cloud.ply", cloud.points, dtype="f8", normals=cloud.points / 3.0)
    for name, kind in (("mesh.ply", curv.Mesh), ("cloud.ply", curv.PointCloud)):
        whole = curv.load(tmp_path / name)
        assert isinstance(whole, kind)
        source = open_source(tmp_path / name)
        assert isinstance(source, asciiply.AsciiPlySource) and source.n == whole.n_vertices
        parts = list(source.chunks(700))
        assert np.array_equal(np.concatenate([p for _, p, _ in parts]), whole.vertices)  # bit for bit
        if kind is curv.PointCloud:
            assert np.array_equal(np.concatenate([m for _, _, m in parts]), curv.load(tmp_path / name).normals)
        scan = source.scan(tmp_path / name.replace(".", "-"), 7)
        assert np.array_equal(scan.sample, whole.vertices[::7])
        assert np.array_equal(np.concatenate([p for _, p, _ in source.chunks(500)]), whole.vertices)
        if kind is curv.Mesh:
            assert np.array_equal(np.concatenate([f for _, f in source.face_chunks(300)]), whole.face_indices.reshape(-1, 3))
            again = reopen(tmp_path / name, tmp_path / name.replace(".", "-"))
            assert np.array_equal(again.vertices_at([5, 0, 599]), whole.vertices[[5, 0, 599]])
            assert np.array_equal(again.faces_at([3, 1]), whole.face_indices.reshape(-1, 3)[[3, 1]])


def test_an_ascii_polygon_mesh_is_read_whole_and_bad_counts_are_one_line(tmp_path):
    from curv.core.errors import LoadError
    from curv.tiles.sources import open_source

    from meshes import torus_grid

    quads = torus_grid(12, 8, quads=True)[0]
    _write_ascii_ply(tmp_path / "quads.ply", quads.vertices, quads.faces)
    assert open_source(tmp_path / "quads.ply") is None  # kept as polygons by curv.load: read whole
    mesh = torus_grid(12, 8)[0]
    _write_ascii_ply(tmp_path / "tri.ply", mesh.vertices, mesh.face_indices.reshape(-1, 3))
    text = (tmp_path / "tri.ply").read_bytes()
    (tmp_path / "cut.ply").write_bytes(text[: len(text) - 40])
    assert open_source(tmp_path / "cut.ply") is None  # unsure: the whole reader says what is wrong
    (tmp_path / "more.ply").write_bytes(text + b"3 0 1 2\n")
    assert open_source(tmp_path / "more.ply") is None
    cloud = text.split(b"element face")[0] + b"end_header\n" + text.split(b"end_header\n")[1]
    (tmp_path / "pts.ply").write_bytes(cloud)  # the faces' lines left as extra data of a cloud
    source = open_source(tmp_path / "pts.ply")
    with pytest.raises(LoadError, match="more than its header declares") as err:
        source.scan(tmp_path / "scratch", 1)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("fault", ["beyond", "negative"])
@pytest.mark.parametrize("form", ["binary", "ascii"])
def test_a_triangle_ply_with_a_bad_corner_is_the_whole_readers_one_line_on_tiles(tmp_path, form, fault):
    from curv.core.errors import LoadError
    from curv.tiles import estimate_file
    from curv.tiles.sources import open_source

    from meshes import torus_grid

    mesh = torus_grid(16, 10)[0]
    faces = mesh.face_indices.reshape(-1, 3).copy()
    bad = {"beyond": (mesh.n_vertices + 4, mesh.n_vertices + 9), "negative": (-3, -5)}[fault]
    faces[57, 1], faces[90, 2] = bad  # the first of two faults of one kind is named
    path = tmp_path / "bad.ply"
    if form == "ascii":
        _write_ascii_ply(path, mesh.vertices, faces)
    else:
        from plyfile import PlyData, PlyElement

        v = np.zeros(mesh.n_vertices, dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
        v["x"], v["y"], v["z"] = mesh.vertices.T
        f = np.empty(len(faces), dtype=[("vertex_indices", "i4", (3,))])
        f["vertex_indices"] = faces
        PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")]).write(str(path))
    assert open_source(path) is not None  # streamed: the chunked reader's own check
    with pytest.raises(Exception) as whole:
        curv.load(path)
    with pytest.raises(LoadError) as tiled:
        estimate_file(path, tmp_path / "out.ply", "mru", 2, tile_size=100, workers=1)
    assert str(tiled.value) == str(whole.value) and "\n" not in str(tiled.value)
    assert "face 57" in str(tiled.value)
    assert not (tmp_path / "out.ply").exists()


@pytest.mark.parametrize("kind", ["mesh", "cloud"])
def test_an_ascii_ply_on_tiles_writes_the_whole_calls_file(tmp_path, kind):
    from plyfile import PlyData

    from curv.surfaces import Torus, sample_points
    from curv.tiles import estimate_file

    from meshes import torus_grid

    if kind == "mesh":
        mesh = torus_grid(60, 30)[0]
        _write_ascii_ply(tmp_path / "in.ply", mesh.vertices, mesh.face_indices.reshape(-1, 3), dtype="f8")
        method, keywords, tile = "mru", {}, 600
    else:
        cloud = sample_points(Torus(), 6000, sampling="uniform", rng=5).cloud
        _write_ascii_ply(tmp_path / "in.ply", cloud.points)
        method, keywords, tile = "jet", {"orient": (0, 0, 10)}, 1500
    shape = curv.load(tmp_path / "in.ply")
    curv.save_ply(tmp_path / "whole.ply", shape, curv.estimate(shape, method, 2, **keywords))
    run = estimate_file(tmp_path / "in.ply", tmp_path / "tiled.ply", method, 2, tile_size=tile, workers=1, **keywords)
    assert run.tiles > 2 and run.budget is not None  # streamed and tiled, not read whole
    a, b = PlyData.read(str(tmp_path / "whole.ply")), PlyData.read(str(tmp_path / "tiled.ply"))
    va, vb = a["vertex"].data, b["vertex"].data
    assert va.dtype == vb.dtype
    for name in va.dtype.names:
        if kind == "cloud" and va[name].dtype.kind == "f":
            np.testing.assert_allclose(va[name], vb[name], rtol=1e-5, atol=1e-6, err_msg=name)  # to rounding
        else:
            assert np.array_equal(va[name], vb[name], equal_nan=True), name  # a mesh: bit for bit
    if kind == "mesh":
        assert np.array_equal(np.stack(a["face"].data["vertex_indices"]), np.stack(b["face"].data["vertex_indices"]))


def test_a_mesh_of_triangles_and_quads_on_tiles_equals_the_whole_call():
    """A tile keeps the padding of its shorter polygons (-1), not a vertex of the tile in its place."""
    from curv.tiles import estimate_tiled

    from meshes import torus_grid

    quads = torus_grid(40, 20, quads=True)[0]
    faces = quads.faces
    polygons = [f for i, f in enumerate(faces) if i % 2 == 0]
    polygons += [t for f in faces[1::2] for t in (f[[0, 1, 2]], f[[0, 2, 3]])]
    mesh = curv.Mesh(quads.vertices, polygons)
    whole = curv.estimate(mesh, "mru", 2)
    tiled = estimate_tiled(mesh, "mru", 2, tile_size=200)
    assert tiled.info["tiles"] > 2 and whole.valid.all()
    assert np.array_equal(whole.reason, tiled.reason) and np.array_equal(whole.k1, tiled.k1)


def test_a_preview_of_an_ascii_ply_mesh_reads_its_text_a_chunk_at_a_time(tmp_path):
    from curv.tiles.preview import read_preview
    from curv.tiles.sources import open_source

    from meshes import torus_grid

    mesh = torus_grid(90, 40)[0]
    _write_ascii_ply(tmp_path / "in.ply", mesh.vertices, mesh.face_indices.reshape(-1, 3))
    source = open_source(tmp_path / "in.ply")  # no scratch copy: faces and vertices from the text
    assert np.array_equal(source.faces_at([7, 2]), mesh.face_indices.reshape(-1, 3)[[7, 2]])
    assert np.array_equal(source.vertices_at([9, 1]), curv.load(tmp_path / "in.ply").vertices[[9, 1]])
    preview = read_preview(tmp_path / "in.ply", 1500)
    assert isinstance(preview.shape, curv.Mesh) and 800 < preview.shown <= 1.25 * 1500
    assert preview.shape.report().components == 1


# ---------------------------------------------------------------------------------------------
# the reach of a point's border flag on real scans


@pytest.mark.parametrize("name, tile_size, halo", [("vegetation_1_3.las", 3561, 0.0376),
                                                     ("simple1_4.las", 3228, 2.25)])
def test_tiles_with_a_narrow_halo_equal_the_whole_call_on_real_scans(name, tile_size, halo):
    """A narrow first halo leaves the certificate (curv.tiles.reach) to decide every point near a
    tile's edge. A point whose angular gap is wide reads the one-sided test's ball, twice the gap
    test's: before that ball was in the reach, 3-4 points of vegetation_1_3.las and 1-7 of
    simple1_4.las took another reason on tiles (BORDER <-> OK, BORDER <-> SINGULAR)."""
    from curv.tiles import estimate_tiled

    cloud = curv.load(laspy_sample(name))
    whole = curv.estimate(cloud, "qs", 2)
    tiled = estimate_tiled(cloud, "qs", 2, tile_size=tile_size, halo=halo)
    np.testing.assert_array_equal(tiled.reason, whole.reason)
    # in memory the tiles sum a support in their own grid's order: equal to rounding (curv.tiles)
    np.testing.assert_allclose(tiled.k1, whole.k1, rtol=1e-9, atol=0)
    np.testing.assert_allclose(tiled.k2, whole.k2, rtol=1e-9, atol=0)


def test_the_reach_holds_the_one_sided_tests_ball_where_the_gap_is_wide():
    from curv.point_normals import border_radii, border_test_radii
    from curv.point_normals.rim import RIM_SCALE
    from curv.tiles import support_reach

    cloud = curv.load(laspy_sample("vegetation_1_3.las"))
    wide = border_test_radii(cloud) > border_radii(cloud)
    assert 0 < wide.sum() < cloud.n_points
    reach = support_reach(cloud, "qs", 2)
    assert np.all(reach[wide] >= RIM_SCALE * border_radii(cloud)[wide])
