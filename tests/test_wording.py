"""Counts read as words ("1 vertex", "2 vertices") in the mesh report, and the anisotropy owner."""

import numpy as np

import curv
from curv.core.quantities import anisotropy
from curv.core.wording import count_text


def test_count_text():
    assert count_text(1, "vertex", "vertices") == "1 vertex"
    assert count_text(0, "vertex", "vertices") == "0 vertices"
    assert count_text(2, "vertex", "vertices") == "2 vertices"


def test_report_of_one_triangle_and_a_stray_vertex_reads_in_the_singular():
    mesh = curv.Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5.0]]), [[0, 1, 2]])
    lines = mesh.report().lines()
    assert lines[0] == "4 vertices, 1 face (1 triangle), 3 edges"
    assert "1 connected component" in lines and "3 border edges in 1 loop" in lines
    assert "1 isolated vertex" in lines


def test_anisotropy():
    got = anisotropy(np.array([1.0, 1.0, 2.0, 0.0]), np.array([1.0, 0.0, -2.0, 0.0]))
    np.testing.assert_allclose(got[:3], [0.0, 1.0, 1.0])
    assert np.isnan(got[3])
