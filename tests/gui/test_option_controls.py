"""The Options rows of the inspect panel in the real main window under Xvfb: one combo per option the
active pane's estimator declares and, on a mesh, the normals; choosing one computes that call, and
the defaults give back the plain pane."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui

import curv  # noqa: E402
from curv.estimators import ESTIMATORS  # noqa: E402
from PySide6.QtCore import Qt  # noqa: E402

from app.model import SurfaceSource  # noqa: E402
from app.model.options import option_rows, options_with  # noqa: E402


def _choose(window, name: str, text: str) -> None:
    """Pick the entry reading ``text`` in option row ``name``, as a click on it would."""
    combo = window.inspect.options.combos[name]
    i = combo.findText(text)
    assert i >= 0, [combo.itemText(j) for j in range(combo.count())]
    combo.setCurrentIndex(i)
    combo.activated.emit(i)


def _set_method(window, method: str) -> None:
    combo = window.inspect.method
    combo.setCurrentIndex(combo.findData(method))
    combo.activated.emit(combo.currentIndex())


def test_rows_follow_the_estimator_and_the_input_kind():
    jet = option_rows("jet", points=False)
    assert [r.name for r in jet] == ["degree", "weights", "width", "fit_range"]
    degree = jet[0]
    assert degree.default == 2 and degree.texts[degree.choices.index(2)] == "2 (default)"
    assert [r.name for r in option_rows("jet", points=True)] == ["degree", "weights", "width"]  # a cloud has no mesh normals
    assert [r.name for r in option_rows("qs", points=False)] == ["fit_range"]
    assert option_rows("qs", points=True) == []
    assert [r.name for r in option_rows("icc", points=False)] == ["from_measures", "fit_range"]
    # a default leaves the option out, so the pane is the plain one again
    assert options_with((), degree, 4) == (("degree", 4),)
    assert options_with((("degree", 4),), degree, 2) == ()
    normals = jet[-1]
    assert options_with((("degree", 4),), normals, 3) == (("degree", 4), ("fit_range", 3), ("normals", "fit"))
    assert options_with((("fit_range", 3), ("normals", "fit")), normals, None) == ()
    assert normals.current((("normals", "fit"),)) == 2 and normals.current(()) is None
    for method, spec in ESTIMATORS.items():  # every declared option has a row with its allowed values
        rows = {r.name: r for r in option_rows(method, points=False)}
        for name, allowed in spec.options.items():
            assert rows[name].choices == tuple(allowed) and rows[name].default in allowed


def test_choosing_options_computes_that_call_and_defaults_give_the_plain_pane(qtbot, window, ui):
    ui.open_surface("quadratic", n_vertices=817, noise=0.05, seed=3)
    _set_method(window, "jet")
    ui.wait_ready()
    doc, options = window.doc, window.inspect.options
    assert options.header.isVisible() and set(options.combos) == {"degree", "weights", "width", "fit_range"}
    assert options.combos["degree"].currentText() == "2 (default)"
    # folded by default (the histogram below stays in view), unfolded by a click on the header
    assert options.header.text() == "Options: defaults" and not options.combos["degree"].isVisible()
    qtbot.mouseClick(options.header, Qt.MouseButton.LeftButton)
    assert options.combos["degree"].isVisible()
    plain_key = doc.panes[0].key
    plain = doc.result(0)

    _choose(window, "degree", "4")
    ui.wait_ready()
    assert doc.panes[0].options == (("degree", 4),) and options.header.text() == "Options: degree 4"
    assert window.grid.viewports[0].title.text().startswith("A: jet R2 degree 4")
    res, expected = doc.result(0), curv.estimate(doc.mesh, "jet", range=2, degree=4)
    np.testing.assert_array_equal(res.valid, expected.valid)
    np.testing.assert_allclose(res.k1[res.valid], expected.k1[expected.valid], rtol=1e-12)
    assert not np.allclose(res.k1[res.valid], plain.k1[res.valid])          # the option changed the result

    _choose(window, "fit_range", "fitted at R4")
    ui.wait_ready()
    assert doc.panes[0].options == (("degree", 4), ("fit_range", 4), ("normals", "fit"))
    res = doc.result(0)
    expected = curv.estimate(doc.mesh, "jet", range=2, degree=4, normals="fit", fit_range=4)
    np.testing.assert_allclose(res.k1[res.valid], expected.k1[expected.valid], rtol=1e-12)

    # back to the defaults: the plain pane and its cached result, nothing computed again
    _choose(window, "fit_range", "mesh vertex normals (default)")
    _choose(window, "degree", "2 (default)")
    ui.wait_ready()
    assert doc.panes[0].options == () and doc.panes[0].key == plain_key and doc.result(0) is plain

    # another estimator shows its own rows, and starts from its defaults
    _choose(window, "degree", "3")
    ui.wait_ready()
    _set_method(window, "qs")
    ui.wait_ready()
    assert doc.panes[0].options == () and set(options.combos) == {"fit_range"}
    assert options.combos["fit_range"].currentText() == "mesh vertex normals (default)"


def test_point_clouds_show_only_the_estimator_options(qtbot, window, ui):
    window.open_surface(SurfaceSource(name="sphere", n_vertices=1500, sampling="uniform"))
    qtbot.waitUntil(lambda: window.doc.source is not None and window.doc.is_points, timeout=ui.timeout)
    ui.wait_ready()
    options = window.inspect.options
    _set_method(window, "qs")
    ui.wait_ready()
    assert not options.header.isVisible()                        # qs has no options, and a cloud no mesh normals
    _set_method(window, "jet")
    ui.wait_ready()
    assert options.header.isVisible() and set(options.combos) == {"degree", "weights", "width"}
    _choose(window, "weights", "smooth")
    ui.wait_ready()
    res = window.doc.result(0)
    expected = curv.estimate(window.doc.mesh, "jet", range=2, weights="smooth")
    np.testing.assert_allclose(res.k1[res.valid], expected.k1[expected.valid], rtol=1e-12)
