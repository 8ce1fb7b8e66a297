"""The inspect panel: estimator and range of the active pane, quantity, colour map and limits,
histogram. Bound to the document: model events update the widgets (signals blocked while syncing),
widget edits call the model's setters."""

from __future__ import annotations

import contextlib

import curv
from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QDoubleValidator
from PySide6.QtWidgets import (
    QCheckBox, QComboBox, QFormLayout, QHBoxLayout, QLabel, QLineEdit, QPushButton, QVBoxLayout, QWidget,
)
from superqt import QEnumComboBox, QLabeledDoubleRangeSlider
from superqt.utils import qdebounced

from app.model import Document, Layer, LimitMode, Quantity, colormap_names

from .histogram import Histogram

__all__ = ["InspectPanel", "blocked"]

ALL_RANGES = (1, 2, 3, 4)


@contextlib.contextmanager
def blocked(*widgets):
    """Block the Qt signals of ``widgets`` while syncing them from the model."""
    old = [w.blockSignals(True) for w in widgets]
    try:
        yield
    finally:
        for w, o in zip(widgets, old):
            w.blockSignals(o)


class InspectPanel(QWidget):
    """Estimator, quantity and colour controls; ``recompute_requested`` asks to redo the active pane."""

    recompute_requested = Signal()

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.method = QComboBox()
        for name, spec in curv.ESTIMATORS.items():
            self.method.addItem(f"{name} — {spec.title}", name)
        self.range = QComboBox()
        for k in ALL_RANGES:
            self.range.addItem(f"R{k}", k)
        self.recompute = QPushButton("Recompute")
        self.quantity = QEnumComboBox(enum_class=Quantity)
        self.layer = QEnumComboBox(enum_class=Layer)
        self.directions = QCheckBox("Principal directions (d1 black, d2 blue)")
        self.cmap_div = QComboBox()
        self.cmap_div.addItems(colormap_names("diverging"))
        self.cmap_seq = QComboBox()
        self.cmap_seq.addItems(colormap_names("sequential"))
        self.limit_mode = QEnumComboBox(enum_class=LimitMode)
        self.percentiles = QLabeledDoubleRangeSlider(Qt.Orientation.Horizontal)
        self.percentiles.setRange(0.0, 100.0)
        self.percentiles.setDecimals(1)
        self.lo_edit, self.hi_edit = QLineEdit(), QLineEdit()
        for e in (self.lo_edit, self.hi_edit):
            e.setValidator(QDoubleValidator())
        self.shared = QCheckBox("Shared colour scale across panes")
        self.histogram = Histogram()
        self.invalid = QLabel()

        form = QFormLayout()
        row = QHBoxLayout()
        row.addWidget(self.range)
        row.addWidget(self.recompute)
        form.addRow("Estimator", self.method)
        form.addRow("Range", row)
        form.addRow("Quantity", self.quantity)
        form.addRow("Show", self.layer)
        form.addRow(self.directions)
        form.addRow("Diverging map", self.cmap_div)
        form.addRow("Sequential map", self.cmap_seq)
        form.addRow("Limits", self.limit_mode)
        form.addRow("Percentiles", self.percentiles)
        lim = QHBoxLayout()
        lim.addWidget(self.lo_edit)
        lim.addWidget(self.hi_edit)
        form.addRow("Min / max", lim)
        form.addRow(self.shared)
        lay = QVBoxLayout(self)
        lay.addLayout(form)
        lay.addWidget(self.histogram)
        lay.addWidget(self.invalid)
        lay.addStretch(1)

        self.method.currentIndexChanged.connect(self._method_edited)
        self.range.currentIndexChanged.connect(self._range_edited)
        self.recompute.clicked.connect(self.recompute_requested)
        self.quantity.currentEnumChanged.connect(lambda q: doc.display.update(quantity=q))
        self.layer.currentEnumChanged.connect(self._layer_edited)
        self.directions.toggled.connect(lambda on: doc.display.update(show_directions=on))
        self.cmap_div.currentTextChanged.connect(lambda n: doc.display.update(diverging_cmap=n))
        self.cmap_seq.currentTextChanged.connect(lambda n: doc.display.update(sequential_cmap=n))
        self.limit_mode.currentEnumChanged.connect(lambda m: doc.display.update(limit_mode=m))
        self._percentiles_edited = qdebounced(self._percentiles_edited, timeout=120)  # big meshes: not every tick
        self.percentiles.valueChanged.connect(self._percentiles_edited)
        self.lo_edit.editingFinished.connect(self._manual_edited)
        self.hi_edit.editingFinished.connect(self._manual_edited)
        self.shared.toggled.connect(lambda on: doc.display.update(shared_scale=on))
        self.histogram.limits_edited.connect(
            lambda lo, hi: doc.display.update(manual=(lo, hi), limit_mode=LimitMode.MANUAL))

        doc.display.changed.connect(lambda names: self.sync())
        doc.panes_changed.connect(self.sync)
        doc.pane_changed.connect(lambda i: self.sync())
        doc.mesh_changed.connect(self.sync)
        self.sync()

    # -- widget -> model ------------------------------------------------------------------------
    def _method_edited(self) -> None:
        method = self.method.currentData()
        spec = curv.ESTIMATORS[method]
        k = self.doc.panes[self.doc.active].range
        if k not in spec.ranges:  # keep the range if the estimator has it, else its nearest one
            k = min(spec.ranges, key=lambda r: abs(r - k))
        self.doc.set_pane(self.doc.active, method=method, range=k)

    def _range_edited(self) -> None:
        self.doc.set_pane(self.doc.active, range=self.range.currentData())

    def _layer_edited(self, layer: Layer) -> None:
        if layer.needs_truth and not self.doc.has_truth:
            self.sync()  # refuse: no truth for a file mesh
            return
        self.doc.display.update(layer=layer)

    def _percentiles_edited(self, value) -> None:
        self.doc.display.update(percentiles=(float(value[0]), float(value[1])), limit_mode=LimitMode.PERCENTILE)

    def _manual_edited(self) -> None:
        try:
            lo, hi = float(self.lo_edit.text()), float(self.hi_edit.text())
        except ValueError:
            return
        if lo < hi:
            self.doc.display.update(manual=(lo, hi), limit_mode=LimitMode.MANUAL)

    # -- model -> widget ------------------------------------------------------------------------
    def sync(self) -> None:
        """Show the document's state in every control without feeding edits back."""
        doc, st = self.doc, self.doc.display.state
        pane = doc.panes[doc.active]
        widgets = (self.method, self.range, self.quantity, self.layer, self.directions, self.cmap_div,
                   self.cmap_seq, self.limit_mode, self.percentiles, self.shared)
        with blocked(*widgets):
            self.method.setCurrentIndex(self.method.findData(pane.method))
            spec = curv.ESTIMATORS.get(pane.method)
            for i, k in enumerate(ALL_RANGES):
                self.range.model().item(i).setEnabled(spec is not None and k in spec.ranges)
            self.range.setCurrentIndex(self.range.findData(pane.range))
            self.quantity.setCurrentEnum(st.quantity)
            for i, layer in enumerate(Layer):
                self.layer.model().item(i).setEnabled(doc.has_truth or not layer.needs_truth)
            self.layer.setCurrentEnum(st.layer)
            self.directions.setChecked(st.show_directions)
            self.cmap_div.setCurrentText(st.diverging_cmap)
            self.cmap_seq.setCurrentText(st.sequential_cmap)
            self.limit_mode.setCurrentEnum(st.limit_mode)
            self.percentiles.setValue(tuple(st.percentiles))
            self.shared.setChecked(st.shared_scale)
            self.shared.setEnabled(len(doc.panes) > 1)

    def show_values(self, drawn, *, table, n_invalid: int | None, n_vertices: int) -> None:
        """Show the active view's field: histogram, limit fields, invalid count.

        Parameters
        ----------
        drawn : (values, clim, rgba) or None
            What :meth:`Document.colours` returned for the active view.
        table : (k, 3) uint8
            Its colour table.
        """
        if drawn is None:
            self.histogram.set_data(None, (0.0, 1.0), table)
            self.invalid.setText("")
            return
        values, clim, _ = drawn
        self.histogram.set_data(values, clim, table)
        for edit, v in zip((self.lo_edit, self.hi_edit), clim):
            if not edit.hasFocus():
                edit.setText(f"{v:.6g}")
        if n_invalid is not None:
            self.invalid.setText(f"Invalid vertices (grey): {n_invalid} of {n_vertices} "
                                 f"({100.0 * n_invalid / max(n_vertices, 1):.1f} %)")
