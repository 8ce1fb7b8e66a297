"""``python -m curv.warmup``: the kernels it compiles are in numba's cache for the next process."""

import os
import subprocess
import sys

PROBE = "from curv.warmup import pending_estimators; print(','.join(pending_estimators()))"


def _run(args, cache, **kw):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    return subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True, timeout=600, **kw)


def test_warmed_estimator_is_cached_for_the_next_process_and_others_are_not(tmp_path):
    before = _run(["-c", PROBE], tmp_path, check=True).stdout.strip().split(",")
    assert "meyer" in before and "csm" in before

    warmed = _run(["-m", "curv.warmup", "meyer", "--jobs", "1"], tmp_path, check=True)
    assert "meyer" in warmed.stdout and "kernels compiled" in warmed.stdout

    after = _run(["-c", PROBE], tmp_path, check=True).stdout.strip().split(",")
    assert "meyer" not in after
    assert "csm" in after  # only what was asked for

    again = _run(["-m", "curv.warmup", "meyer", "--if-needed"], tmp_path, check=True)
    assert again.stdout == ""  # nothing pending: nothing run


def test_unknown_step_is_refused_by_name(tmp_path):
    res = _run(["-m", "curv.warmup", "nosuch"], tmp_path)
    assert res.returncode == 2
    assert "nosuch" in res.stderr and "meyer" in res.stderr
