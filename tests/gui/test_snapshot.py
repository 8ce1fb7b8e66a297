"""``curvlab ... --screenshot`` opens the real window, renders, saves and exits with a status."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

pytestmark = pytest.mark.gui


def _run(*args, timeout=180):
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.run([sys.executable, "-m", "app", *args], capture_output=True, text=True,
                          timeout=timeout, env=env)


def test_snapshot_writes_a_coloured_png_of_the_window_size(tmp_path, qapp):
    from PySide6.QtGui import QImage

    out = tmp_path / "shot.png"
    proc = _run("--surface", "torus", "--vertices", "642", "--method", "mru", "--range", "2",
                "--quantity", "gaussian", "--compare", "nc:2", "--screenshot", str(out), "--size", "1400x800")
    assert proc.returncode == 0, proc.stderr
    image = QImage(str(out))
    assert (image.width(), image.height()) == (1400, 800)
    ptr = image.convertToFormat(QImage.Format.Format_RGB888)
    arr = np.frombuffer(ptr.constBits(), np.uint8).reshape(800, ptr.bytesPerLine())[:, :4200].reshape(800, 1400, 3)
    assert len(np.unique(arr.reshape(-1, 3), axis=0)) > 200                   # not blank
    reddish = (arr[..., 0] > 150) & (arr[..., 2] < 110)
    bluish = (arr[..., 2] > 150) & (arr[..., 0] < 110)
    assert reddish.sum() > 500 and bluish.sum() > 500                          # K > 0 outside, < 0 inside


def test_snapshot_fails_with_a_message(tmp_path):
    proc = _run(str(tmp_path / "missing.ply"), "--screenshot", str(tmp_path / "x.png"))
    assert proc.returncode == 1 and "missing.ply" in proc.stderr and not (tmp_path / "x.png").exists()
    proc = _run("--method", "nope", "--screenshot", str(tmp_path / "x.png"))
    assert proc.returncode == 2 and "unknown estimator 'nope'" in proc.stderr
