"""The viewer's document model on its own (plain Python: no display needed)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("app.model")

import curv  # noqa: E402
from app.model import Document, LimitMode, Pane, colormap, compute_limits, map_colours  # noqa: E402
from app.model.colors import INVALID_RGBA  # noqa: E402
from app.model.scalars import relative_error  # noqa: E402


def test_map_colours_ends_centre_and_nan():
    cmap = colormap("coolwarm")
    rgba = map_colours(np.array([-5.0, -1.0, 0.0, 1.0, 5.0, np.nan]), (-1.0, 1.0), cmap)
    assert rgba.dtype == np.uint8 and rgba.shape == (6, 4)
    from curv.colors import CLIP_SHADE

    np.testing.assert_array_equal(rgba[0, :3], (cmap.table[0] * CLIP_SHADE).astype(np.uint8))  # clipped: darkened
    np.testing.assert_array_equal(rgba[1, :3], cmap.table[0])                                   # at the limit: end colour
    np.testing.assert_array_equal(rgba[2, :3], cmap.table[128])  # 0 maps to the middle entry
    np.testing.assert_array_equal(rgba[4, :3], (cmap.table[-1] * CLIP_SHADE).astype(np.uint8))
    np.testing.assert_array_equal(rgba[3, :3], cmap.table[-1])
    np.testing.assert_array_equal(rgba[5], INVALID_RGBA)
    assert rgba[0, 2] > rgba[0, 0] and rgba[4, 0] > rgba[4, 2]  # blue low, red high


def test_limits_symmetric_percentile_minmax_manual():
    v = np.r_[np.linspace(-1.0, 3.0, 101), np.nan]
    assert compute_limits(v, mode=LimitMode.MINMAX, signed=True) == (-3.0, 3.0)
    assert compute_limits(v, mode=LimitMode.MINMAX, signed=False) == (-1.0, 3.0)
    lo, hi = compute_limits(v, mode=LimitMode.PERCENTILE, signed=True, percentiles=(2, 98))
    assert hi == pytest.approx(np.percentile(v[:-1], 98)) and lo == -hi
    assert compute_limits(v, mode=LimitMode.MANUAL, signed=True, manual=(0.5, -0.2)) == (-0.2, 0.5)
    lo, hi = compute_limits(np.full(4, 2.0), mode=LimitMode.MINMAX, signed=False)
    assert lo < 2.0 < hi


def test_relative_error_exact_values():
    est = curv.Curvature(k1=np.array([1.1, 2.0]), k2=np.array([0.9, np.nan]), d1=np.zeros((2, 3)),
                         d2=np.zeros((2, 3)), normals=np.zeros((2, 3)), valid=np.array([True, False]))
    truth = curv.Curvature(k1=np.array([1.0, 1.0]), k2=np.array([1.0, 1.0]), d1=np.zeros((2, 3)),
                           d2=np.zeros((2, 3)), normals=np.zeros((2, 3)), valid=np.array([True, True]))
    e = relative_error(est, truth)
    assert e[0] == pytest.approx(0.1) and np.isnan(e[1])


def _result(n, value):
    return curv.Curvature(k1=np.full(n, value), k2=np.full(n, value), d1=np.zeros((n, 3)), d2=np.zeros((n, 3)),
                          normals=np.zeros((n, 3)), valid=np.ones(n, bool))


def test_failure_reverts_pane_to_last_good_and_events_fire():
    mesh = curv.Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    doc = Document(default_panes=(Pane("mru", 2), Pane("nc", 2)))
    seen = []
    doc.pane_changed.connect(lambda i: seen.append(("pane", i)))
    doc.set_mesh("src", mesh)
    doc.set_result(Pane("mru", 2).key, _result(3, 1.0))
    doc.set_pane(0, method="ru")
    assert doc.missing_keys() == [Pane("ru", 2).key]
    doc.set_failure(Pane("ru", 2).key, "ru needs triangles")
    assert doc.panes[0] == Pane("mru", 2) and Pane("ru", 2).key in doc.failures
    assert seen == [("pane", 0), ("pane", 0)]
    doc.set_pane_count(2)
    assert doc.panes[1] == Pane("nc", 2) and doc.missing_keys() == [Pane("nc", 2).key]
    doc.set_result(Pane("nc", 2).key, _result(3, 3.0))
    doc.set_difference(True)
    fields = doc.fields()
    assert len(fields) == 3
    lo, hi = fields[0][1]
    assert fields[1][1] == (lo, hi) and 1.0 <= lo < hi <= 3.0      # shared scale over A and B (H = 1, 3)
    assert fields[0][2].kind == "sequential"                       # one sign: the whole sequential map
    np.testing.assert_allclose(fields[2][0], -2.0)               # A - B


def test_a_pane_left_at_the_default_follows_the_input_kind():
    """The default estimator is one registry fact per input kind (issue 36, item 11): the viewer asks
    it when the input kind changes, and keeps what was chosen or asked for on the command line."""
    from curv.estimators import DEFAULT_ESTIMATORS
    from curv.surfaces import make_surface

    mesh = make_surface("sphere", n_vertices=200).mesh
    cloud = curv.PointCloud(mesh.vertices)
    doc = Document()
    doc.set_mesh("cloud", cloud)  # the first input: a pane at the mesh default moves to the cloud default
    assert doc.panes[0] == Pane.default(DEFAULT_ESTIMATORS["points"]) != Pane.default(DEFAULT_ESTIMATORS["mesh"])
    doc.set_mesh("mesh", mesh)
    assert doc.panes[0] == Pane.default(DEFAULT_ESTIMATORS["mesh"])
    doc.set_pane(0, method="qs")  # a choice stays
    doc.set_mesh("cloud", cloud)
    assert doc.panes[0].method == "qs"
    asked = Document()
    asked.panes_asked = True  # curvlab --method mru scan.laz
    asked.set_mesh("cloud", cloud)
    assert asked.panes[0] == Pane.default(DEFAULT_ESTIMATORS["mesh"])
