"""A file whose header promises what it cannot hold, opened in the viewer (readers bounded by their input).

The 400-byte text file that starts with ``LASF`` made laspy read VLRs for ever: the viewer's load
worker never returned. Now it shows the one-line error, the previous scene stays, no worker is left
running, and the next file opens.
"""

from __future__ import annotations

import numpy as np
import pytest

import curv
from tests.gui.conftest import TIMEOUT_MS

pytestmark = pytest.mark.gui

WAIT_MS = 60_000
"""A bad header is refused at once; a minute only bounds a hang."""


def _good_las(path):
    laspy = pytest.importorskip("laspy")
    from curv.surfaces import QuadraticPatch, sample_points

    points = sample_points(QuadraticPatch(), 1500, rng=4).cloud.points
    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.2"))
    las.header.scales = np.array([1e-4, 1e-4, 1e-4])
    las.x, las.y, las.z = points.T
    las.write(path)
    return path


@pytest.mark.parametrize("name, data", [
    ("x.las", ("LASF but not really\n" * 20).encode()),
    ("vlrs.las", None),  # a valid LAS header whose number of VLRs is 2^32 - 1
])
def test_a_bad_las_header_shows_one_line_and_the_window_stays_usable(qtbot, window, ui, tmp_path, name, data):
    ui.open_surface("saddle")
    mesh, result = window.doc.mesh, window.doc.result(0)
    good = _good_las(tmp_path / "good.las")
    if data is None:
        raw = bytearray(good.read_bytes())
        raw[100:104] = (2**32 - 1).to_bytes(4, "little")
        data = bytes(raw)
    bad = tmp_path / name
    bad.write_bytes(data)
    with qtbot.waitSignal(window.error_shown, timeout=WAIT_MS) as blocker:
        window.open_path(bad)
    text = blocker.args[0]
    assert name in text and "\n" not in text and "Traceback" not in text
    assert name in window.status_label.text()
    assert window.doc.mesh is mesh and window.doc.result(0) is result
    qtbot.waitUntil(lambda: not window.controller.busy, timeout=WAIT_MS)  # no load left running

    window.open_path(good)  # the window still opens files
    qtbot.waitUntil(lambda: isinstance(window.doc.mesh, curv.PointCloud), timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert window.doc.mesh.n_points == 1500
