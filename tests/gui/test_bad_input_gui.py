"""A representative subset of the bad-input corpus opened in the viewer (issue 5).

Every bad file gives one error line naming the file, in the status bar and through ``error_shown``;
the previous scene stays; the window keeps working. A defective but loadable mesh opens and its
report appears in the status bar.
"""

from __future__ import annotations

import pytest

from tests.corpus import session_corpus
from tests.gui.conftest import TIMEOUT_MS

pytestmark = pytest.mark.gui

CASES = {c.name: c for c in session_corpus()}
BAD = ["truncated_binary", "nan_coordinate", "index_out_of_range", "not_a_mesh", "directory",
       "ascii_count_too_low", "empty_file"]
# a vertex-only PLY is a point cloud now, and opens as one (tests/gui/test_points_gui.py)


@pytest.mark.parametrize("name", BAD)
def test_bad_file_reports_one_line_and_keeps_scene(qtbot, window, ui, name):
    ui.open_surface("saddle")
    mesh, result = window.doc.mesh, window.doc.result(0)
    case = CASES[name]
    with qtbot.waitSignal(window.error_shown, timeout=TIMEOUT_MS) as blocker:
        window.open_path(case.path)
    text = blocker.args[0]
    assert str(case.path.name) in text and "\n" not in text and "Traceback" not in text
    assert case.message.lower() in text.lower()
    assert case.path.name in window.status_label.text()
    assert window.doc.mesh is mesh and window.doc.result(0) is result
    qtbot.waitUntil(lambda: not window.controller.busy, timeout=TIMEOUT_MS)


@pytest.mark.parametrize("name", ["bowtie_vertex", "isolated_vertices", "mixed_polygons"])
def test_defective_mesh_opens_with_its_report(qtbot, window, ui, name):
    case = CASES[name]
    window.open_path(case.path)
    qtbot.waitUntil(lambda: window.doc.mesh is not None
                    and window.doc.mesh.n_vertices == len(__import__("curv").load(case.path).vertices),
                    timeout=TIMEOUT_MS)
    ui.wait_ready()
    assert "vertices" in window.status_label.text() or window.doc.failures
