"""Progress over every phase of an estimate (issue 36, item 6): the set-up's normals and orientation
are measured (curv.core.jit.iter_watched), the command line shows a bar per phase on a terminal and a
line every few seconds elsewhere, and the time left is the phase's own, never a guess from a phase
that has not started."""

from __future__ import annotations

import io
import threading
import time

import numpy as np
import plyfile
import pytest

import curv
from curv import progress as P
from curv.cli import main
from curv.core import jit as J
from curv.surfaces import Sphere, sample_points


def _chunked_work(n_chunks: int, seconds: float, log: list):
    """Work that runs its own chunk loop to the end (as the point normals do), announcing a second step."""
    def run(lo, hi):
        time.sleep(seconds)
        log.append(hi)

    def work():
        J.run_to_end(J.iter_chunks(n_chunks, run, chunk=1))
        J.announce("second step")
        time.sleep(3 * seconds)
        return "done"

    return work


def test_watched_work_reports_its_chunks_and_steps(monkeypatch):
    monkeypatch.setattr(J, "POLL_SECONDS", 0.005)
    log = []
    steps = []
    gen = J.iter_watched(_chunked_work(10, 0.02, log), phase="normals")
    while True:
        try:
            steps.append(next(gen))
        except StopIteration as stop:
            assert stop.value == "done"
            break
    phases = [s.phase for s in steps]
    assert phases[0] == "normals" and phases[-1] == "second step"
    assert "normals" not in phases[phases.index("second step"):]  # in that order
    fractions = [float(s) for s in steps if s.phase == "normals"]
    assert len(set(fractions)) >= 3 and fractions == sorted(fractions) and max(fractions) <= 1.0
    assert log == list(range(1, 11))


def test_closing_watched_work_stops_it_at_its_next_chunk(monkeypatch):
    monkeypatch.setattr(J, "POLL_SECONDS", 0.005)
    log = []
    gen = J.iter_watched(_chunked_work(200, 0.01, log), phase="normals")
    next(gen)
    gen.close()  # the viewer's cancel
    time.sleep(0.1)
    stopped_at = len(log)
    time.sleep(0.1)
    assert len(log) == stopped_at < 200
    assert not [t for t in threading.enumerate() if t.name == "curv normals"]


def test_an_error_of_watched_work_is_raised_to_its_caller():
    def work():
        raise curv.EstimatorError("bad option")

    with pytest.raises(curv.EstimatorError, match="bad option"):
        J.run_to_end(J.iter_watched(work))


@pytest.fixture(scope="module")
def cloud():
    """40,000 points of a sphere without normals: the normals take a few tenths of a second or more."""
    return sample_points(Sphere(2.0), 40_000, sampling="uniform", rng=4).cloud


def test_an_estimate_on_a_cloud_reports_its_normals_orientation_estimate_and_checks(cloud, monkeypatch):
    monkeypatch.setattr(J, "POLL_SECONDS", 0.002)
    steps = []
    gen = curv.iter_estimate(curv.PointCloud(cloud.points), "qs", 2)
    while True:
        try:
            steps.append(next(gen))
        except StopIteration as stop:
            res = stop.value
            break
    assert res.valid.mean() > 0.9
    order = list(dict.fromkeys(s.phase for s in steps))
    assert order == ["normals", "orientation", "estimate", "checks"], order
    normals = [float(s) for s in steps if s.phase == "normals"]
    assert len(set(normals)) >= 3 and max(normals) > 0.5  # the fit's own chunks, not 0 until it ends
    for phase in order:
        fractions = [float(s) for s in steps if s.phase == phase]
        assert 0.0 <= min(fractions) and max(fractions) <= 1.0


def test_a_mesh_estimate_names_its_setup_and_a_fitted_one_its_normals():
    from tests.meshes import icosphere

    mesh = icosphere(3)
    phases = {s.phase for s in _steps(curv.iter_estimate(mesh, "qs", 2))}
    assert {"setup", "estimate", "checks"} <= phases and "normals" not in phases
    phases = {s.phase for s in _steps(curv.iter_estimate(mesh, "qs", 2, normals="fit"))}
    assert "normals" in phases


def _steps(gen) -> list:
    out = []
    while True:
        try:
            out.append(next(gen))
        except StopIteration:
            return out


def test_time_left_is_measured_from_the_phases_first_fraction():
    """The issue's bar sat at 0 % for 40 s and then said "ETA 201265.1s": the time before a phase's
    first fraction (normals, compiling) is not a rate."""
    phase = P._Phase("estimate", now=0.0)
    phase.record(0.0, now=0.0)
    phase.record(0.0002, now=40.0)  # the first chunk, after 40 s of something else
    assert phase.left(40.5) is None  # not measured yet
    phase.record(0.1002, now=41.0)
    phase.record(0.2002, now=42.0)
    assert phase.left(42.0) == pytest.approx((1 - 0.2002) / 0.1)  # 8 s, not 40 / 0.0002
    phase.record(0.01, now=43.0)  # a new pass within the phase: measured anew
    assert phase.left(43.0) is None


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _run(progress: P.PhaseProgress):
    with progress:
        progress.phase("load")
        time.sleep(0.15)
        for i in range(1, 31):
            progress.update(J.Progress(i / 30, "compiling curvature kernels (first run only)..." if i == 1 else "",
                                       "normals" if i <= 20 else "estimate"))
            time.sleep(0.01)
        progress.phase("write")
        time.sleep(0.15)


def test_lines_every_few_seconds_when_not_a_terminal(monkeypatch):
    monkeypatch.setattr(P, "_RATE_SECONDS", 0.05)
    stream = io.StringIO()
    _run(P.PhaseProgress("qs R2", stream=stream, interval=0.05))
    lines = stream.getvalue().splitlines()
    assert lines.count("curv: compiling curvature kernels (first run only)...") == 1
    shown = [line for line in lines if line.startswith("curv: qs R2: ")]
    assert any(" load after " in line for line in shown)  # a phase that blocks gets lines too
    assert any(" normals " in line and " % after " in line for line in shown)
    assert any(" write after " in line for line in shown)
    assert any("left" in line for line in shown)
    assert "\r" not in stream.getvalue()


def test_short_work_writes_no_lines_and_quiet_writes_nothing():
    stream = io.StringIO()
    with P.PhaseProgress("qs R2", stream=stream, interval=30) as progress:
        progress.phase("load")
        progress.update(J.Progress(0.5, "", "estimate"))
    assert stream.getvalue() == ""
    stream = io.StringIO()
    _run(P.PhaseProgress("qs R2", stream=stream, mode="off", interval=0.01))
    assert stream.getvalue() == ""


def test_a_bar_per_phase_on_a_terminal():
    stream = _Terminal()
    _run(P.PhaseProgress("qs R2", stream=stream))
    text = stream.getvalue()
    for phase in ("load", "normals", "estimate", "write"):
        assert f"qs R2: {phase}" in text
    assert "100%|" in text and "curv: compiling curvature kernels" in text


def _write_cloud(path, points) -> None:
    vert = np.empty(len(points), dtype=[(c, "f8") for c in "xyz"])
    for i, c in enumerate("xyz"):
        vert[c] = points[:, i]
    plyfile.PlyData([plyfile.PlyElement.describe(vert, "vertex")]).write(str(path))


def test_the_command_writes_progress_lines_on_a_pipe(cloud, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(P, "LINE_SECONDS", 0.02)
    path = tmp_path / "sphere.ply"
    _write_cloud(path, cloud.points)
    assert main(["estimate", str(path), "-o", str(tmp_path / "out.ply")]) == 0
    err = capsys.readouterr().err.splitlines()
    shown = [line for line in err if line.startswith("curv: jet R2: ")]
    phases = {line.split(": ")[2].split(" ")[0] for line in shown}
    assert "normals" in phases and phases <= {"load", "normals", "orientation", "estimate", "checks", "write"}
    assert main(["estimate", str(path), "-q"]) == 0
    assert capsys.readouterr().err == ""


def test_a_phase_without_fractions_shows_its_time_alone():
    phase = P._Phase("orientation", now=0.0)
    phase.record(0.0, now=1.0)
    assert phase.words(6.7) == "orientation after 6.7 s"
    phase.record(0.25, now=7.0)
    assert phase.words(7.0).startswith("orientation 25 % after 7.0 s")
