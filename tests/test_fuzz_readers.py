"""Readers bounded by their input: header promises checked against the file, and a fuzz run of every format.

A header that promises more than its file holds (a LAS file's VLR count, a PLY element count, a
PCD or glTF size) is a one-line :class:`LoadError` naming the field, before a library allocates or
loops on it. ``tests/fuzzing.py`` mutates valid small files of every format curv reads; a short run
is part of the default suite, the long one is ``python -m tests.fuzzing --cases 10000`` (or
``pytest -m slow tests/test_fuzz_readers.py``).
"""

from __future__ import annotations

import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import curv
from curv.core.errors import LoadError
from curv.formats.lasheader import check_las_header
from tests.fuzzing import ROOT, Worker, real_las_seeds, run_cases, seed_files

LASF_TEXT = "LASF but not really\n" * 20
"""The 400-byte file of the issue: laspy read VLRs from it for ever."""


@pytest.fixture(scope="module")
def seeds():
    return {seed.name: seed for seed in seed_files()}


def _write(tmp_path, name, data: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def _field(data: bytes, offset: int, code: str, value) -> bytes:
    out = bytearray(data)
    out[offset:offset + struct.calcsize(code)] = struct.pack(code, value)
    return bytes(out)


def _load_error(path) -> str:
    with pytest.raises(LoadError) as info:
        curv.load(path)
    message = str(info.value)
    assert message.startswith(str(path)) and "\n" not in message
    return message


# --- the LASF file of the issue, in a watched worker (it hung for ever before) ------------------

def _hang_cases(tmp_path, seeds) -> dict[str, Path]:
    las = seeds["LAS 1.2"].data
    return {"issue": _write(tmp_path, "x.las", LASF_TEXT.encode()),
            "vlr count": _write(tmp_path, "vlrs.las", _field(las, 100, "<I", 2**32 - 1)),
            "laz evlr count": _write(tmp_path, "evlrs.laz", _field(seeds["LAZ 1.4 normals"].data, 243, "<I", 2**32 - 1))}


def test_the_lasf_file_and_huge_record_counts_end_in_one_line_at_once(tmp_path, seeds):
    worker = Worker()
    try:
        for name, path in _hang_cases(tmp_path, seeds).items():
            answer = worker.ask(path, 60.0, estimate=False, cli=False)
            assert answer["outcome"] == "error", (name, answer)
            assert answer["seconds"] < 5.0, (name, answer)  # a header check, not a read: well under this
    finally:
        worker.stop()


def test_the_cli_on_the_lasf_file_exits_2_with_one_line_and_no_output(tmp_path):
    path = _write(tmp_path, "x.las", LASF_TEXT.encode())
    out = tmp_path / "out.ply"
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, "-m", "curv.cli", "estimate", str(path), "-m", "qs", "-r", "2",
                           "-o", str(out)], capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1 and "x.las" in lines[0] and "LAS version" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.las"]


# --- each LAS/LAZ promise, named --------------------------------------------------------------

LAS_PROMISES = [  # (seed, offset, struct code, value, words the message must hold)
    ("LAS 1.2", 94, "<H", 100, "header size 100"),
    ("LAS 1.2", 94, "<H", 60000, "header size 60000"),
    ("LAS 1.2", 96, "<I", 2**31, "offset to point data 2147483648"),
    ("LAS 1.2", 100, "<I", 7, "number of VLRs (7)"),
    ("LAS 1.2", 104, "<B", 11, "point data format 11"),
    ("LAS 1.2", 105, "<H", 20, "record length 20"),
    ("LAS 1.2", 107, "<I", 201, "point count 201"),
    ("LAS 1.2", 107, "<I", 2**31, "point count 2147483648"),
    ("LAS 1.2", 131, "<d", 0.0, "x scale factor 0.0"),
    ("LAS 1.2", 163, "<d", float("nan"), "y offset nan"),
    ("LAS 1.4 normals", 247, "<Q", 2**40, "point count 1099511627776"),
    ("LAS 1.4 normals", 243, "<I", 1, "start of first EVLR 0"),
    ("LAZ 1.2", 107, "<I", 2**31, "point count 2147483648"),
    ("LAZ 1.2", 107, "<I", 0, "point count 0"),
    ("LAZ 1.4 normals", 247, "<Q", 2**40, "point count 1099511627776"),
]


@pytest.mark.parametrize("case", LAS_PROMISES, ids=[f"{c[0]}@{c[1]}={c[3]}" for c in LAS_PROMISES])
def test_a_las_promise_the_file_cannot_hold_is_one_line_naming_the_field(tmp_path, seeds, case):
    name, offset, code, value, words = case
    seed = seeds[name]
    message = _load_error(_write(tmp_path, f"bad{seed.suffix}", _field(seed.data, offset, code, value)))
    assert words in message


def _vlr_at(data: bytes, user: bytes) -> int:
    header_size, _, n_vlrs = struct.unpack_from("<HII", data, 94)
    at = header_size
    for _ in range(n_vlrs):
        if data[at + 2:at + 18].split(b"\0")[0] == user:
            return at
        at += 54 + struct.unpack_from("<H", data, at + 20)[0]
    raise AssertionError(f"no {user} VLR")


def test_laz_promises_are_checked_against_the_chunk_table_not_the_file_size(tmp_path, seeds):
    data = seeds["LAZ 1.2"].data
    offset = struct.unpack_from("<I", data, 96)[0]
    table = struct.unpack_from("<q", data, offset)[0]
    laszip = _vlr_at(data, b"laszip encoded") + 54
    cases = [(_field(data, offset, "<q", 2**40), "chunk table offset 1099511627776"),
             (_field(data, table + 4, "<I", 2**31), "number of chunks (2147483648)"),
             (_field(data, laszip + 12, "<I", 100), "does not fill the LAZ chunk table's 1 chunks of 100 points"),
             (_field(data, laszip + 32, "<H", 9), "number of items (9)"),
             (_field(data, _vlr_at(data, b"laszip encoded") + 20, "<H", 2), "holds 2 bytes"),
             (_field(data, 104, "<B", 3), "point count 200 x record length 34")]  # the compression bit cleared
    for i, (bad, words) in enumerate(cases):
        assert words in _load_error(_write(tmp_path, f"bad{i}.laz", bad))
    info = check_las_header(_write(tmp_path, "good.laz", data))  # what a streaming reader gets
    assert info.compressed and info.point_count == 200 and info.laszip.chunks == ((200, table - offset - 8),)
    assert info.point_data == (offset + 8, table)


def test_check_las_header_describes_a_valid_file_for_other_readers(tmp_path, seeds):
    data = seeds["LAS 1.4 normals"].data
    info = check_las_header(_write(tmp_path, "a.las", data))
    assert info.version == (1, 4) and info.point_format == 6 and not info.compressed and info.laszip is None
    assert info.record_length == 30 + 12 and info.point_count == 200
    assert info.point_data == (info.offset_to_point_data, info.offset_to_point_data + 200 * 42)
    assert [v.user_id for v in info.vlrs] == ["LASF_Spec"] and info.scales == (1e-4, 1e-4, 1e-4)


# --- the other formats' promises --------------------------------------------------------------

def _replace(data: bytes, old: bytes, new: bytes) -> bytes:
    assert data.count(old) >= 1
    return data.replace(old, new, 1)


OTHER_PROMISES = [  # (seed, old bytes, new bytes, words the message must hold)
    ("PLY ascii mesh", b"element vertex 162", b"element vertex 1099511627776", "element vertex count 1099511627776"),
    ("PLY ascii cloud", b"element vertex 200", b"element vertex -1", "element vertex count -1 is negative"),
    ("PLY binary mesh", b"element face 320", b"element face 2147483648", "element face count 2147483648"),
    ("PLY binary cloud", b"element vertex 200", b"element vertex 201", "element vertex count 201"),
    ("OFF", b"162 320 0", b"162 2147483648 0", "OFF face count 2147483648 needs a line"),
    ("OFF", b"162 320 0", b"-1 320 0", "OFF vertex count -1 is negative"),
    ("PCD binary", b"POINTS 200", b"POINTS 2147483648", "POINTS 2147483648"),
    ("PCD ascii", b"COUNT 1", b"COUNT 1099511627776", "COUNT 1099511627776"),
    ("PCD ascii", b"WIDTH 200", b"WIDTH -200", "WIDTH -200 is negative"),
    ("PTS Leica", b"200\n", b"1099511627776\n", "point count 1099511627776 on line 1"),
    ("PTS Expe binary", b"nofpoints 200", b"nofpoints 2147483648", "nofpoints 2147483648"),
    ("PTS Expe ascii", b"nofpoints 200", b"nofpoints 1099511627776", "nofpoints 1099511627776"),
    ("glTF", b'"count": 162', b'"count": 1099511627776', "count 1099511627776"),
]


@pytest.mark.parametrize("case", OTHER_PROMISES, ids=[f"{c[0]}:{c[2].decode()}" for c in OTHER_PROMISES])
def test_a_header_promise_the_file_cannot_hold_is_one_line_naming_the_field(tmp_path, seeds, case):
    name, old, new, words = case
    seed = seeds[name]
    assert words in _load_error(_write(tmp_path, f"bad{seed.suffix}", _replace(seed.data, old, new)))


def test_binary_headers_of_stl_glb_and_compressed_pcd(tmp_path, seeds):
    stl, glb, pcd = seeds["STL binary"], seeds["GLB"], seeds["PCD compressed"]
    assert "STL face count 2147483648" in _load_error(_write(tmp_path, "a.stl", _field(stl.data, 80, "<I", 2**31)))
    assert "GLB header's length" in _load_error(_write(tmp_path, "a.glb", _field(glb.data, 8, "<I", 2**31)))
    assert "GLB JSON chunk length" in _load_error(_write(tmp_path, "b.glb", _field(glb.data, 12, "<I", 2**31)))
    assert "GLB BIN length" in _load_error(_write(tmp_path, "c.glb", _field(glb.data, glb.fields[2][0], "<I", 2**31)))
    at = pcd.fields[0][0]  # the compressed and unpacked sizes after DATA binary_compressed
    packed = struct.unpack_from("<I", pcd.data, at)[0]
    assert "says 4294967295" in _load_error(_write(tmp_path, "a.pcd", _field(pcd.data, at, "<I", 2**32 - 1)))
    assert "unpacks to 4294967295" in _load_error(_write(tmp_path, "b.pcd", _field(pcd.data, at + 4, "<I", 2**32 - 1)))
    assert packed > 0


def test_an_ascii_ply_count_is_refused_before_plyfile_allocates_it(tmp_path, seeds, monkeypatch):
    import plyfile

    def refuse(*args, **kwargs):
        raise AssertionError("plyfile was asked to read the file")

    monkeypatch.setattr(plyfile.PlyData, "read", refuse)
    data = _replace(seeds["PLY ascii mesh"].data, b"element vertex 162", b"element vertex 2147483648")
    assert "element vertex count 2147483648" in _load_error(_write(tmp_path, "a.ply", data))


# --- PTS ----------------------------------------------------------------------------------------

def test_leica_pts_with_intensity_colours_and_two_scans_reads_the_positions(tmp_path):
    rows = np.array([[0.5, 1.0, -2.0, -1024, 10, 20, 30], [1.5, 0.0, 2.25, 2047, 255, 0, 7]])
    text = "2\n" + "".join(" ".join(f"{v:g}" for v in r) + "\n" for r in rows) + "1\n3 4 5\n\n"
    cloud = curv.load(_write(tmp_path, "scan.pts", text.encode()))
    assert isinstance(cloud, curv.PointCloud) and cloud.normals is None
    np.testing.assert_array_equal(cloud.points, [[0.5, 1.0, -2.0], [1.5, 0.0, 2.25], [3, 4, 5]])
    for bad, words in (("2\n1 2 3\n", "point count 2 on line 1 is more than the 1 line after it"),
                       ("1\n1 2 3\n4 5 6\n", "line 3 is not a point count"),
                       ("2\n1 2 3 4 5\n1 2 3 4 5\n", "5 columns"),
                       ("x y z\n1 2 3\n", "first line is not a point count")):
        assert words in _load_error(_write(tmp_path, "bad.pts", bad.encode()))


def test_expe_point_sets_read_with_their_normals(tmp_path, seeds):
    for name in ("PTS Expe binary", "PTS Expe ascii"):
        cloud = curv.load(_write(tmp_path, "a.pts", seeds[name].data))
        assert cloud.n_points == 200 and cloud.normals is not None
        np.testing.assert_allclose(np.linalg.norm(cloud.normals, axis=1), 1.0, atol=1e-5)
        np.testing.assert_allclose(np.linalg.norm(cloud.points, axis=1), 2.0, atol=1e-5)


def test_pymeshlab_chameleon_pts_loads_as_a_cloud_with_normals():
    pymeshlab = pytest.importorskip("pymeshlab")
    path = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "chameleon.pts"
    if not path.is_file():
        pytest.skip("pymeshlab ships no chameleon.pts")
    cloud = curv.load(path)
    assert isinstance(cloud, curv.PointCloud) and cloud.n_points == 4594
    np.testing.assert_allclose(np.linalg.norm(cloud.normals, axis=1), 1.0, atol=1e-6)
    assert np.ptp(cloud.points, axis=0).max() == pytest.approx(100.0)  # the chameleon is 100 units long
    res = curv.estimate(cloud, "qs", 2)
    assert res.valid.mean() > 0.8


# --- laspy's real sample files still load ----------------------------------------------------

def _laspy_folder() -> Path:
    """A folder of laspy's sample files: ``$CURV_LASPY_DATA``, else the tests' fetched copy; else skip."""
    if os.environ.get("CURV_LASPY_DATA"):
        return Path(os.environ["CURV_LASPY_DATA"])
    try:
        from tests.laspy_samples import laspy_sample
    except ImportError:
        pytest.skip("no laspy sample files: set CURV_LASPY_DATA to a folder of them")
    return laspy_sample("autzen_trim.laz").parent


def test_laspy_sample_files_pass_the_header_checks_and_load_as_laspy_reads_them():
    laspy = pytest.importorskip("laspy")
    files = sorted(_laspy_folder().glob("*.la[sz]"))
    assert files
    for path in files:
        info = check_las_header(path)
        cloud = curv.load(path)
        expected = laspy.read(path)
        assert cloud.n_points == info.point_count == len(expected.points), path.name
        np.testing.assert_array_equal(cloud.points[:, 0], np.asarray(expected.x))


def test_a_rust_readers_panic_is_a_one_line_load_error(tmp_path):
    from curv.core.paths import read_with

    class PanicException(BaseException):  # what pyo3 raises when lazrs panics: no Exception
        pass

    def reader(path):
        raise PanicException("attempt to calculate the remainder with a divisor of zero")

    with pytest.raises(LoadError, match=r"a\.laz: not a readable LAZ file \(the reader failed: attempt"):
        read_with(reader, tmp_path / "a.laz", "LAZ")
    with pytest.raises(KeyboardInterrupt):
        read_with(lambda path: (_ for _ in ()).throw(KeyboardInterrupt()), tmp_path / "a.laz", "LAZ")


# --- the fuzz runs ------------------------------------------------------------------------------

def _assert_clean(report):
    failures = "\n".join(f"case {i} ({name}; {mutation}): {kind}: {detail}"
                         for i, name, mutation, kind, detail in report.failures[:20])
    assert not report.failures, f"{len(report.failures)} failures\n{failures}\n{report.table()}"


def test_short_fuzz_run_of_every_format_ends_in_results_or_one_line_errors(tmp_path):
    # 12 mutations of each seed file, each read in a watched worker; every 4th that fails to load also
    # through `curv estimate FILE -o out.ply` (exit 2, one line, no file left)
    report = run_cases(12 * len(seed_files()), tmp_path, cli_every=4)
    _assert_clean(report)
    assert {c["error"] > 0 for c in report.counts.values()} == {True}
    assert sum(c["result"] for c in report.counts.values()) > 0


@pytest.mark.slow
def test_long_fuzz_run(tmp_path):
    """10,000 cases (laspy's sample files among the seeds when there are some), every tenth that fails
    to load through the CLI; prints the table (``pytest -m slow -s``)."""
    try:
        real = real_las_seeds(_laspy_folder())
    except pytest.skip.Exception:
        real = []
    seeds = seed_files() + real
    report = run_cases(10_000, tmp_path, cli_every=10, seeds=seeds)
    print("\n" + report.table())
    _assert_clean(report)
