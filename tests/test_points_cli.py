"""``curv estimate`` and ``curv list`` on point-cloud files, end to end on small generated clouds."""

from __future__ import annotations

import json

import numpy as np
import plyfile
import pytest

import curv
from curv.cli import main

RADIUS = 2.0


def _sphere(n=3000):
    """An even (Fibonacci) sample of a sphere of radius 2 and its outward unit normals."""
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    phi = np.pi * (1 + 5 ** 0.5) * i
    unit = np.column_stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z])
    return RADIUS * unit, unit


def _write_ply(path, points, normals=None):
    names = list("xyz") + (["nx", "ny", "nz"] if normals is not None else [])
    vert = np.empty(len(points), dtype=[(c, "f8") for c in names])
    for i, c in enumerate("xyz"):
        vert[c] = points[:, i]
        if normals is not None:
            vert[f"n{c}"] = normals[:, i]
    plyfile.PlyData([plyfile.PlyElement.describe(vert, "vertex")]).write(str(path))
    return path


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("points_cli")
    points, normals = _sphere()
    return {"normals": _write_ply(folder / "sphere_n.ply", points, normals),
            "bare": _write_ply(folder / "sphere.ply", points)}


def _run(capsys, *argv):
    code = main(["estimate", *map(str, argv)])
    out = capsys.readouterr()
    return code, out.out, out.err.strip()


def test_estimate_writes_a_vertex_only_ply_with_the_curvature(files, tmp_path, capsys):
    out = tmp_path / "out.ply"
    code, text, _ = _run(capsys, files["normals"], "-m", "jet", "-r", "2", "-o", out, "-q")
    assert code == 0
    ply = plyfile.PlyData.read(str(out))
    assert [e.name for e in ply.elements] == ["vertex"]
    v = ply["vertex"].data
    assert len(v) == 3000 and v["valid"].mean() > 0.95
    ok = v["valid"] == 1
    np.testing.assert_allclose(v["k1"][ok], 1 / RADIUS, rtol=0.02)  # outward normals: +1/r
    np.testing.assert_allclose(v["k2"][ok], 1 / RADIUS, rtol=0.02)
    assert np.isnan(v["k1"][~ok]).all()
    np.testing.assert_array_equal(v["shown"][ok], v["mean"][ok])
    head = text.splitlines()[0]
    assert head.startswith(f"{files['normals']}: 3,000 points; spacing ") and "normals from the file" in head
    assert "coincident points 0" in text and "border points" in text
    assert "jet R2:" in text and "of 3000 points valid" in text and "write" in text


@pytest.mark.parametrize("flags, label", [(["--knn", "20"], "qs knn=20"), (["--radius", "0.35"], "qs r=0.35"),
                                          (["-r", "2.5"], "qs R2.5")])
def test_knn_radius_and_range_run_and_are_named(files, capsys, flags, label):
    code, text, _ = _run(capsys, files["normals"], "-m", "qs", *flags, "-q")
    assert code == 0 and f"{label}:" in text


@pytest.mark.parametrize("orient, sign", [([], 1), (["--orient-normals", "outward"], 1),
                                          (["--orient-normals", "0", "0", "0"], -1)])
def test_estimated_normals_orientation_sets_the_sign(files, tmp_path, capsys, orient, sign):
    out = tmp_path / "o.ply"
    code, text, _ = _run(capsys, files["bare"], "-m", "qs", "-r", "2", "-q", "-o", out, *orient)
    assert code == 0 and "normals estimated (jet R2" in text
    v = plyfile.PlyData.read(str(out))["vertex"].data
    ok = v["valid"] == 1
    assert ok.mean() > 0.9
    assert (np.sign(v["mean"][ok]) == sign).all()  # normals towards the centre: -1/r
    assert abs(np.median(v["mean"][ok]) - sign / RADIUS) < 0.005


def test_coincident_points_are_counted_and_marked(tmp_path, capsys):
    points, normals = _sphere()
    points = np.vstack([points, points[:5]])
    path = _write_ply(tmp_path / "dup.ply", points, np.vstack([normals, normals[:5]]))
    out = tmp_path / "o.ply"
    code, text, _ = _run(capsys, path, "-m", "mru", "-q", "-o", out)
    assert code == 0 and "coincident points 5" in text
    v = plyfile.PlyData.read(str(out))["vertex"].data
    assert (v["reason"][3000:] == curv.Reason.DEGENERATE).all()


def test_an_open_patch_reports_its_border(tmp_path, capsys):
    g = np.linspace(-1, 1, 41)
    x, y = [a.ravel() for a in np.meshgrid(g, g)]
    path = tmp_path / "patch.xyz"
    np.savetxt(path, np.column_stack([x, y, 0.25 * (x * x + y * y)]))
    code, text, _ = _run(capsys, path, "-m", "jet", "-q")
    assert code == 0
    border = int(text.split("border points ")[1].split()[0].replace(",", ""))
    assert 4 * 40 <= border < 0.5 * 41 * 41  # the rim (at least one ring), not the inside


@pytest.mark.parametrize("suffix", [".vtu", ".vtp"])
def test_vtk_outputs_of_points(files, tmp_path, capsys, suffix):
    meshio = pytest.importorskip("meshio")
    out = tmp_path / f"o{suffix}"
    code, _, _ = _run(capsys, files["normals"], "-m", "mru", "-q", "-o", out)
    assert code == 0
    text = out.read_text(errors="replace")
    assert ('type="PolyData"' in text) == (suffix == ".vtp") and 'Name="reason_BORDER"' in text
    if suffix == ".vtu":
        grid = meshio.read(out)
        assert grid.cells[0].type == "vertex" and len(grid.cells[0].data) == 3000
        ok = grid.point_data["valid"] == 1
        np.testing.assert_allclose(grid.point_data["mean"][ok], 1 / RADIUS, rtol=0.03)


def test_las_input_end_to_end(tmp_path, capsys):
    laspy = pytest.importorskip("laspy")
    points, _ = _sphere()
    header = laspy.LasHeader(point_format=0, version="1.2")
    header.scales, header.offsets = [1e-6] * 3, [0.0, 0.0, 0.0]
    las = laspy.LasData(header)
    las.x, las.y, las.z = points.T
    las.write(tmp_path / "scan.laz")
    code, text, _ = _run(capsys, tmp_path / "scan.laz", "-m", "jet", "-r", "2", "-q", "--orient-normals", "outward")
    assert code == 0 and "3,000 points" in text
    median = float(text.split("mean ")[1].split("median")[1].split()[0])
    assert abs(median - 1 / RADIUS) < 0.01


@pytest.mark.parametrize("flags, words", [
    (["-m", "meyer"], "does not run on point clouds; use one of:"),
    (["-m", "csm"], "does not run on point clouds"),
    (["--merge-vertices"], "--merge-vertices needs a mesh's faces"),
    (["--features", "30"], "--features needs a mesh's faces"),
    (["--smooth", "mesh"], "--smooth needs a mesh's faces"),
    (["--normals", "max"], "--normals max weights face normals"),
    (["--knn", "2"], "knn must be a whole number of neighbours >= 3"),
    (["--knn", "20", "-r", "2"], "give one of range=, radius= or knn="),
    (["--orient-normals", "sideways"], "--orient-normals takes up, top, outward or a viewpoint"),
    (["-o", "out.stl"], "cannot write .stl"),
])
def test_bad_requests_are_one_line_errors_before_the_file_is_read(tmp_path, capsys, flags, words):
    path = tmp_path / "bad.xyz"
    path.write_text("0 0 0\n1 nan 0\n")  # reading it would fail: the request is refused first
    code, text, err = _run(capsys, path, *flags)
    assert code == 2 and words in err and len(err.splitlines()) == 1 and "nan" not in err.lower()
    assert text == ""


def test_bad_files_are_one_line_errors(tmp_path, capsys):
    path = tmp_path / "bad.xyz"
    path.write_text("0 0 0\n1 nan 0\n")
    code, _, err = _run(capsys, path, "-m", "qs")
    assert code == 2 and err == f"curv: error: {path}: point 1 has a NaN coordinate"
    code, _, err = _run(capsys, tmp_path / "missing.pcd")
    assert code == 2 and err.endswith("missing.pcd: no such file")


def test_file_normals_with_an_orientation_asked_is_refused(files, capsys):
    code, _, err = _run(capsys, files["normals"], "--orient-normals", "up")
    assert code == 2 and "normals come from the file; add --normals pca or fit" in err


def test_point_options_on_a_mesh_are_refused(tmp_path, capsys):
    from tests.meshes import icosphere

    path = curv.save_ply(tmp_path / "m.ply", icosphere(1), curv.estimate(icosphere(1), "qs"))
    for flags, words in ((["--knn", "10"], "--knn is for point clouds"),
                         (["--orient-normals", "up"], "--orient-normals is for point clouds"),
                         (["--normals", "pca"], "--normals pca is for point clouds")):
        code, _, err = _run(capsys, path, *flags)
        assert code == 2 and words in err


def test_list_names_the_estimators_that_take_points(capsys):
    assert main(["list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    column = lines[0].index("points")
    rows = {ln.split()[0]: ln for ln in lines[2:] if ln[:1].isalpha()}
    taking = {name for name, row in rows.items() if row[column:column + 7].strip() == "yes"}
    assert {"qs", "nc", "an", "mru", "jet"} <= taking and not {"meyer", "csm", "ru", "icc"} & taking
    assert taking == {name for name, spec in curv.ESTIMATORS.items() if spec.takes_points}


def test_advise_and_method_auto_take_a_point_cloud(files, capsys):
    """Point clouds are advised too (their candidates checked on the cloud's twin); ``--method
    auto`` estimates with the advised call and says it as flags."""
    assert main(["advise", str(files["normals"]), "--json", "--no-check"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["call"].startswith("curv.estimate(cloud") and not data["checked"] and "check=False" in data["note"]
    assert main(["estimate", str(files["bare"]), "--method", "auto", "-q"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("auto: ") and "; the same as --method " in out[0] and "measured median e_rel" in out[0]


def test_a_cloud_too_big_for_memory_is_refused_from_its_header(tmp_path, capsys):
    path = tmp_path / "huge.ply"  # a header that declares 10^9 points, and their 12 GB (a sparse file)
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\n"
              "property float y\nproperty float z\nend_header\n").encode()
    with open(path, "wb") as fh:
        fh.write(header)
        fh.truncate(len(header) + 12 * 10**9)
    code, _, err = _run(capsys, path, "-m", "qs")
    assert code == 2 and "qs R2 on 1,000,000,000 points needs about" in err and "refusing to start" in err
    assert "give -o OUT to run it on tiles" in err  # too large whole: it would run on tiles, which need a file
    path.write_bytes(header)  # the header alone: a promise the file cannot hold, whatever the memory
    for flags in ((), ("--no-memory-check",)):
        code, _, err = _run(capsys, path, "-m", "qs", *flags)
        assert code == 2 and "refusing" not in err and str(path) in err and "element vertex count 1000000000" in err


def test_summary_counts_the_one_sided_normals(tmp_path, capsys):
    from curv.surfaces import QuadraticPatch, sample_points

    rows = sample_points(QuadraticPatch(), 4000, sampling="rows", ratio=4, rng=12).cloud
    path = _write_ply(tmp_path / "rows.ply", rows.points)
    code, out, _ = _run(capsys, path, "-m", "qs", "-r", "2", "-q")
    assert code == 0
    line = next(line for line in out.splitlines() if "one-sided normals" in line)
    assert int(line.split()[2].replace(",", "")) == curv.estimate(rows, "qs", 2).info["one_sided_normals"] > 0
