"""The inspect panel: the active pane's estimator and range (one group), the display settings every
pane shares (another group), and the histogram. Bound to the document: model events update the
widgets (signals blocked while syncing), widget edits call the model's setters."""

from __future__ import annotations

import contextlib

from curv import ranges
from curv.errors import EstimatorError
from curv.estimators import ESTIMATORS
from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QDoubleValidator
from PySide6.QtWidgets import (
    QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QGroupBox, QHBoxLayout, QLabel, QLineEdit,
    QPushButton, QToolButton, QVBoxLayout, QWidget,
)
from superqt import QEnumComboBox, QLabeledDoubleRangeSlider
from superqt.utils import qdebounced

from app.model import Document, Layer, LimitMode, Pane, Quantity, colormap_names, format_limit, pane_letter
from app.model.document import takes_support

from .histogram import Histogram
from .style import PANE_COLOURS

__all__ = ["InspectPanel", "blocked", "estimator_tooltip"]


@contextlib.contextmanager
def blocked(*widgets):
    """Block the Qt signals of ``widgets`` while syncing them from the model."""
    old = [w.blockSignals(True) for w in widgets]
    try:
        yield
    finally:
        for w, o in zip(widgets, old):
            w.blockSignals(o)


def estimator_tooltip(spec) -> str:
    """Rich-text tooltip of an estimator from its registry entry."""
    named = ", ".join(ranges.range_label(k) for k in spec.ranges)
    extra = ("any real range from " + ranges.range_label(min(spec.ranges)) + " up, or a fixed radius"
             if takes_support(spec) else "its fixed 1-ring only")
    polys = "triangles only" if spec.triangles_only else "triangles and polygons"
    return (f"<b>{spec.name}</b>: {spec.title}<br>{spec.reference}<br>ranges {named}; {extra}<br>{polys}; "
            f"{'border vertices and those whose support reaches a border are invalid' if spec.closed_ring else 'fits near borders too'}")


RANGE_TIP = ("<b>Range Rk</b> (paper §4.1): the support of vertex p is every vertex connected to p within "
             "k × the longest edge of p's 1-ring. Pick a preset R1–R4 or type a real k such as 2.5.<br>"
             "<b>Radius</b>: the same ball of radius r (mesh units) at every vertex instead.")
LIMITS_TIP = ("<b>Percentile</b>: robust limits from the 2–98 % percentiles (adjustable); <b>Min / max</b>: the "
              "whole span; <b>Manual</b>: the values you type or drag on the histogram. Signed fields that "
              "straddle 0 get symmetric limits and a diverging map; fields of one sign a sequential map. "
              "Values beyond the limits are drawn in the map's end colours darkened.")


class InspectPanel(QWidget):
    """Estimator, quantity and colour controls.

    Signals
    -------
    recompute_requested()
        Redo the active pane.
    message(str)
        A one-line note for the status bar (e.g. a range the estimator does not take).
    """

    recompute_requested = Signal()
    message = Signal(str)

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.method = QComboBox()
        for i, (name, spec) in enumerate(ESTIMATORS.items()):
            self.method.addItem(f"{name} — {spec.title}", name)
            self.method.setItemData(i, estimator_tooltip(spec), Qt.ItemDataRole.ToolTipRole)
        self.method.setToolTip("Estimator of the active pane (hover an entry for its reference)")
        self.range = QComboBox()
        self.range.setEditable(True)
        self.range.setInsertPolicy(QComboBox.InsertPolicy.NoInsert)
        for k in ranges.PAPER_RANGES:
            self.range.addItem(ranges.range_label(k), k)
        self.range.setToolTip(RANGE_TIP)
        self.use_radius = QCheckBox("Radius")
        self.use_radius.setToolTip(RANGE_TIP)
        self.radius = QDoubleSpinBox()
        self.radius.setDecimals(6)
        self.radius.setStepType(QDoubleSpinBox.StepType.AdaptiveDecimalStepType)
        self.radius.setRange(1e-6, 1e9)
        self.radius.setKeyboardTracking(False)
        self.radius.setSpecialValueText("—")  # shown while no radius is set
        self.radius.setToolTip("Ball radius in mesh units (the same at every vertex)")
        self.recompute = QPushButton("Recompute")
        self.recompute.setToolTip("Compute the active pane again (F5)")
        self.advise_button = QToolButton()  # the window binds it to its Advise action
        self.advise_button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextOnly)
        self.quantity = QEnumComboBox(enum_class=Quantity)
        self.quantity.setToolTip("<br>".join(f"<b>{q.title}</b>: {q.spec.formula}" for q in Quantity))
        self.layer = QEnumComboBox(enum_class=Layer)
        self.directions = QCheckBox("Principal directions")
        self.edges = QCheckBox("Edges")
        self.borders = QCheckBox("Borders")
        self.points = QCheckBox("Points")
        self.edges.setToolTip("Wireframe overlay of the mesh edges")
        self.borders.setToolTip("Border edges (one face) highlighted")
        self.points.setToolTip("Draw the vertices as points")
        self.cmap_div = QComboBox()
        self.cmap_div.addItems(colormap_names("diverging"))
        self.cmap_div.setToolTip("Map of signed fields that straddle zero (centred on 0)")
        self.cmap_seq = QComboBox()
        self.cmap_seq.addItems(colormap_names("sequential"))
        self.cmap_seq.setToolTip("Map of unsigned fields and of signed ones of one sign")
        self.limit_mode = QEnumComboBox(enum_class=LimitMode)
        self.limit_mode.setToolTip(LIMITS_TIP)
        self.percentiles = QLabeledDoubleRangeSlider(Qt.Orientation.Horizontal)
        self.percentiles.setRange(0.0, 100.0)
        self.percentiles.setDecimals(1)
        self.lo_edit, self.hi_edit = QLineEdit(), QLineEdit()
        for e in (self.lo_edit, self.hi_edit):
            e.setValidator(QDoubleValidator())
            e.setToolTip(LIMITS_TIP)
        self.lock = QCheckBox("Keep for new meshes")
        self.lock.setToolTip("Keep manual limits when another mesh opens (otherwise they reset to percentiles)")
        self.shared = QCheckBox("Shared colour scale across panes")
        self.histogram = Histogram()
        self.histogram.setToolTip("Drag a limit line to set manual limits")
        self.invalid = QLabel()
        self.invalid.setWordWrap(True)

        self.pane_box = QGroupBox()
        self.pane_box.setObjectName("pane_box")
        pane_form = QFormLayout(self.pane_box)
        pane_form.addRow("Estimator", self.method)
        range_row = QHBoxLayout()
        range_row.addWidget(self.range, 1)
        range_row.addWidget(self.recompute)
        pane_form.addRow("Range", range_row)
        radius_row = QHBoxLayout()
        radius_row.addWidget(self.use_radius)
        radius_row.addWidget(self.radius, 1)
        pane_form.addRow("", radius_row)
        pane_form.addRow("", self.advise_button)
        self.all_box = QGroupBox("All panes")
        form = QFormLayout(self.all_box)
        form.addRow("Quantity", self.quantity)
        form.addRow("Show", self.layer)
        overlays = QHBoxLayout()
        for w in (self.directions, self.edges):
            overlays.addWidget(w)
        form.addRow(overlays)
        overlays2 = QHBoxLayout()
        for w in (self.borders, self.points):
            overlays2.addWidget(w)
        form.addRow(overlays2)
        form.addRow("Diverging map", self.cmap_div)
        form.addRow("Sequential map", self.cmap_seq)
        form.addRow("Limits", self.limit_mode)
        form.addRow("Percentiles", self.percentiles)
        lim = QHBoxLayout()
        lim.addWidget(self.lo_edit)
        lim.addWidget(self.hi_edit)
        form.addRow("Min / max", lim)
        form.addRow("", self.lock)
        form.addRow(self.shared)
        form.addRow(self.histogram)
        form.addRow(self.invalid)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addWidget(self.pane_box)
        lay.addWidget(self.all_box)
        lay.addStretch(1)
        for combo in self.findChildren(QComboBox):  # narrow docks: combos shrink and elide, never clip the panel
            combo.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
            combo.setMinimumContentsLength(6)

        self.method.currentIndexChanged.connect(self._method_edited)
        self.range.activated.connect(lambda _i: self._range_edited())
        self.range.lineEdit().editingFinished.connect(self._range_edited)
        self.use_radius.toggled.connect(self._radius_toggled)
        self.radius.valueChanged.connect(self._radius_edited)
        self.recompute.clicked.connect(self.recompute_requested)
        self.quantity.currentEnumChanged.connect(lambda q: doc.display.update(quantity=q))
        self.layer.currentEnumChanged.connect(self._layer_edited)
        self.directions.toggled.connect(lambda on: doc.display.update(show_directions=on))
        self.edges.toggled.connect(lambda on: doc.display.update(show_edges=on))
        self.borders.toggled.connect(lambda on: doc.display.update(show_borders=on))
        self.points.toggled.connect(lambda on: doc.display.update(show_points=on))
        self.cmap_div.currentTextChanged.connect(lambda n: doc.display.update(diverging_cmap=n))
        self.cmap_seq.currentTextChanged.connect(lambda n: doc.display.update(sequential_cmap=n))
        self.limit_mode.currentEnumChanged.connect(lambda m: doc.display.update(limit_mode=m))
        self._percentiles_edited = qdebounced(self._percentiles_edited, timeout=120)  # big meshes: not every tick
        self.percentiles.valueChanged.connect(self._percentiles_edited)
        self.lo_edit.editingFinished.connect(self._manual_edited)
        self.hi_edit.editingFinished.connect(self._manual_edited)
        self.lock.toggled.connect(lambda on: doc.display.update(lock_limits=on))
        self.shared.toggled.connect(lambda on: doc.display.update(shared_scale=on))
        self.histogram.limits_edited.connect(
            lambda lo, hi: doc.display.update(manual=(lo, hi), limit_mode=LimitMode.MANUAL))

        doc.display.changed.connect(lambda names: self.sync())
        doc.panes_changed.connect(self.sync)
        doc.pane_changed.connect(lambda i: self.sync())
        doc.mesh_changed.connect(lambda change: self.sync())
        self.sync()

    # -- widget -> model ------------------------------------------------------------------------
    def _set_pane(self, **changes) -> bool:
        """Apply ``changes`` to the active pane if :mod:`curv.ranges` accepts them; else say why."""
        doc = self.doc
        try:
            pane = Pane(**{**doc.panes[doc.active].__dict__, **changes}).validated()
        except EstimatorError as exc:
            self.message.emit(str(exc))
            self.sync()
            return False
        doc.set_pane(doc.active, method=pane.method, range=pane.range, radius=pane.radius)
        return True

    def _method_edited(self) -> None:
        method = self.method.currentData()
        spec = ESTIMATORS[method]
        pane = self.doc.panes[self.doc.active]
        k, radius = pane.range, pane.radius
        if not takes_support(spec):
            k, radius = spec.ranges[0], None
        elif k < min(spec.ranges):  # keep the range if the estimator takes it, else its smallest
            k = min(spec.ranges)
        self._set_pane(method=method, range=k, radius=radius)

    def _range_edited(self) -> None:
        text = self.range.currentText().strip()
        try:
            k = ranges.parse_range(text)
        except EstimatorError as exc:
            self.message.emit(str(exc))
            self.sync()
            return
        k = int(k) if float(k).is_integer() else k
        self._set_pane(range=k, radius=None)

    def _radius_toggled(self, on: bool) -> None:
        doc = self.doc
        if on:
            if doc.mesh is not None and self.radius.value() <= 1e-6 * 1.0001:
                self.radius.setValue(2.0 * float(doc.mesh.mean_edge_length))
            self._set_pane(radius=float(self.radius.value()))
        else:
            self._set_pane(radius=None)

    def _radius_edited(self, value: float) -> None:
        if self.use_radius.isChecked():
            self._set_pane(radius=float(value))

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
        letter = pane_letter(doc.active)
        colour = PANE_COLOURS[doc.active % len(PANE_COLOURS)]
        several = len(doc.panes) > 1
        self.pane_box.setTitle(f"Pane {letter}: estimator and range" + (" (click a pane to switch)" if several else ""))
        self.pane_box.setStyleSheet(
            f"#pane_box {{ border: 2px solid {colour if several else '#c8c8c8'}; border-radius: 4px; margin-top: 1.2em; }}"
            "#pane_box::title { subcontrol-origin: margin; left: 8px; padding: 0 3px; }")
        widgets = (self.method, self.range, self.use_radius, self.radius, self.quantity, self.layer,
                   self.directions, self.edges, self.borders, self.points, self.cmap_div, self.cmap_seq,
                   self.limit_mode, self.percentiles, self.shared, self.lock)
        with blocked(*widgets, self.range.lineEdit()):
            self.method.setCurrentIndex(self.method.findData(pane.method))
            spec = ESTIMATORS.get(pane.method)
            support = spec is not None and takes_support(spec)
            for i, k in enumerate(ranges.PAPER_RANGES):
                allowed = spec is not None and (k in spec.ranges or (support and k >= min(spec.ranges)))
                self.range.model().item(i).setEnabled(allowed)
            self.range.setEditText(ranges.range_label(pane.range))
            self.range.setEnabled(pane.radius is None)
            self.use_radius.setEnabled(support)
            self.use_radius.setChecked(pane.radius is not None)
            self.radius.setEnabled(pane.radius is not None)
            if pane.radius is not None:
                self.radius.setValue(pane.radius)
            self.quantity.setCurrentEnum(st.quantity)
            for i, layer in enumerate(Layer):
                self.layer.model().item(i).setEnabled(doc.has_truth or not layer.needs_truth)
            self.layer.setCurrentEnum(st.layer)
            self.directions.setChecked(st.show_directions)
            self.edges.setChecked(st.show_edges)
            self.borders.setChecked(st.show_borders)
            self.points.setChecked(st.show_points)
            self.cmap_div.setCurrentText(st.diverging_cmap)
            self.cmap_seq.setCurrentText(st.sequential_cmap)
            self.limit_mode.setCurrentEnum(st.limit_mode)
            self.percentiles.setValue(tuple(st.percentiles))
            self.percentiles.setEnabled(st.limit_mode is LimitMode.PERCENTILE)
            self.lock.setChecked(st.lock_limits)
            self.shared.setChecked(st.shared_scale)
            self.shared.setEnabled(several)

    def show_values(self, drawn, *, table, n_invalid: int | None, n_vertices: int) -> None:
        """Show the active view's field: histogram, limit fields, invalid count.

        Parameters
        ----------
        drawn : (values, clim, cmap) or None
            The active view's entry of :meth:`Document.fields`.
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
                edit.setText(format_limit(v))
        if n_invalid is not None:
            self.invalid.setText(f"Invalid vertices (magenta): {n_invalid} of {n_vertices} "
                                 f"({100.0 * n_invalid / max(n_vertices, 1):.1f} %)")
