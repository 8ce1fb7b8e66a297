"""Every corpus file through ``curv estimate`` in a subprocess: status, one-line errors, no stray files.

The runs are started together (two at a time) once per session; each test then checks one of them.
"""

from __future__ import annotations

import functools
import os
import resource
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import curv
from tests.corpus import LOAD_ERROR, OK, as_root, session_corpus

CURV = str(Path(sys.executable).with_name("curv"))
CASES = {c.name: c for c in session_corpus()}


def _run(args, *, preexec_fn=None, timeout=120) -> subprocess.CompletedProcess:
    return subprocess.run([CURV, *map(str, args)], capture_output=True, text=True, timeout=timeout,
                          preexec_fn=preexec_fn)


def _args(case, out: Path) -> list:
    flags = {"merge_vertices": "--merge-vertices", "remove_degenerate": "--remove-degenerate",
             "orient": "--orient", "remove_unreferenced": "--remove-unreferenced"}
    return ["estimate", case.path, "-q", "-o", out, *(flags[k] for k, on in case.load_kwargs.items() if on)]


@functools.lru_cache(maxsize=1)
def _all_runs() -> dict:
    out_dir = Path(tempfile.mkdtemp(prefix="curv-cli-"))
    jobs = {}
    with ThreadPoolExecutor(max_workers=2) as pool:
        for name, case in CASES.items():
            if not case.as_root and as_root():
                continue  # tested separately as an unprivileged user
            out = out_dir / f"{name}.out.ply"
            jobs[name] = (out, pool.submit(_run, _args(case, out)))
    return {name: (out, fut.result()) for name, (out, fut) in jobs.items()}


def _one_line_error(proc, path) -> str:
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("curv: error: "), lines[0]
    assert str(path) in lines[0]
    return lines[0]


def _no_temp_files(folder: Path) -> None:
    assert not [p.name for p in folder.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize("name", [n for n in CASES if CASES[n].as_root or not as_root()])
def test_cli_on_corpus_file(name):
    case = CASES[name]
    out, proc = _all_runs()[name]
    assert "Traceback" not in proc.stderr + proc.stdout
    _no_temp_files(out.parent)
    if case.outcome == OK:
        assert proc.returncode == 0, proc.stderr
        assert proc.stdout.startswith(f"{case.path}: ")
        written = curv.load(out)
        assert written.n_vertices == curv.load(case.path, **case.load_kwargs).n_vertices
    else:
        assert proc.returncode == 2, (proc.returncode, proc.stderr)
        line = _one_line_error(proc, case.path)
        assert case.message.lower() in line.lower()
        assert not out.exists()


def test_cli_unreadable_file_as_unprivileged_user(tmp_path):
    case = CASES["unreadable"]
    if not as_root():
        proc = _run(["estimate", case.path, "-q"])
    else:
        setpriv = shutil.which("setpriv")
        if setpriv is None:
            pytest.skip("running as root without setpriv: cannot drop privileges")
        folder = Path(tempfile.mkdtemp(prefix="curv-perm-"))
        os.chmod(folder, 0o755)
        target = folder / "locked.ply"
        shutil.copyfile(CASES["sphere"].path, target)
        os.chmod(target, 0)
        # the checkout may sit where the unprivileged user cannot enter (a clone under mktemp -d):
        # run a world-readable copy of the package, with numba's cache in a folder it may write
        src = folder / "src"
        shutil.copytree(Path(curv.__file__).parent, src / "curv",
                        ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
        cache = folder / "numba-cache"
        cache.mkdir()
        os.chmod(cache, 0o777)
        for root, dirs, files in os.walk(src):
            os.chmod(root, 0o755)
            for name in files:
                os.chmod(Path(root) / name, 0o644)
        env = {**os.environ, "PYTHONPATH": str(src), "NUMBA_CACHE_DIR": str(cache)}
        # the interpreter and its site-packages may sit inside that folder too (a venv in the clone):
        # then nobody but root can run curv at all, and there is nothing to test
        probe = subprocess.run([setpriv, "--reuid=65534", "--regid=65534", "--clear-groups", sys.executable,
                                "-c", "import numpy, scipy, numba, plyfile, trimesh, curv.cli"],
                               capture_output=True, text=True, timeout=120, env=env, cwd=str(folder))
        if probe.returncode != 0:
            shutil.rmtree(folder)
            last = (probe.stderr.strip().splitlines() or ["no output"])[-1]
            pytest.skip(f"an unprivileged user cannot run this environment's python here ({last})")
        proc = subprocess.run([setpriv, "--reuid=65534", "--regid=65534", "--clear-groups", sys.executable,
                               "-m", "curv.cli", "estimate", str(target), "-q"], capture_output=True, text=True,
                              timeout=120, env=env, cwd=str(folder))
        shutil.rmtree(folder)
        case = type(case)(**{**case.__dict__, "path": target})
    assert proc.returncode == 2, proc.stderr
    assert "permission denied" in _one_line_error(proc, case.path)


def test_cli_triangle_only_estimator_on_polygons_is_one_line():
    case = CASES["mixed_polygons"]
    proc = _run(["estimate", case.path, "-q", "-m", "meyer", "-r", "1"])
    assert proc.returncode == 2
    assert "needs a triangle mesh" in _one_line_error(proc, "meyer")


def test_cli_unknown_estimator_and_range_are_one_line():
    path = CASES["sphere"].path
    for args, text in ((["-m", "nope"], "unknown estimator"), (["-m", "mru", "-r", "R1"], "allowed: any k >= 2"),
                       (["-m", "qs", "-r", "two"], "a number k >= 1 such as 2 or 2.5"),
                       (["-m", "meyer", "--radius", "0.3"], "takes no radius"),
                       (["-m", "qs", "-r", "2", "--radius", "0.3"], "either range= or radius=")):
        proc = _run(["estimate", path, "-q", *args])
        assert proc.returncode == 2
        line = proc.stderr.strip()
        assert "\n" not in line and text in line and "Traceback" not in line


def test_cli_bad_output_folder_fails_before_estimating(tmp_path):
    proc = _run(["estimate", CASES["sphere"].path, "-q", "-o", tmp_path / "no" / "such" / "out.ply"])
    assert proc.returncode == 2
    assert "does not exist" in _one_line_error(proc, tmp_path / "no" / "such")
    assert proc.stdout == ""


def _limit_file_size():
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))


def test_cli_failure_mid_write_leaves_no_file(tmp_path):
    """The output dies after 4 KiB (RLIMIT_FSIZE): one-line error, no partial file, no temp file."""
    out = tmp_path / "out.ply"
    proc = _run(["estimate", CASES["two_components"].path, "-q", "-o", out], preexec_fn=_limit_file_size)
    assert proc.returncode == 2, proc.stderr
    assert "file too large" in _one_line_error(proc, out).lower()
    assert list(tmp_path.iterdir()) == []


def test_cli_failure_mid_write_keeps_previous_output(tmp_path):
    out = tmp_path / "out.ply"
    out.write_bytes(b"previous result")
    proc = _run(["estimate", CASES["two_components"].path, "-q", "-o", out], preexec_fn=_limit_file_size)
    assert proc.returncode == 2
    assert out.read_bytes() == b"previous result"
    assert [p.name for p in tmp_path.iterdir()] == ["out.ply"]


def test_cli_refuses_up_front_when_memory_would_not_fit(tmp_path):
    """A PLY header announcing 10^9 vertices is refused from the header alone, naming the estimate."""
    path = tmp_path / "huge.ply"
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty double x\n"
              "property double y\nproperty double z\nelement face 2000000000\n"
              "property list uchar int vertex_indices\nend_header\n").encode()
    with open(path, "wb") as fh:  # the data the header promises, as a sparse file (no disk used)
        fh.write(header)
        fh.truncate(len(header) + 24 * 10**9 + 13 * 2 * 10**9)
    proc = _run(["estimate", path, "-q"], timeout=30)
    assert proc.returncode == 2
    line = _one_line_error(proc, path)
    assert "needs about" in line and "GiB" in line and "available" in line
    path.write_bytes(header)  # the header alone promises what the file cannot hold: refused as such
    proc = _run(["estimate", path, "-q"], timeout=30)
    assert proc.returncode == 2 and "element vertex count 1000000000 needs at least" in _one_line_error(proc, path)


def test_cli_hints_at_repairs():
    proc = _run(["estimate", CASES["triangle_soup"].path, "-q"])
    assert proc.returncode == 0
    assert "try --merge-vertices" in proc.stdout
    merged = _all_runs()["triangle_soup_merged"][1]
    assert "repair: merged 798 duplicate vertices" in merged.stdout
    assert "try --merge-vertices" not in merged.stdout


def test_cli_written_values_match_the_library(tmp_path):
    out, proc = _all_runs()["sphere"]
    from plyfile import PlyData

    vert = PlyData.read(str(out))["vertex"].data
    res = curv.estimate(curv.load(CASES["sphere"].path), "mru", 2)
    np.testing.assert_allclose(vert["k1"], res.k1, rtol=1e-6)
    assert np.array_equal(vert["valid"].astype(bool), res.valid)
