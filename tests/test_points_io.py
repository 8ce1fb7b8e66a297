"""Point-cloud files: every format read back exactly as written, the bad files, the exports."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.core.errors import LoadError, MeshError
from curv.formats.lzf import decompress


@pytest.fixture
def cloud():
    """40 points on a unit sphere with their outward normals; coordinates exact in float32."""
    rng = np.random.default_rng(7)
    p = rng.normal(size=(40, 3))
    n = p / np.linalg.norm(p, axis=1)[:, None]
    return (2.0 * n).astype(np.float32).astype(np.float64), n.astype(np.float32).astype(np.float64)


def _ply(path, points, normals=None, *, text=False, dtype="f8"):
    from plyfile import PlyData, PlyElement

    names = list("xyz") + (["nx", "ny", "nz"] if normals is not None else [])
    vert = np.empty(len(points), dtype=[(c, dtype) for c in names])
    for i, c in enumerate("xyz"):
        vert[c] = points[:, i]
        if normals is not None:
            vert[f"n{c}"] = normals[:, i]
    PlyData([PlyElement.describe(vert, "vertex")], text=text).write(str(path))
    return path


# --- reading each format back ---------------------------------------------------------------------

@pytest.mark.parametrize("text", [False, True], ids=["binary", "ascii"])
@pytest.mark.parametrize("with_normals", [False, True], ids=["points", "normals"])
@pytest.mark.parametrize("dtype", ["f4", "f8"])
def test_vertex_only_ply_reads_back_exactly(tmp_path, cloud, text, with_normals, dtype):
    points, normals = cloud
    out = curv.load(_ply(tmp_path / "a.ply", points, normals if with_normals else None, text=text, dtype=dtype))
    assert isinstance(out, curv.PointCloud) and out.n_points == 40
    np.testing.assert_array_equal(out.points, points)
    if with_normals:
        np.testing.assert_array_equal(out.normals, normals)
    else:
        assert out.normals is None


def test_ply_with_faces_stays_a_mesh_and_with_zero_faces_is_a_point_cloud(tmp_path):
    from plyfile import PlyData, PlyElement

    vert = np.array([(0, 0, 0), (1, 0, 0), (0, 1, 0)], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    for count in (1, 0):
        face = np.array([([0, 1, 2],)] * count, dtype=[("vertex_indices", "i4", (3,))])
        path = tmp_path / f"f{count}.ply"
        PlyData([PlyElement.describe(vert, "vertex"), PlyElement.describe(face, "face")]).write(str(path))
        assert isinstance(curv.load(path), curv.Mesh if count else curv.PointCloud)


@pytest.mark.parametrize("suffix", [".xyz", ".txt", ".csv"])
@pytest.mark.parametrize("style", ["plain", "comma", "header", "cloudcompare", "comment-extra-column"])
@pytest.mark.parametrize("with_normals", [False, True], ids=["points", "normals"])
def test_text_points_read_back_exactly(tmp_path, cloud, suffix, style, with_normals):
    points, normals = cloud
    table = np.hstack([points, normals]) if with_normals else points
    names = ["x", "y", "z", "nx", "ny", "nz"][: table.shape[1]]
    path = tmp_path / f"a{suffix}"
    if style == "plain":
        np.savetxt(path, table, fmt="%.17g")
    elif style == "comma":
        np.savetxt(path, table, fmt="%.17g", delimiter=", ")
    elif style == "header":
        np.savetxt(path, table, fmt="%.17g", header=" ".join(names), comments="")
    elif style == "cloudcompare":
        np.savetxt(path, table, fmt="%.17g", delimiter=",", header=",".join(n.upper() for n in names), comments="//")
    else:  # a comment line, then a header naming an extra column that is ignored
        extra = np.hstack([table, np.arange(40)[:, None]])
        np.savetxt(path, extra, fmt="%.17g", header="scanned in code\n" + " ".join(names + ["intensity"]))
        text = path.read_text().replace("# " + " ".join(names), " ".join(names))
        path.write_text(text)
    out = curv.load(path)
    np.testing.assert_array_equal(out.points, points)
    if with_normals:
        np.testing.assert_array_equal(out.normals, normals)
    else:
        assert out.normals is None


def _pcd(path, points, normals, data, *, pad=True):
    """A PCD file with x y z [normal_x normal_y normal_z], a padding field and a packed rgb."""
    n = len(points)
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    if pad:
        fields.append(("_0", "<f4"))
    if normals is not None:
        fields += [("normal_x", "<f4"), ("normal_y", "<f4"), ("normal_z", "<f4")]
    fields.append(("rgb", "<u4"))
    rec = np.zeros(n, dtype=fields)
    for i, c in enumerate("xyz"):
        rec[c] = points[:, i]
        if normals is not None:
            rec[f"normal_{c}"] = normals[:, i]
    rec["rgb"] = 0x00FF8040
    names = ["_" if f[0] == "_0" else f[0] for f in fields]
    head = (f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {' '.join(names)}\n"
            f"SIZE {' '.join('4' for _ in fields)}\nTYPE {' '.join('U' if f[0] == 'rgb' else 'F' for f in fields)}\n"
            f"COUNT {' '.join('1' for _ in fields)}\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
            f"POINTS {n}\nDATA {data}\n").encode()
    if data == "ascii":
        rows = "\n".join(" ".join(repr(float(v)) if f[1] == "<f4" else str(int(v)) for v, f in zip(r, fields))
                         for r in rec.tolist())
        body = rows.encode() + b"\n"
    elif data == "binary":
        body = rec.tobytes()
    else:
        columns = b"".join(np.ascontiguousarray(rec[f[0]]).tobytes() for f in fields)
        packed = _lzf_compress(columns)
        body = np.array([len(packed), len(columns)], dtype="<u4").tobytes() + packed
    path.write_bytes(head + body)
    return path


def _lzf_compress(data: bytes, window: int = 512) -> bytes:
    """A small greedy LZF encoder (literal runs and back references), enough to test the decoder."""
    out, literal, i, n = bytearray(), bytearray(), 0, len(data)

    def flush():
        for s in range(0, len(literal), 32):
            chunk = literal[s:s + 32]
            out.append(len(chunk) - 1)
            out.extend(chunk)
        literal.clear()

    while i < n:
        best, offset = 0, 0
        for j in range(max(0, i - window), i):
            length = 0
            while i + length < n and length < 264 and data[j + length] == data[i + length]:
                length += 1
            if length > best:
                best, offset = length, i - j - 1
        if best >= 3:
            flush()
            code = best - 2
            if code < 7:
                out.append((code << 5) | (offset >> 8))
            else:
                out += bytes([(7 << 5) | (offset >> 8), code - 7])
            out.append(offset & 0xFF)
            i += best
        else:
            literal.append(data[i])
            i += 1
    flush()
    return bytes(out)


@pytest.mark.parametrize("data", ["ascii", "binary", "binary_compressed"])
@pytest.mark.parametrize("with_normals", [False, True], ids=["points", "normals"])
def test_pcd_reads_back_exactly(tmp_path, cloud, data, with_normals):
    points, normals = cloud
    out = curv.load(_pcd(tmp_path / "a.pcd", points, normals if with_normals else None, data))
    np.testing.assert_array_equal(out.points, points)
    if with_normals:
        np.testing.assert_array_equal(out.normals, normals)
    else:
        assert out.normals is None


def test_lzf_decoder_follows_the_format_on_a_hand_made_stream():
    # literal "a", then a back reference one byte back of length 7 + 0 + 2 = 9 (overlapping itself)
    assert decompress(bytes([0x00, 0x61, 0xE0, 0x00, 0x00]), 10).tobytes() == b"a" * 10
    # literal "abc", then 3 bytes from 3 back: (1 << 5) | 0, offset byte 2
    assert decompress(bytes([0x02, 0x61, 0x62, 0x63, 0x20, 0x02]), 6).tobytes() == b"abcabc"
    with pytest.raises(ValueError, match="malformed"):
        decompress(bytes([0x20, 0x05]), 4)  # a reference before the start
    with pytest.raises(ValueError, match="gives 3 bytes"):
        decompress(bytes([0x02, 0x61, 0x62, 0x63]), 4)


@pytest.mark.parametrize("suffix", [".las", ".laz"])
@pytest.mark.parametrize("with_normals", [False, True], ids=["points", "normals"])
def test_las_and_laz_read_back_exactly(tmp_path, cloud, suffix, with_normals):
    laspy = pytest.importorskip("laspy")
    points, normals = cloud
    header = laspy.LasHeader(point_format=3, version="1.4")
    header.scales, header.offsets = [1e-4] * 3, [10.0, -20.0, 5.0]
    if with_normals:
        header.add_extra_dims([laspy.ExtraBytesParams(name=c, type=np.float64) for c in ("nx", "ny", "nz")])
    las = laspy.LasData(header)
    las.x, las.y, las.z = points[:, 0] + 10, points[:, 1] - 20, points[:, 2] + 5
    if with_normals:
        las.nx, las.ny, las.nz = normals.T
    las.write(tmp_path / f"a{suffix}")
    expected = laspy.read(tmp_path / f"a{suffix}")
    out = curv.load(tmp_path / f"a{suffix}")
    np.testing.assert_array_equal(out.points, np.column_stack([expected.x, expected.y, expected.z]))
    np.testing.assert_allclose(out.points, points + [10, -20, 5], atol=0.51e-4)  # the file's 1e-4 grid
    if with_normals:
        np.testing.assert_array_equal(out.normals, normals)
    else:
        assert out.normals is None


# --- bad files: one line naming the file and the problem -----------------------------------------

def _write(path, text):
    path.write_text(text)
    return path


BAD_TEXT = {
    "nan.xyz": ("0 0 0\n1 nan 0\n0 1 0\n", "point 1 has a NaN"),
    "four.xyz": ("0 0 0 1\n1 0 0 1\n", "rows have 4 columns"),
    "ragged.xyz": ("0 0 0\n1 0\n0 1 0\n", "not a readable point file"),
    "word.csv": ("0,0,0\n1,abc,0\n", "not a readable point file"),
    "colours.xyz": ("0 0 0 255 128 0\n1 0 0 255 128 0\n", "columns 4-6 are not unit normals"),
    "noxyz.txt": ("a b c\n0 0 0\n", "neither numbers nor a header naming x, y, z"),
    "header-count.txt": ("x y z nx\n0 0 0 1\n", "has nx but not ny, nz"),
    "header-width.txt": ("x y z\n0 0 0 1\n", "the header names 3 columns but the rows have 4"),
    "only-header.csv": ("x,y,z\n", "has no points"),
    "blank.xyz": ("\n\n# nothing\n", "has no points"),
    "nohead.pcd": ("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n",
                   "no DATA line"),
    "noz.pcd": ("FIELDS x y\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n0 0\n",
                "lack coordinate(s) z"),
    "short.pcd": ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n"
                  "0 0 0\n1 1 1\n", "declares 3 points of 3 values, the data has 2 rows"),
    "mismatch.pcd": ("FIELDS x y z\nSIZE 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n0 0 0\n",
                     "lists 3 FIELDS but 2 SIZE"),
    "kind.pcd": ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA lzma\n",
                 "DATA lzma is not ascii, binary or binary_compressed"),
    "wh.pcd": ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n",
               "WIDTH 2 x HEIGHT 2 but POINTS 3"),
    "nan.pcd": ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n"
                "0 0 0\nnan nan nan\n", "point 1 has a NaN"),
    "garbage.las": ("this is not a LAS file at all, just some text\n" * 10, "not a readable LAS file"),
    "empty.ply": ("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                  "property float z\nend_header\n", "has no points"),
    "noz.ply": ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
                "lack coordinate(s) z"),
    "normal.ply": ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                   "property float nx\nend_header\n0 0 0 1\n", "has nx but not ny, nz"),
}


@pytest.mark.parametrize("name", sorted(BAD_TEXT))
def test_bad_point_files_are_one_line_load_errors_naming_the_file(tmp_path, name):
    text, expected = BAD_TEXT[name]
    path = _write(tmp_path / name, text)
    with pytest.raises(LoadError) as info:
        curv.load(path)
    message = str(info.value)
    assert message.startswith(str(path)) and expected in message and "\n" not in message


def test_empty_file_and_binary_length_errors(tmp_path, cloud):
    points, normals = cloud
    with pytest.raises(LoadError, match="file is empty"):
        curv.load(_write(tmp_path / "e.xyz", ""))
    pcd = _pcd(tmp_path / "b.pcd", points, None, "binary")
    data = pcd.read_bytes()
    pcd.write_bytes(data[:-5])
    with pytest.raises(LoadError, match="5 bytes fewer than its header declares"):
        curv.load(pcd)
    pcd.write_bytes(data + b"\0" * 8)
    with pytest.raises(LoadError, match="8 bytes more than its header declares"):
        curv.load(pcd)
    ply = _ply(tmp_path / "b.ply", points, normals)
    ply.write_bytes(ply.read_bytes() + b"\0" * 24)
    with pytest.raises(LoadError, match="24 bytes more than its header declares"):
        curv.load(ply)
    comp = _pcd(tmp_path / "c.pcd", points, normals, "binary_compressed")
    data = bytearray(comp.read_bytes())
    at = data.index(b"DATA binary_compressed\n") + len(b"DATA binary_compressed\n") + 8
    data[at] = 0x3F  # a reference before the start of the output
    comp.write_bytes(bytes(data))
    with pytest.raises(LoadError, match="LZF stream is malformed"):
        curv.load(comp)


def test_repairs_are_refused_on_a_point_cloud(tmp_path, cloud):
    path = _ply(tmp_path / "a.ply", *cloud)
    with pytest.raises(MeshError, match="is a point cloud; merge_vertices"):
        curv.load(path, merge_vertices=True)


def test_peek_points_reads_the_count_from_headers(tmp_path, cloud):
    from curv.io import is_point_file, peek_counts
    from curv.formats.pointio import peek_points

    points, normals = cloud
    ply = _ply(tmp_path / "a.ply", points)
    assert peek_counts(ply) == (40, 0) and is_point_file(ply)
    assert peek_points(_pcd(tmp_path / "a.pcd", points, normals, "binary")) == 40
    assert peek_points(_write(tmp_path / "a.xyz", "0 0 0\n")) is None
    assert peek_points(tmp_path / "missing.pcd") is None


# --- exports of a point cloud's result ------------------------------------------------------------

@pytest.fixture
def cloud_result():
    """A point cloud and a curvature result at its points (estimated on the sphere mesh of the same points)."""
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=2, radius=2.0)
    mesh = curv.Mesh(s.vertices, s.faces)
    res = curv.estimate(mesh, "mru", 2)
    return curv.PointCloud(mesh.vertices), res


def test_point_ply_export_holds_the_mesh_export_fields_and_reads_back(tmp_path, cloud_result):
    from plyfile import PlyData

    from curv.core.quantities import EXPORTED

    cloud, res = cloud_result
    out = curv.save_result(tmp_path / "out.ply", cloud, res, quantity="gaussian")
    ply = PlyData.read(str(out))
    assert [e.name for e in ply.elements] == ["vertex"]
    vert = ply["vertex"].data
    for name in EXPORTED:
        np.testing.assert_array_equal(vert[name], getattr(res, name).astype(np.float32))
    np.testing.assert_array_equal(vert["shown"], res.gaussian.astype(np.float32))
    np.testing.assert_array_equal(vert["d2y"], res.d2[:, 1].astype(np.float32))
    np.testing.assert_array_equal(vert["valid"], res.valid)
    np.testing.assert_array_equal(vert["reason"], res.reason)
    assert ply.comments[1] == curv.core.validity.reason_legend() and "colours show gaussian" in ply.comments[0]
    assert len(np.unique(np.column_stack([vert["red"], vert["green"], vert["blue"]]), axis=0)) > 1
    back = curv.load(out)
    np.testing.assert_array_equal(back.points, cloud.points)
    np.testing.assert_array_equal(back.normals, res.normals.astype(np.float32))


@pytest.mark.parametrize("suffix", [".vtu", ".vtp"])
def test_point_vtk_exports_hold_vertex_cells_and_the_fields(tmp_path, cloud_result, suffix):
    pv = pytest.importorskip("pyvista")
    cloud, res = cloud_result
    out = curv.save_result(tmp_path / f"out{suffix}", cloud, res, extra={"error_rel": np.arange(cloud.n_points)})
    grid = pv.read(out)
    assert type(grid).__name__ == ("PolyData" if suffix == ".vtp" else "UnstructuredGrid")
    assert grid.n_points == grid.n_cells == cloud.n_points
    if suffix == ".vtp":
        assert grid.n_verts == cloud.n_points  # every cell a vertex cell (n_cells == n_points above)
    np.testing.assert_array_equal(grid.points, cloud.points)
    for name in ("k1", "k2", "mean", "gaussian", "d1", "d2", "normals"):
        np.testing.assert_array_equal(grid[name], getattr(res, name))
    np.testing.assert_array_equal(grid["reason"], res.reason)
    np.testing.assert_array_equal(grid["shown"], res.mean)
    np.testing.assert_array_equal(grid["error_rel"], np.arange(cloud.n_points))
    assert int(grid.field_data["reason_BORDER"][0]) == int(curv.Reason.BORDER)


def test_mesh_vtp_export_keeps_the_faces(tmp_path):
    pv = pytest.importorskip("pyvista")
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=1)
    mesh = curv.Mesh(s.vertices, s.faces)
    res = curv.estimate(mesh, "qs", 2)
    grid = pv.read(curv.save_result(tmp_path / "m.vtp", mesh, res))
    np.testing.assert_array_equal(grid.faces.reshape(-1, 4)[:, 1:], mesh.triangles)
    np.testing.assert_array_equal(grid["k2"], res.k2)


def test_the_viewer_reads_a_point_file_whatever_mesh_repairs_are_ticked(tmp_path):
    from app.controller.sources import load_source
    from app.model.sources import FileSource

    path = tmp_path / "cloud.xyz"
    np.savetxt(path, np.random.default_rng(0).normal(size=(50, 3)))
    with pytest.raises(curv.MeshError, match="repair"):
        curv.load(path, merge_vertices=True)  # the library refuses a repair of a point cloud ...
    _, cloud, truth = load_source(FileSource(str(path), repairs=("merge_vertices", "orient")))
    assert isinstance(cloud, curv.PointCloud) and cloud.n_points == 50 and truth is None  # ... the viewer asks for none


@pytest.mark.parametrize("style", ["spaces", "tabs and CRLF", "commas", "blank lines and header"])
def test_text_layouts_read_back_to_the_last_bit(tmp_path, style):
    """Tabs, CRLF, commas, blank lines and a header line: the numbers read back exactly."""
    rng = np.random.default_rng(7)
    values = rng.normal(size=(500, 6)) * 10.0 ** rng.integers(-8, 8, size=(500, 6))
    values[:, 3:] /= np.linalg.norm(values[:, 3:], axis=1, keepdims=True)
    rows = [" ".join(repr(float(v)) for v in row) for row in values]
    if style == "tabs and CRLF":
        text = "\r\n".join(r.replace(" ", "\t") for r in rows) + "\r\n"
    elif style == "commas":
        text = "\n".join(r.replace(" ", ", ") for r in rows)
    elif style == "blank lines and header":
        text = "x y z nx ny nz\n" + "\n\n".join(rows) + "\n  \n"
    else:
        text = "\n".join("  " + r + "  " for r in rows) + "\n"
    path = tmp_path / "a.xyz"
    path.write_text(text)
    cloud = curv.load(path)
    np.testing.assert_array_equal(cloud.points, values[:, :3])
    np.testing.assert_array_equal(cloud.normals, values[:, 3:])
