"""The viewer's status says when a pane's radius left the mesh without estimates (issue 36, item 5):
the library's RadiusWarning words, naming the radius and the median spacing."""

from __future__ import annotations

import numpy as np
import pytest

from app.model import Pane

pytestmark = pytest.mark.gui


def test_the_status_names_a_radius_below_the_spacing(qtbot, window, ui):
    ui.open_surface("saddle", n_vertices=817)
    spacing = float(np.median(window.doc.mesh.longest_edge))
    radius = round(0.4 * spacing, 4)
    window.controller.compute_in_pane(0, Pane("qs", 2, radius=radius).validated())
    ui.wait_ready()
    assert window.doc.result(0).valid.sum() == 0
    text = window.status_label.text()
    assert f"radius={radius:g} is below the median spacing {spacing:.4g}" in text, text
