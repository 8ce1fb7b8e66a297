"""The Region panel: estimate every pane only around the picked vertex or in the active pane's view."""

from __future__ import annotations

import numpy as np
from curv.core.errors import EstimatorError
from PySide6.QtCore import Signal
from PySide6.QtWidgets import QCheckBox, QFormLayout, QHBoxLayout, QLabel, QLineEdit, QPushButton, QWidget

from app.model import Document, pane_letter
from app.model.inputs import is_points, unit_length
from app.model.region import REST_NOTE, ball_region, index_region, show_region, shown_region

__all__ = ["RegionPanel", "vertices_in_view"]

DEFAULT_RADIUS_EDGES = 8.0
"""The radius offered for a new mesh, in mean edge lengths."""


def vertices_in_view(viewport) -> np.ndarray:
    """(c,) int64 vertices of ``viewport``'s mesh inside its camera's view (the frame on screen,
    between the near and far planes); sides facing away or hidden behind others count too."""
    if viewport.poly is None:
        return np.zeros(0, np.int64)
    clip = viewport.clip_coordinates()
    w = clip[:, 3]
    inside = (w > 0) & np.all(np.abs(clip[:, :3]) <= w[:, None], axis=1)
    return np.flatnonzero(inside).astype(np.int64)


class RegionPanel(QWidget):
    """Region controls bound to the document; ``grid`` gives the active pane's view.

    Signals
    -------
    message(str, bool)
        A one-line note for the status bar, and whether it is an error.
    """

    message = Signal(str, bool)

    def __init__(self, doc: Document, grid, parent=None) -> None:
        super().__init__(parent)
        self.doc, self.grid = doc, grid
        self.centre = QLabel()
        self.centre.setWordWrap(True)
        self.radius = QLineEdit()
        self.radius.setToolTip("Radius of the ball around the picked vertex, in mesh units")
        self.around = QPushButton("Around picked vertex")
        self.around.setToolTip("Estimate every pane only at the vertices within the radius of the picked vertex")
        self.in_view = QPushButton("In view")
        self.in_view.setToolTip("Estimate every pane only at the vertices inside the active pane's view "
                                "(zoom in on a large mesh first)")
        self.whole = QPushButton("Whole mesh")
        self.whole.setToolTip("Estimate every pane on the whole mesh again (results already computed are reused)")
        self.follow = QCheckBox("Follow picks")
        self.follow.setToolTip("While a region around a vertex is shown, picking another vertex moves it there")
        self.follow.setChecked(True)
        self.around_hook = None
        """Called first by *Around picked vertex*; True when it handled the pick (a large file's preview
        is read at full resolution there, app.views.large_panel)."""
        self.status = QLabel()
        self.status.setWordWrap(True)
        self.status.setObjectName("region_status")
        note = QLabel(REST_NOTE)
        note.setWordWrap(True)
        note.setStyleSheet("color: #555;")
        buttons = QHBoxLayout()
        for b in (self.around, self.in_view, self.whole):
            buttons.addWidget(b)
        form = QFormLayout(self)
        form.addRow("Centre", self.centre)
        radius_row = QHBoxLayout()
        radius_row.addWidget(self.radius, 1)
        radius_row.addWidget(self.follow)
        form.addRow("Radius", radius_row)
        form.addRow(buttons)
        form.addRow(self.status)
        form.addRow(note)
        self.around.clicked.connect(self.estimate_around)
        self.in_view.clicked.connect(self.estimate_in_view)
        self.whole.clicked.connect(lambda: self._show(None))
        self.radius.returnPressed.connect(self.estimate_around)
        doc.mesh_changed.connect(self._on_mesh)
        doc.picked_changed.connect(self._on_picked)
        doc.panes_changed.connect(self.sync)
        doc.pane_changed.connect(lambda i: self.sync())
        self.sync()

    # -- actions --------------------------------------------------------------------------------
    def estimate_around(self) -> None:
        """Every pane estimated within the radius of the picked vertex (a one-line message if there is none)."""
        doc = self.doc
        if doc.mesh is None or doc.picked is None:
            self.message.emit("Pick a vertex in a pane first (click on the mesh)", True)
            return
        if self.around_hook is not None and self.around_hook():
            return
        if not self.radius.text().strip():  # a new mesh's default, asked when first needed
            self.radius.setText(f"{DEFAULT_RADIUS_EDGES * unit_length(doc.mesh):.3g}")
        try:
            region = ball_region(doc.mesh, doc.picked, float(self.radius.text()))
        except (ValueError, EstimatorError):
            self.message.emit(f"The region radius must be a positive length in mesh units; got {self.radius.text()!r}",
                              True)
            return
        self._show(region)

    def estimate_in_view(self) -> None:
        """Every pane estimated at the vertices inside the active pane's view."""
        doc = self.doc
        if doc.mesh is None or doc.active >= len(self.grid.viewports):
            return
        idx = vertices_in_view(self.grid.viewports[doc.active])
        if idx.size == 0:
            self.message.emit("No vertex of the mesh is in view: press R to see it again", True)
            return
        self._show(index_region(f"in view of pane {pane_letter(doc.active)}", idx))

    def _show(self, region) -> None:
        if self.doc.mesh is not None:
            show_region(self.doc, region)
            self.message.emit("Whole mesh" if region is None else f"Estimating in {region.title}", False)

    # -- model -> widgets ----------------------------------------------------------------------
    def _on_mesh(self, change) -> None:
        # the default radius is filled in at the first region: a mesh's length unit needs its edge
        # table, which neither an estimate nor the first picture needs (seconds at 1M vertices)
        self.radius.clear()
        unit = "spacings" if is_points(change.mesh) else "mean edge lengths"
        self.radius.setPlaceholderText(f"{DEFAULT_RADIUS_EDGES:g} {unit}")
        self.sync()

    def _on_picked(self, index) -> None:
        region = shown_region(self.doc)
        if index is not None and region is not None and self.follow.isChecked() \
                and region.centre is not None and region.centre != index:
            self.estimate_around()
        self.sync()

    def sync(self) -> None:
        doc = self.doc
        picked = doc.picked
        self.centre.setText("pick a vertex in a pane" if picked is None else f"vertex {picked} (picked)")
        self.around.setEnabled(doc.mesh is not None and picked is not None)
        self.in_view.setEnabled(doc.mesh is not None)
        region = shown_region(doc)
        self.whole.setEnabled(region is not None)
        if region is None or doc.mesh is None:
            self.status.setText("Every pane is estimated on the whole mesh.")
        else:
            share = 100.0 * region.size / max(doc.mesh.n_vertices, 1)
            self.status.setText(f"Shown: {region.title}, {share:.2g} % of the mesh.")
