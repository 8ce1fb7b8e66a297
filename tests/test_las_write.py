"""LAS/LAZ out (curv.formats.laswrite): every record, VLR and EVLR of real LiDAR files kept, the
curvature added as documented extra bytes; nothing partial on bad input or a full disk."""

from __future__ import annotations

import errno

import numpy as np
import pytest

import curv
from curv.core.errors import LoadError
from curv.formats.laswrite import FIELDS, GROUPS, fields_for, save_las, write_las

from laspy_samples import laspy_sample

laspy = pytest.importorskip("laspy")

# laspy's own sample files: LAS 1.1 to 1.4, point formats 1, 3, 6, 7 and 8, LAZ, COPC, EVLRs,
# WKT and GeoTIFF coordinate systems, the file's own extra bytes
SAMPLES = ("simple1_1.las", "simple.las", "simple.laz", "vegetation_1_3.las", "simple1_3.las", "simple1_4.las",
           "1_4_w_evlr.las", "1_4_w_evlr.laz", "file_with_both_wkt_and_geotiff_vlrs.las", "extrabytes.las",
           "extra.laz", "simple.copc.laz", "test1_4.las", "autzen.las", "unregistered_extra_bytes.las")


def _fake(start: int, stop: int) -> dict:
    """Result columns of points start..stop-1 whose values say which point they belong to."""
    i = np.arange(start, stop, dtype=np.float64)
    m = stop - start
    rows = {"k1": i + 0.5, "k2": -i, "d1": np.tile([1.0, 0.0, 0.0], (m, 1)), "d2": np.tile([0.0, 1.0, 0.0], (m, 1)),
            "normals": np.tile([0.0, 0.0, 1.0], (m, 1)), "valid": (np.arange(start, stop) % 3) != 0,
            "reason": (np.arange(start, stop) % 3 == 0).astype(np.uint8), "k1_se": i * 0.1, "k2_se": i * 0.2}
    return rows


def _vlrs(header_or_list):
    out = []
    for v in header_or_list:
        if type(v).__name__ in ("ExtraBytesVlr", "LasZipVlr") or v.user_id.rstrip("\0") in ("copc", "laszip encoded"):
            continue
        try:
            data = bytes(v.record_data_bytes())
        except AttributeError:
            data = bytes(v.record_data)
        out.append((v.user_id, v.record_id, data))
    return out


@pytest.mark.parametrize("name", SAMPLES)
def test_every_record_vlr_and_evlr_of_a_real_file_is_kept(tmp_path, name):
    source = laspy_sample(name)
    out = tmp_path / ("out" + source.suffix)
    write_las(out, source, _fake, groups=GROUPS, chunk=400)  # several chunks even for the small files
    a, b = laspy.read(source), laspy.read(out)
    assert b.header.version == a.header.version and b.point_format.id == a.point_format.id
    assert np.array_equal(b.header.scales, a.header.scales) and np.array_equal(b.header.offsets, a.header.offsets)
    assert b.header.point_count == a.header.point_count
    for dim in a.point_format.dimension_names:  # standard dimensions and the file's own extra bytes, in order
        assert np.array_equal(a[dim], b[dim], equal_nan=True), dim
    assert _vlrs(b.header.vlrs) == _vlrs(a.header.vlrs)  # the coordinate system's among them
    assert _vlrs(b.evlrs or []) == _vlrs(a.evlrs or [])
    n = a.header.point_count
    expected = _fake(0, n)
    np.testing.assert_array_equal(b["k1"], expected["k1"].astype(np.float32))
    np.testing.assert_array_equal(b["mean"], (0.5 * (expected["k1"] + expected["k2"])).astype(np.float32))
    np.testing.assert_array_equal(b["gaussian"], (expected["k1"] * expected["k2"]).astype(np.float32))
    np.testing.assert_array_equal(b["valid"], expected["valid"].astype(np.uint8))
    np.testing.assert_array_equal(b["reason"], expected["reason"])
    np.testing.assert_array_equal(b["d2y"], np.ones(n, np.float32))
    np.testing.assert_array_equal(b["k2_se"], (expected["k2_se"]).astype(np.float32))
    assert b["nz"].dtype == np.float32


def test_the_extra_bytes_are_described_for_other_readers(tmp_path):
    source = laspy_sample("simple.las")
    write_las(tmp_path / "out.las", source, _fake)
    with laspy.open(tmp_path / "out.las") as reader:
        vlr = reader.header.vlrs.get("ExtraBytesVlr")[0]
        described = {s.name.rstrip(b"\0").decode(): s.description.rstrip(b"\0").decode()
                     for s in vlr.extra_bytes_structs}
    assert list(described) == [f.name for f in fields_for()]  # the curvature group only, by default
    assert described["k1"] == "larger principal curvature" and described["reason"].startswith("curvlab reason")
    assert all(len(f.description) <= 32 and len(f.name) <= 32 for f in FIELDS)


def test_a_real_scan_with_its_curvature(tmp_path):
    source = laspy_sample("vegetation_1_3.las")
    res = curv.estimate(curv.load(source), "qs", orient=(0, 0, 1e4))
    save_las(tmp_path / "out.laz", source, res, groups=("normals",))
    b = laspy.read(tmp_path / "out.laz")
    np.testing.assert_array_equal(b["k1"], res.k1.astype(np.float32))
    np.testing.assert_array_equal(b["valid"], res.valid.astype(np.uint8))
    np.testing.assert_array_equal(b["nz"], res.normals[:, 2].astype(np.float32))
    assert np.isnan(b["k1"][~res.valid]).all()


def test_a_file_curvlab_wrote_is_written_again_in_place_of_its_values(tmp_path):
    source = laspy_sample("simple.las")
    write_las(tmp_path / "once.las", source, _fake)
    write_las(tmp_path / "twice.las", tmp_path / "once.las", lambda a, b: {**_fake(a, b), "k1": np.zeros(b - a)})
    twice = laspy.read(tmp_path / "twice.las")
    assert list(twice.point_format.extra_dimension_names).count("k1") == 1
    assert np.all(twice["k1"] == 0)


def test_a_dimension_of_another_type_with_a_curvature_name_is_refused(tmp_path):
    header = laspy.LasHeader(point_format=3, version="1.4")
    header.add_extra_dims([laspy.ExtraBytesParams(name="k1", type=np.int32)])
    las = laspy.LasData(header)
    las.x, las.y, las.z = np.arange(5.0), np.arange(5.0), np.arange(5.0)
    las.write(tmp_path / "clash.las")
    with pytest.raises(LoadError, match="k1"):
        write_las(tmp_path / "out.las", tmp_path / "clash.las", _fake)
    assert not (tmp_path / "out.las").exists()


def test_a_truncated_input_leaves_no_output(tmp_path):
    source = laspy_sample("autzen_trim.laz")
    cut = tmp_path / "cut.laz"
    cut.write_bytes(source.read_bytes()[: source.stat().st_size * 2 // 3])
    with pytest.raises(LoadError, match="cut.laz"):
        write_las(tmp_path / "out.laz", cut, _fake)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cut.laz"]


def test_a_full_disk_leaves_no_output(tmp_path, monkeypatch):
    source = laspy_sample("simple1_4.las")
    written = []
    real = laspy.LasWriter.write_points

    def filling(self, points):
        if written:
            raise OSError(errno.ENOSPC, "No space left on device")
        written.append(len(points))
        return real(self, points)

    monkeypatch.setattr(laspy.LasWriter, "write_points", filling)
    with pytest.raises(OSError) as caught:
        write_las(tmp_path / "out.las", source, _fake, chunk=5000)
    assert caught.value.errno == errno.ENOSPC and written
    assert list(tmp_path.iterdir()) == []


def test_a_result_of_another_length_is_refused(tmp_path):
    source = laspy_sample("simple.las")
    res = curv.estimate(curv.PointCloud(np.random.default_rng(0).normal(size=(50, 3))), "qs", knn=10)
    with pytest.raises(ValueError, match="1065"):
        save_las(tmp_path / "out.las", source, res)
