"""The per-vertex uncertainty in the viewer (issue 19 item 4): Show > Uncertainty (2 sigma), the
picked vertex's ``k1 = 0.52 ± 0.04`` and the exports' standard-error fields."""

from __future__ import annotations

import numpy as np
import pytest

from app.model import Layer, Quantity, readout_rows
from app.model.colors import INVALID_RGBA
from app.model.readout import fmt, fmt_se

pytestmark = pytest.mark.gui


def _noisy(ui, method: str = "qs") -> None:
    ui.open_surface("sphere", n_vertices=642, noise=0.05, seed=4)
    ui.window.doc.set_pane(0, method=method, range=2)
    ui.wait_ready()


def test_show_uncertainty_colours_twice_the_standard_error_of_the_chosen_principal_curvature(qtbot, window, ui):
    ui.window = window
    _noisy(ui)
    doc = window.doc
    window.inspect.layer.setCurrentEnum(Layer.UNCERTAINTY)     # offered without an analytic truth too
    assert doc.display.layer is Layer.UNCERTAINTY
    res = doc.result(0)
    np.testing.assert_array_equal(doc.values(0), 2.0 * res.k1_se)
    doc.display.update(quantity=Quantity.K2)
    np.testing.assert_array_equal(doc.values(0), 2.0 * res.k2_se)
    assert doc.display.state.field_title() == "2σ of k2"
    # an estimator without a fit has no standard error: every vertex drawn as invalid
    doc.set_pane(0, method="meyer", range=1)
    ui.wait_ready()
    assert np.isnan(doc.values(0)).all()
    assert (np.asarray(window.grid.viewports[0].colours) == INVALID_RGBA).all()


def test_picked_vertex_reads_value_plus_minus_two_standard_errors(qtbot, window, ui):
    ui.window = window
    _noisy(ui)
    doc = window.doc
    res = doc.result(0)
    v = int(np.flatnonzero(res.valid)[0])
    doc.set_picked(v)
    rows = dict(readout_rows(doc, v))
    assert rows["k1 ± 2σ"][0] == f"{fmt(res.k1[v])} ± {fmt_se(2 * res.k1_se[v])}"
    assert rows["k2 ± 2σ"][0] == f"{fmt(res.k2[v])} ± {fmt_se(2 * res.k2_se[v])}"
    assert f"{fmt(res.k1[v])} ± {fmt_se(2 * res.k1_se[v])}" in window.readout.toPlainText()
    doc.set_pane(0, method="meyer", range=1)                  # no standard error: the plain value
    ui.wait_ready()
    rows = dict(readout_rows(doc, v))
    assert rows["k1"][0] == fmt(doc.result(0).k1[v])


def test_viewer_exports_carry_the_standard_errors(qtbot, window, ui, tmp_path):
    import meshio
    from plyfile import PlyData

    ui.window = window
    _noisy(ui, "jet")
    res = window.doc.result(0)
    vert = PlyData.read(str(window.export_ply(tmp_path / "out.ply")))["vertex"].data
    np.testing.assert_allclose(vert["k1_se"], res.k1_se, rtol=1e-6)
    np.testing.assert_allclose(vert["k2_se"], res.k2_se, rtol=1e-6)
    data = meshio.read(window.export_vtu(tmp_path / "out.vtu")).point_data
    np.testing.assert_allclose(data["k1_se"], res.k1_se, rtol=1e-12)
