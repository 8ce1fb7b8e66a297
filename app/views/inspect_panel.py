"""The inspect panel: the active pane's estimator, range and options (one group), the display settings every
pane shares (another group), and the histogram. Bound to the document: model events update the
widgets (signals blocked while syncing), widget edits call the model's setters."""

from __future__ import annotations

import contextlib

from curv.core import ranges
from curv.core.errors import EstimatorError
from curv.estimators import ESTIMATORS, refusal
from PySide6.QtCore import QEvent, QObject, Qt, Signal
from PySide6.QtGui import QDoubleValidator
from PySide6.QtWidgets import (
    QCheckBox, QComboBox, QFormLayout, QGridLayout, QGroupBox, QHBoxLayout, QLabel, QLineEdit,
    QPushButton, QSizePolicy, QSpinBox, QToolButton, QVBoxLayout, QWidget,
)
from superqt import QEnumComboBox, QLabeledDoubleRangeSlider
from superqt.utils import qdebounced

from app.model import Document, Layer, LimitMode, Pane, Quantity, colormap_names, format_limit, pane_letter
from app.model.inputs import DEFAULT_KNN, POINT_SIZES, items_word, unit_length

from .histogram import Histogram
from .option_controls import OptionControls
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


def estimator_tooltip(spec, refused: str | None = None) -> str:
    """Rich-text tooltip of an estimator from its registry entry; ``refused`` (why it cannot run on
    the mesh shown, :func:`curv.estimators.refusal`) comes first when given."""
    named = ", ".join(ranges.range_label(k) for k in spec.ranges)
    polys = "triangles only" if spec.triangles_only else "triangles and polygons"
    why = f"<b style='color:#b00020'>Not available: {refused}</b><br>" if refused else ""
    return (f"{why}<b>{spec.name}</b>: {spec.title}<br>{spec.reference}<br>ranges {named}: "
            f"{ranges.describe_ranges(spec)}<br>{polys}; "
            f"{'border vertices and those whose support reaches a border are invalid' if spec.closed_ring else 'fits near borders too'}")


RANGE_TIP = ("<b>Range Rk</b> (paper §4.1): the support of vertex p is every vertex connected to p within "
             "k × the longest edge of p's 1-ring; on a point cloud, every point within k × p's spacing. "
             "Pick a preset R1–R4 or type a real k such as 2.5.<br>"
             "<b>Radius</b>: the same ball of radius r (mesh units) at every vertex instead.<br>"
             "<b>Nearest</b> (point clouds): the K nearest points instead.")
POINT_SIZE_TIP = "Width of a point cloud's points in pixels (drawn as shaded spheres)"
LIMITS_TIP = ("<b>Percentile</b>: robust limits from the 2–98 % percentiles (adjustable); <b>Min / max</b>: the "
              "whole span; <b>Manual</b>: the values you type or drag on the histogram. Signed fields that "
              "straddle 0 get symmetric limits and a diverging map; fields of one sign a sequential map. "
              "Values beyond the limits are drawn in the map's end colours darkened.")


class _LetsRThrough(QObject):
    """Event filter for numeric fields: a plain R is not text there (a range is typed as 2.5; the R of
    ``R2`` is optional), so the key goes to the window's shortcut (reset camera) instead."""

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 (Qt API)
        if (event.type() == QEvent.Type.ShortcutOverride and event.key() == Qt.Key.Key_R
                and not event.modifiers() & ~Qt.KeyboardModifier.KeypadModifier):
            event.ignore()
            return True
        return False


class InspectPanel(QWidget):
    """Estimator, quantity and colour controls.

    Signals
    -------
    recompute_requested()
        Redo the active pane.
    pane_requested(Pane)
        The user chose this (validated) estimator and range for the active pane: show it and
        compute it unless its result is there (a cancelled or failed one is tried again).
    message(str)
        A one-line note for the status bar (e.g. a range the estimator does not take).
    """

    recompute_requested = Signal()
    pane_requested = Signal(object)
    message = Signal(str)

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.shown_limits: tuple[float, float] | None = None
        """The colour limits of the active view as last drawn (where Manual starts from)."""
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
        self.radius = QLineEdit()  # read by curv.core.ranges, which refuses bad input with a message
        self.radius.setPlaceholderText("—")
        self.radius.setToolTip("Ball radius in mesh units (the same at every vertex), a positive number")
        self.use_knn = QCheckBox("Nearest")
        self.use_knn.setToolTip(RANGE_TIP)
        self.knn = QSpinBox()  # what K may be is curv.core.ranges' rule: a refused K comes back with its message
        self.knn.setRange(1, 10_000)
        self.knn.setValue(DEFAULT_KNN)
        self.knn.setSuffix(" points")
        self.knn.setKeyboardTracking(False)
        self.knn.setToolTip("The support of each point is its K nearest points (point clouds only)")
        self.point_size = QSpinBox()
        self.point_size.setRange(*POINT_SIZES)
        self.point_size.setSuffix(" px")
        self.point_size.setToolTip(POINT_SIZE_TIP)
        self.options = OptionControls()
        self.recompute = QPushButton("Recompute")
        self.recompute.setToolTip("Compute the active pane again (F5)")
        self.advise_button = QToolButton()  # the window binds it to its Advise action
        self.advise_button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextOnly)
        self.quantity = QEnumComboBox(enum_class=Quantity)
        self.quantity.setToolTip("<br>".join(f"<b>{q.title}</b>: {q.spec.formula}" for q in Quantity))
        self.layer = QEnumComboBox(enum_class=Layer)
        self.directions = QCheckBox("Directions")
        self.directions.setToolTip("Principal directions: d1 (of k1) and d2 (of k2) as crosses; the pane header "
                                   "gives their colours")
        self.edges = QCheckBox("Edges")
        self.borders = QCheckBox("Borders and features")
        self.points = QCheckBox("Points")
        self.edges.setToolTip("Wireframe overlay of the mesh edges")
        self.borders.setToolTip("Border edges (one face) in red; feature edges (sharper than a pane's "
                                "feature angle) in black")
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
        # two lines of their own (what, then the count): a wrapping label in a scrolled form got one
        # line's height and spilled over the next row; it never widens the dock either
        self.invalid = QLabel()
        self.invalid.setObjectName("invalid_count")
        self.invalid.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Fixed)
        self.centre_note = QLabel()
        self.centre_note.setWordWrap(True)
        self.centre_note.setObjectName("centre_note")
        self.centre_note.setStyleSheet("color: #8a5a00;")
        self.centre_note.setVisible(False)

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
        knn_row = QHBoxLayout()
        knn_row.addWidget(self.use_knn)
        knn_row.addWidget(self.knn, 1)
        pane_form.addRow("", knn_row)
        self.pane_form = pane_form  # the window adds the Feature angle row under the range
        header_row = QHBoxLayout()  # the options' fold-out header beside Advise: no height while folded
        header_row.addWidget(self.options.header)
        header_row.addStretch(1)
        header_row.addWidget(self.advise_button)
        pane_form.addRow(header_row)
        pane_form.addRow(self.options)
        self.all_box = QGroupBox("All panes")
        form = QFormLayout(self.all_box)  # the histogram high up: it must show without scrolling
        form.addRow("Quantity", self.quantity)
        form.addRow("Show", self.layer)
        form.addRow("Limits", self.limit_mode)
        form.addRow("Percentiles", self.percentiles)
        lim = QHBoxLayout()
        lim.addWidget(self.lo_edit)
        lim.addWidget(self.hi_edit)
        form.addRow("Min / max", lim)
        form.addRow(self.histogram)
        form.addRow(self.centre_note)
        form.addRow(self.invalid)
        form.addRow("", self.lock)
        maps = QHBoxLayout()
        maps.addWidget(self.cmap_div)
        maps.addWidget(self.cmap_seq)
        form.addRow("Maps", maps)
        self.cmap_div.setToolTip("Diverging map: " + self.cmap_div.toolTip())
        self.cmap_seq.setToolTip("Sequential map: " + self.cmap_seq.toolTip())
        overlays = QGridLayout()  # two rows: "Borders and features" is long for a narrow dock
        for i, w in enumerate((self.directions, self.edges, self.borders, self.points)):
            overlays.addWidget(w, i // 2, i % 2)
        form.addRow(overlays)
        form.addRow("Point size", self.point_size)
        form.addRow(self.shared)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addWidget(self.pane_box)
        lay.addWidget(self.all_box)
        lay.addStretch(1)
        self._numbers_only = _LetsRThrough(self)
        for edit in [*self.findChildren(QLineEdit), self.range]:  # numeric fields: R stays the reset-camera key
            edit.installEventFilter(self._numbers_only)  # (the combo too: it hands the key to its edit directly)
        for combo in self.findChildren(QComboBox):  # narrow docks: combos shrink and elide, never clip the panel
            combo.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
            combo.setMinimumContentsLength(6)

        self.method.currentIndexChanged.connect(self._method_edited)
        self.method.activated.connect(lambda _i: self._method_edited())  # the same entry again: compute it
        self.range.activated.connect(lambda _i: self._range_edited())
        self.range.lineEdit().editingFinished.connect(self._range_edited)
        self.use_radius.toggled.connect(self._radius_toggled)
        self.radius.editingFinished.connect(self._radius_edited)
        self.use_knn.toggled.connect(self._knn_toggled)
        self.knn.valueChanged.connect(lambda _k: self._knn_edited())
        self.options.options_edited.connect(lambda options: self._set_pane(options=options))
        self.point_size.valueChanged.connect(lambda px: doc.display.update(point_size=float(px)))
        self.recompute.clicked.connect(self.recompute_requested)
        self.quantity.currentEnumChanged.connect(lambda q: doc.display.update(quantity=q))
        self.layer.currentEnumChanged.connect(self._layer_edited)
        self.directions.toggled.connect(lambda on: doc.display.update(show_directions=on))
        self.edges.toggled.connect(lambda on: doc.display.update(show_edges=on))
        self.borders.toggled.connect(lambda on: doc.display.update(show_borders=on))
        self.points.toggled.connect(lambda on: doc.display.update(show_points=on))
        self.cmap_div.currentTextChanged.connect(lambda n: doc.display.update(diverging_cmap=n))
        self.cmap_seq.currentTextChanged.connect(lambda n: doc.display.update(sequential_cmap=n))
        self.limit_mode.currentEnumChanged.connect(self._limit_mode_edited)
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
        """Ask for ``changes`` in the active pane if the estimator can run on the mesh and
        :mod:`curv.core.ranges` accepts them; else say why in red and start nothing."""
        doc = self.doc
        try:
            pane = Pane(**{**doc.panes[doc.active].__dict__, **changes}).validated()
        except EstimatorError as exc:
            self._refuse(str(exc))
            return False
        refused = None if doc.mesh is None else refusal(ESTIMATORS[pane.method], doc.mesh)
        if refused:
            self._refuse(refused)
            return False
        self.pane_requested.emit(pane)
        return True

    def _refuse(self, text: str) -> None:
        self.message.emit(text)
        self.sync()

    def _method_edited(self) -> None:
        spec = ESTIMATORS[self.method.currentData()]
        pane = self.doc.panes[self.doc.active]
        radius = pane.radius if ranges.takes_any_range(spec) else None
        knn = pane.knn if ranges.takes_any_range(spec) else None
        self._set_pane(method=spec.name, range=ranges.nearest_allowed(spec, pane.range), radius=radius, knn=knn,
                       options=())  # another estimator starts from its defaults

    def _range_edited(self) -> None:
        try:
            k = ranges.canonical_k(ranges.parse_range(self.range.currentText()))
        except EstimatorError as exc:
            self._refuse(str(exc))
            return
        self._set_pane(range=k, radius=None, knn=None)

    def _radius_toggled(self, on: bool) -> None:
        doc = self.doc
        if on:
            if doc.mesh is not None and not self.radius.text().strip():
                self.radius.setText(f"{2.0 * unit_length(doc.mesh):.6g}")
            self._radius_edited()
        else:
            self._set_pane(radius=None)

    def _knn_toggled(self, on: bool) -> None:
        if on:
            self._knn_edited()
        else:
            self._set_pane(knn=None)

    def _knn_edited(self) -> None:
        if self.use_knn.isChecked():
            self._set_pane(knn=int(self.knn.value()), radius=None)

    def _radius_edited(self) -> None:
        if self.use_radius.isChecked():
            spec = ESTIMATORS[self.doc.panes[self.doc.active].method]
            try:  # curv.core.ranges owns what a radius may be: anything else is refused with its message
                radius = ranges.resolve(spec, radius=self.radius.text().strip()).radius
            except EstimatorError as exc:
                self._refuse(str(exc))
                return
            self._set_pane(radius=radius, knn=None)

    def _layer_edited(self, layer: Layer) -> None:
        if layer.needs_truth and not self.doc.has_truth:
            self.sync()  # refuse: no truth for a file mesh
            return
        self.doc.display.update(layer=layer)

    def _percentiles_edited(self, value) -> None:
        self.doc.display.update(percentiles=(float(value[0]), float(value[1])), limit_mode=LimitMode.PERCENTILE)

    def _limit_mode_edited(self, mode: LimitMode) -> None:
        """Manual limits start from the limits on screen, not from the last manual ones."""
        if mode is LimitMode.MANUAL and self.shown_limits is not None:
            self.doc.display.update(manual=self.shown_limits, limit_mode=mode)
        else:
            self.doc.display.update(limit_mode=mode)

    def _manual_edited(self) -> None:
        try:
            lo, hi = float(self.lo_edit.text()), float(self.hi_edit.text())
        except ValueError:
            return
        if not lo < hi:
            self.message.emit(f"Colour limits need min < max; got min {format_limit(lo)}, max {format_limit(hi)}")
            self._show_limits(self.shown_limits)
            return
        self.doc.display.update(manual=(lo, hi), limit_mode=LimitMode.MANUAL)

    # -- model -> widget ------------------------------------------------------------------------
    def sync(self) -> None:
        """Show the document's state in every control without feeding edits back."""
        doc, st = self.doc, self.doc.display.state
        pane = doc.panes[doc.active]
        letter = pane_letter(doc.active)
        colour = PANE_COLOURS[doc.active % len(PANE_COLOURS)]
        several = len(doc.panes) > 1
        self.pane_box.setTitle(f"Pane {letter} (click a pane to switch)" if several else f"Pane {letter}: estimator, range, options")
        self.pane_box.setStyleSheet(
            f"#pane_box {{ border: 2px solid {colour if several else '#c8c8c8'}; border-radius: 4px; margin-top: 1.2em; }}"
            "#pane_box::title { subcontrol-origin: margin; left: 8px; padding: 0 3px; }")
        widgets = (self.method, self.range, self.use_radius, self.radius, self.use_knn, self.knn, self.point_size,
                   self.quantity, self.layer,
                   self.directions, self.edges, self.borders, self.points, self.cmap_div, self.cmap_seq,
                   self.limit_mode, self.percentiles, self.shared, self.lock)
        with blocked(*widgets, self.range.lineEdit()):
            self._sync_estimators()
            self.method.setCurrentIndex(self.method.findData(pane.method))
            spec = ESTIMATORS[pane.method]
            allowed = ranges.allowed_paper_ranges(spec)
            for i, k in enumerate(ranges.PAPER_RANGES):
                self.range.model().item(i).setEnabled(k in allowed)
            self.range.setEditText(ranges.range_label(pane.range))
            self.range.setEnabled(pane.radius is None and pane.knn is None)
            self.use_radius.setEnabled(ranges.takes_any_range(spec))
            self.use_radius.setChecked(pane.radius is not None)
            self.radius.setEnabled(pane.radius is not None)
            if pane.radius is not None:
                self.radius.setText(f"{pane.radius:g}")
            points = doc.is_points
            self.use_knn.setEnabled(points and ranges.takes_any_range(spec))
            self.use_knn.setChecked(pane.knn is not None)
            self.knn.setEnabled(pane.knn is not None)
            if pane.knn is not None:
                self.knn.setValue(pane.knn)
            self.options.show_pane(pane, points=points)
            self.point_size.setValue(int(round(st.point_size)))
            self.point_size.setEnabled(points)
            self.edges.setEnabled(not points)  # a cloud has no edges and is drawn as points
            self.points.setEnabled(not points)
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

    def _sync_estimators(self) -> None:
        """Grey out the estimators that cannot run on the mesh shown, with the reason as tooltip."""
        mesh = self.doc.mesh
        for i, spec in enumerate(ESTIMATORS.values()):
            refused = None if mesh is None else refusal(spec, mesh)
            self.method.model().item(i).setEnabled(refused is None)
            self.method.setItemData(i, estimator_tooltip(spec, refused), Qt.ItemDataRole.ToolTipRole)

    def _show_limits(self, clim) -> None:
        """The limits on screen in the min / max fields (a field being typed in is left alone)."""
        if clim is None:
            return
        for edit, v in zip((self.lo_edit, self.hi_edit), clim):
            if not edit.hasFocus():
                edit.setText(format_limit(v))

    def _show_centre_note(self, clim, cmap_kind: str) -> None:
        """Say where the diverging map's middle colour sits when manual limits are not centred on 0."""
        lo, hi = clim
        middle = 0.5 * (lo + hi)
        off = (self.doc.display.limit_mode is LimitMode.MANUAL and cmap_kind == "diverging"
               and abs(middle) > 1e-3 * (hi - lo))
        self.centre_note.setText(
            f"Manual limits not centred on 0: the diverging map's middle colour is at {format_limit(middle)}, "
            f"not 0 (type -x and x to centre it)." if off else "")
        self.centre_note.setVisible(off)

    def show_values(self, drawn, *, table, histogram, n_invalid: int | None, n_vertices: int) -> None:
        """Show the active view's field: histogram, limit fields, invalid count.

        Parameters
        ----------
        drawn : (clim, cmap) or None
            The active view's colour limits and map (None: nothing drawn yet).
        table : (k, 3) uint8
            Its colour table.
        histogram : (counts, edges, n_nan) or None
            :func:`app.model.picture.histogram_counts` of its values, computed with the picture.
        """
        if drawn is None:
            self.histogram.set_counts(None, (0.0, 1.0), table)
            self.invalid.setText("")
            self.invalid.setToolTip("")
            self.centre_note.setVisible(False)
            return
        clim, cmap = drawn
        self.shown_limits = (float(clim[0]), float(clim[1]))
        self.histogram.set_counts(histogram, clim, table)
        self._show_limits(clim)
        self._show_centre_note(clim, cmap.kind)
        if n_invalid is not None:
            word = "vertices" if self.doc.mesh is None else items_word(self.doc.mesh)
            count = f"{n_invalid} of {n_vertices} ({100.0 * n_invalid / max(n_vertices, 1):.1f} %)"
            self.invalid.setText(f"Invalid {word} (magenta):\n{count}")
            self.invalid.setToolTip(f"Invalid {word} (magenta): {count}")
