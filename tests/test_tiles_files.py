"""File to file on tiles (curv.tiles.estimate_file, curv estimate --tile-size): the same output as
the whole call, on real LAS files and on PLY points and meshes; interrupted runs resume; bad input,
a full disk and a killed worker never leave a partial output."""

from __future__ import annotations

import errno
import os
import pickle
import shutil
import signal

import numpy as np
import pytest

import curv
from curv.cli import main
from curv.core.errors import LoadError
from curv.tiles import estimate_file, iter_estimate_file
from curv.tiles.files import default_scratch

from laspy_samples import laspy_sample
from meshes import torus_grid

laspy = pytest.importorskip("laspy")

SCANNER = (637000.0, 850000.0, 3000.0)


def las_dims_equal(a, b, *, float_rtol: float = 0.0):
    """Every dimension of two LAS files equal (the added float ones to ``float_rtol`` when given)."""
    a, b = laspy.read(a), laspy.read(b)
    assert list(a.point_format.dimension_names) == list(b.point_format.dimension_names)
    for name in a.point_format.dimension_names:
        x, y = np.asarray(a[name]), np.asarray(b[name])
        if float_rtol and x.dtype.kind == "f":
            np.testing.assert_allclose(x, y, rtol=float_rtol, atol=1e-6, err_msg=name)
        else:
            assert np.array_equal(x, y, equal_nan=True), name


def leftovers(folder) -> list:
    """Temporary files a writer left beside its output."""
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


@pytest.fixture(scope="module")
def small_las():
    return laspy_sample("vegetation_1_3.las")


def test_a_real_las_file_on_tiles_equals_the_whole_call(tmp_path, small_las):
    from curv.formats.laswrite import save_las

    cloud = curv.load(small_las)
    whole = curv.estimate(cloud, "qs", orient=SCANNER)
    save_las(tmp_path / "whole.laz", small_las, whole)
    run = estimate_file(small_las, tmp_path / "tiled.laz", "qs", orient=SCANNER, tile_size=3000, workers=1)
    assert run.tiles >= 3 and run.points == cloud.n_points
    assert run.reasons.get("OK", 0) == int(whole.valid.sum())
    las_dims_equal(tmp_path / "whole.laz", tmp_path / "tiled.laz", float_rtol=1e-6)
    assert not default_scratch(tmp_path / "tiled.laz").exists()  # a finished run removes its scratch folder
    assert leftovers(tmp_path) == []


def _ply_rows(path):
    from plyfile import PlyData

    data = PlyData.read(str(path))
    faces = data["face"].data["vertex_indices"] if "face" in [e.name for e in data.elements] else None
    return data["vertex"].data, None if faces is None else np.stack(faces), data.comments


def _write_ply(path, vertices, faces=None, dtype="f4"):
    from plyfile import PlyData, PlyElement

    v = np.zeros(len(vertices), dtype=[("x", dtype), ("y", dtype), ("z", dtype)])
    v["x"], v["y"], v["z"] = np.asarray(vertices).T
    elements = [PlyElement.describe(v, "vertex")]
    if faces is not None:
        f = np.zeros(len(faces), dtype=[("vertex_indices", "i4", (3,))])
        f["vertex_indices"] = faces
        elements.append(PlyElement.describe(f, "face", len_types={"vertex_indices": "u1"}))
    PlyData(elements).write(str(path))


def test_a_ply_mesh_on_tiles_writes_the_whole_calls_file(tmp_path):
    mesh = torus_grid(90, 40)[0]
    _write_ply(tmp_path / "in.ply", mesh.vertices, mesh.face_indices.reshape(-1, 3), dtype="f8")
    shape = curv.load(tmp_path / "in.ply")
    curv.save_ply(tmp_path / "whole.ply", shape, curv.estimate(shape, "csm", 3))
    estimate_file(tmp_path / "in.ply", tmp_path / "tiled.ply", "csm", 3, tile_size=900, workers=1)
    (a, fa, ca), (b, fb, cb) = _ply_rows(tmp_path / "whole.ply"), _ply_rows(tmp_path / "tiled.ply")
    assert a.dtype == b.dtype and ca == cb
    for name in a.dtype.names:
        assert np.array_equal(a[name], b[name], equal_nan=True), name
    assert np.array_equal(fa, fb)


def test_a_process_opens_the_input_once_for_all_its_tiles_and_again_when_it_changes(tmp_path, monkeypatch):
    from curv.tiles import sources

    opened = []

    def counting(path, folder):
        opened.append(path)
        return reopen(path, folder)

    reopen = sources.reopen
    monkeypatch.setattr(sources, "reopen", counting)
    from curv.tiles import driver

    def as_a_cluster_sends_them(self, function, tasks, **keywords):  # each task its own copy of the input
        return iter_run(self, function, [pickle.loads(pickle.dumps(args)) for args in tasks], **keywords)

    iter_run = driver.Runner.iter_run
    monkeypatch.setattr(driver.Runner, "iter_run", as_a_cluster_sends_them)
    mesh = torus_grid(40, 20)[0]
    _write_ply(tmp_path / "in.ply", mesh.vertices, mesh.face_indices.reshape(-1, 3), dtype="f8")
    run = estimate_file(tmp_path / "in.ply", tmp_path / "a.ply", "mru", 2, tile_size=200, workers=1)
    assert run.tiles >= 3 and len(opened) == 1  # each tile's ring vertices read through one opening
    _write_ply(tmp_path / "in.ply", mesh.vertices * 2.0, mesh.face_indices.reshape(-1, 3), dtype="f8")
    os.utime(tmp_path / "in.ply", ns=(1, 1))  # another time, whatever the clock's resolution
    estimate_file(tmp_path / "in.ply", tmp_path / "b.ply", "mru", 2, tile_size=200, workers=1)
    assert len(opened) == 2
    shape = curv.load(tmp_path / "in.ply")
    curv.save_ply(tmp_path / "whole.ply", shape, curv.estimate(shape, "mru", 2))
    (a, _, _), (b, _, _) = _ply_rows(tmp_path / "whole.ply"), _ply_rows(tmp_path / "b.ply")
    for name in a.dtype.names:  # the second run read the new file's vertices, not the first's
        assert np.array_equal(a[name], b[name], equal_nan=True), name


def test_a_ply_cloud_on_tiles_writes_the_whole_calls_values(tmp_path):
    from curv.surfaces import Torus, sample_points

    pts = sample_points(Torus(), 8000, sampling="uniform", rng=5).cloud.points
    _write_ply(tmp_path / "in.ply", pts)
    cloud = curv.load(tmp_path / "in.ply")
    curv.save_ply(tmp_path / "whole.ply", cloud, curv.estimate(cloud, "jet", orient=(0, 0, 10)))
    estimate_file(tmp_path / "in.ply", tmp_path / "tiled.ply", "jet", orient=(0, 0, 10), tile_size=2000, workers=1)
    (a, _, ca), (b, _, cb) = _ply_rows(tmp_path / "whole.ply"), _ply_rows(tmp_path / "tiled.ply")
    assert a.dtype == b.dtype
    for name in a.dtype.names:
        if a[name].dtype.kind == "f":
            np.testing.assert_allclose(a[name], b[name], rtol=1e-5, atol=1e-6, err_msg=name)
        else:
            assert np.array_equal(a[name], b[name]), name


@pytest.mark.parametrize("workers", [1, 2])
def test_a_ply_scene_of_many_parts_on_tiles_writes_the_whole_calls_orientation(tmp_path, workers):
    """Oriented from each part's top (a PLY is not georeferenced): every part of every tile turned as
    the whole call orients it, in this process or on a local cluster (the parts travel with the
    rows; tests/test_tiles.py has the in-memory twin of this scene)."""
    from clouds import ground_ball_and_roof

    _write_ply(tmp_path / "in.ply", ground_ball_and_roof())
    cloud = curv.load(tmp_path / "in.ply")
    curv.save_ply(tmp_path / "whole.ply", cloud, curv.estimate(cloud, "qs"))
    run = estimate_file(tmp_path / "in.ply", tmp_path / "tiled.ply", "qs", tile_size=11000 // workers, workers=workers)
    assert run.tiles == 2 * workers
    (a, _, _), (b, _, _) = _ply_rows(tmp_path / "whole.ply"), _ply_rows(tmp_path / "tiled.ply")
    for name in ("valid", "reason"):
        assert np.array_equal(a[name], b[name]), name
    for name in ("nx", "ny", "nz", "k1", "k2"):
        np.testing.assert_allclose(a[name], b[name], rtol=1e-5, atol=1e-6, err_msg=name)


def test_the_command_tiles_when_asked_and_says_so(tmp_path, small_las, capsys):
    args = ["estimate", str(small_las), "-m", "qs", "--orient-normals", *map(str, SCANNER), "--quiet"]
    assert main([*args, "-o", str(tmp_path / "whole.laz")]) == 0
    whole_out = capsys.readouterr().out
    assert main([*args, "-o", str(tmp_path / "tiled.laz"), "--tile-size", "3000", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "tiles of at most 3,000 points" in out and "valid" in out
    valid = next(line for line in whole_out.splitlines() if line.startswith("qs R2:")).split(" of ")[0]
    assert valid.replace(",", "").split()[-1] in out.replace(",", "")
    las_dims_equal(tmp_path / "whole.laz", tmp_path / "tiled.laz", float_rtol=1e-6)


def test_the_command_writes_las_only_from_las(tmp_path, capsys):
    mesh = torus_grid(20, 10)[0]
    _write_ply(tmp_path / "in.ply", mesh.vertices, mesh.face_indices.reshape(-1, 3))
    assert main(["estimate", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out.laz")]) == 2
    err = capsys.readouterr().err
    assert "the input must be LAS/LAZ" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out.laz").exists()


def test_an_interrupted_run_leaves_no_output_and_resumes_from_its_finished_tiles(tmp_path, small_las):
    out = tmp_path / "out.laz"
    gen = iter_estimate_file(small_las, out, "qs", orient=SCANNER, tile_size=2000, workers=1)
    for step in gen:
        if getattr(step, "message", "").startswith("tiles 2/"):
            break
    with pytest.raises(KeyboardInterrupt):
        gen.throw(KeyboardInterrupt)  # Ctrl-C while the tiles run
    assert not out.exists() and leftovers(tmp_path) == []
    assert len(list((default_scratch(out) / "rows").glob("*.npy"))) == 2
    run = estimate_file(small_las, out, "qs", orient=SCANNER, tile_size=2000, workers=1)
    assert run.resumed == 2 and run.tiles > 2
    estimate_file(small_las, tmp_path / "again.laz", "qs", orient=SCANNER, tile_size=2000, workers=1)
    las_dims_equal(out, tmp_path / "again.laz")


def test_a_truncated_laz_is_one_line_and_no_output(tmp_path, capsys):
    source = laspy_sample("autzen_trim.laz")
    cut = tmp_path / "cut.laz"
    cut.write_bytes(source.read_bytes()[: source.stat().st_size // 2])
    with pytest.raises(LoadError):
        estimate_file(cut, tmp_path / "out.laz", "qs", tile_size=20000, workers=1)
    assert main(["estimate", str(cut), "-o", str(tmp_path / "out.laz"), "--tile-size", "20000", "--workers", "1",
                 "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "cut.laz" in err
    assert not (tmp_path / "out.laz").exists() and leftovers(tmp_path) == []


def test_a_header_promising_more_records_than_the_file_holds_is_refused(tmp_path, small_las):
    bad = tmp_path / "short.las"
    data = bytearray(small_las.read_bytes())
    with laspy.open(small_las) as reader:
        count = reader.header.point_count
    # LAS 1.3: the legacy point count at byte 107 (uint32)
    data[107:111] = np.uint32(count + 500).tobytes()
    bad.write_bytes(bytes(data))
    with pytest.raises(LoadError, match="short.las"):
        estimate_file(bad, tmp_path / "out.laz", "qs", tile_size=3000, workers=1)
    assert not (tmp_path / "out.laz").exists() and leftovers(tmp_path) == []


def test_a_full_disk_while_writing_leaves_no_output(tmp_path, small_las, monkeypatch):
    calls = []

    def full(self, points):
        calls.append(len(points))
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(laspy.LasWriter, "write_points", full)
    with pytest.raises(OSError) as caught:
        estimate_file(small_las, tmp_path / "out.laz", "qs", orient=SCANNER, tile_size=3000, workers=1)
    assert caught.value.errno == errno.ENOSPC and calls
    assert not (tmp_path / "out.laz").exists() and leftovers(tmp_path) == []


def test_a_full_disk_while_the_tiles_run_leaves_no_output(tmp_path, small_las, monkeypatch):
    import curv.tiles.scratch as scratch

    def full(path, array):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("curv.tiles.tasks.write_array", full)
    with pytest.raises(OSError):
        estimate_file(small_las, tmp_path / "out.laz", "qs", orient=SCANNER, tile_size=3000, workers=1)
    assert not (tmp_path / "out.laz").exists() and leftovers(tmp_path) == []
    del scratch


def test_a_local_cluster_gives_the_same_output_and_retries_a_killed_worker(tmp_path, small_las):
    """Two worker processes; one is killed once its first tile is done: its work is run again."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  env={"CURV_THREADS": "1"}) as cluster, distributed.Client(cluster) as client:
        killed = []
        gen = iter_estimate_file(small_las, tmp_path / "cluster.laz", "qs", orient=SCANNER, tile_size=1500,
                                 client=client)
        for step in gen:
            if not killed and getattr(step, "message", "").startswith("tiles 1/"):
                victim = sorted(client.scheduler_info()["workers"])[0]
                pid = client.run(os.getpid, workers=[victim])[victim]
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)
        assert killed
    estimate_file(small_las, tmp_path / "plain.laz", "qs", orient=SCANNER, tile_size=1500, workers=1)
    las_dims_equal(tmp_path / "plain.laz", tmp_path / "cluster.laz")


@pytest.mark.slow
def test_two_workers_started_by_hand_give_the_plain_runs_output(tmp_path, small_las):
    """A scheduler and two workers started as separate commands on 127.0.0.1 (docs/LARGE_SCANS.md)."""
    import socket
    import subprocess
    import sys
    import time

    pytest.importorskip("distributed")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    bin_dir = os.path.dirname(sys.executable)
    env = {**os.environ, "CURV_THREADS": "1"}
    procs = [subprocess.Popen([os.path.join(bin_dir, "dask"), "scheduler", "--host", "127.0.0.1", "--port", str(port),
                               "--no-dashboard"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    time.sleep(3)
    for _ in range(2):
        procs.append(subprocess.Popen([os.path.join(bin_dir, "dask"), "worker", f"tcp://127.0.0.1:{port}",
                                       "--nthreads", "1", "--no-dashboard"], env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL))
    try:
        time.sleep(5)
        assert main(["estimate", str(small_las), "-m", "qs", "--orient-normals", *map(str, SCANNER), "-o",
                     str(tmp_path / "cluster.laz"), "--scheduler", f"tcp://127.0.0.1:{port}", "--tile-size", "3000",
                     "--quiet"]) == 0
    finally:
        for p in procs:
            p.terminate()
        for p in procs:
            p.wait(timeout=30)
    estimate_file(small_las, tmp_path / "plain.laz", "qs", orient=SCANNER, tile_size=3000, workers=1)
    las_dims_equal(tmp_path / "plain.laz", tmp_path / "cluster.laz")
    shutil.rmtree(default_scratch(tmp_path / "cluster.laz"), ignore_errors=True)


def test_a_preview_says_what_it_shows_and_a_region_reads_full_resolution(tmp_path, small_las):
    """The viewer's preview of a large file and its region at full resolution (curv.tiles.preview,
    curv.tiles.regions): the region's values are the whole file's."""
    from curv.core.jit import run_to_end
    from curv.tiles.preview import read_preview
    from curv.tiles.regions import FileRegions

    preview = read_preview(small_las, 3000)
    n = curv.load(small_las).n_points
    stride = -(-n // 3000)
    assert preview.stride == stride and preview.words == f"{preview.shown:,} of {n:,} points shown (every {stride}th)"
    regions = FileRegions(small_las, scratch=tmp_path / "regions")
    centre = preview.shape.points[len(preview.shape.points) // 2]
    around = run_to_end(regions.iter_around(centre, 3.0, [("qs", 2, {"orient": SCANNER})]))
    assert around.ball.size > 20 and around.shape.n_points > around.ball.size  # the ball and its halo
    part = curv.estimate(around.shape, "qs", orient=SCANNER, vertices=around.ball)
    whole = curv.estimate(curv.load(small_las), "qs", orient=SCANNER)
    rows = around.ids[around.ball]
    np.testing.assert_allclose(part.k1[around.ball], whole.k1[rows], rtol=1e-9, atol=1e-12)
    assert np.array_equal(part.reason[around.ball], whole.reason[rows])
    regions.close()
    assert not (tmp_path / "regions").exists()


def test_a_preview_of_a_mesh_clusters_its_vertices(tmp_path):
    from curv.tiles.preview import read_preview

    mesh = torus_grid(120, 50)[0]
    _write_ply(tmp_path / "in.ply", mesh.vertices, mesh.face_indices.reshape(-1, 3))
    preview = read_preview(tmp_path / "in.ply", 1500)
    assert isinstance(preview.shape, curv.Mesh) and 800 < preview.shown <= 1.25 * 1500
    assert preview.words.endswith("vertices shown (clustered)") and "of 6,000" in preview.words
    assert preview.shape.report().components == 1  # still one closed torus


def test_the_command_tiles_by_itself_what_would_not_fit_in_its_budget():
    from argparse import Namespace

    from curv.tiles.command import wants_tiles

    args = Namespace(tile_size=None, scheduler=None, memory="2GB", memory_check=True, method="qs")
    assert wants_tiles(args, (5_000_000, 0), points=True)        # about 5 GB whole
    assert not wants_tiles(args, (100_000, 0), points=True)      # 0.3 GB whole
    assert not wants_tiles(args, None, points=True)              # a header that does not say: read whole
    assert wants_tiles(Namespace(**{**vars(args), "tile_size": 5000}), (100, 0), points=True)  # asked
    assert not wants_tiles(Namespace(**{**vars(args), "memory": None, "memory_check": False}), (10**9, 0), points=True)


@pytest.mark.parametrize("name", ["vegetation_1_3.las", "plane.laz"])
def test_a_real_scan_turned_up_by_default_equals_the_whole_call(tmp_path, name):
    """LAS/LAZ clouds are georeferenced: normals turned up at every point, which a tile decides as the
    whole call (plane.laz: coordinates on a 1 cm grid, a third of the points coincident)."""
    from curv.formats.laswrite import save_las

    source = laspy_sample(name)
    whole = curv.estimate(curv.load(source), "qs")
    assert whole.info["orientation"] == "up"
    save_las(tmp_path / "whole.laz", source, whole)
    run = estimate_file(source, tmp_path / "tiled.laz", "qs", tile_size=4000, workers=1)
    assert run.tiles >= 2
    las_dims_equal(tmp_path / "whole.laz", tmp_path / "tiled.laz", float_rtol=1e-6)


def test_a_tile_measuring_another_coordinate_step_runs_again_with_the_whole_clouds():
    """Half a scan on a 1 cm grid, half on a 1 mm grid: a tile of the coarse half measures 1 cm, the
    whole cloud 1 mm; the support floor (10 steps) lies between them and the radii, so those tiles
    run again with the whole cloud's step and equal the whole call."""
    from curv.tiles import estimate_tiled

    rng = np.random.default_rng(3)
    n = 12000
    xy = rng.uniform(0, [4.0, 1.0], size=(n, 2))
    z = 0.05 * np.sin(3 * xy[:, 0]) * np.cos(2 * xy[:, 1])
    pts = np.column_stack([xy, z])
    coarse = pts[:, 0] < 2.0
    pts[coarse] = np.round(pts[coarse], 2)
    pts[~coarse] = np.round(pts[~coarse], 3)
    cloud = curv.PointCloud(pts, georeferenced=True)
    whole = curv.estimate(cloud, "qs")
    assert whole.info["coordinate_step"] == pytest.approx(0.001)
    tiled = estimate_tiled(cloud, "qs", tile_size=3000)
    assert np.array_equal(tiled.reason, whole.reason)
    np.testing.assert_allclose(tiled.k1, whole.k1, rtol=1e-9, atol=1e-12)


def test_the_commands_progress_says_the_tiles_done_the_rate_and_the_time_left(tmp_path, small_las, capsys,
                                                                             monkeypatch):
    import curv.progress

    monkeypatch.setattr(curv.progress, "LINE_SECONDS", 0.01)  # a line at every tick: stderr is no terminal here
    monkeypatch.setattr(curv.progress, "_TICK_SECONDS", 0.01)
    assert main(["estimate", str(small_las), "-m", "qs", "--orient-normals", *map(str, SCANNER), "-o",
                 str(tmp_path / "tiled.laz"), "--tile-size", "3000", "--workers", "1"]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if line.startswith("curv: qs R2: tiles ")]
    assert any(" % after " in line and "points/s" in line and " left" in line and "tiles " in line.split(", ")[1]
               for line in lines), lines[-5:]


def test_a_tile_whose_workers_keep_dying_is_one_line_that_says_what_to_change():
    from distributed.scheduler import KilledWorker

    from curv.core.errors import CurvError
    from curv.tiles.driver import Runner, TileFailed

    runner = Runner(workers=1, worker_bytes=2 * 2**30)
    text = runner._failure("curv-tile-84d4d668-3", KilledWorker("curv-tile-84d4d668-3", "tcp://127.0.0.1:43075", 3))
    assert text.startswith("tile 3: every worker that ran it died") and "--memory" in text and "\n" not in text
    assert runner._failure("curv-tile-ab-12", ValueError("bad")) == "tile 12: ValueError: bad"
    assert issubclass(TileFailed, CurvError)  # the command prints it as one line, not as a bug
