"""The synthetic-surface panel: surface, its parameters (or random with a seed), density,
irregularity and noise. Edits are applied after a short pause (debounced)."""

from __future__ import annotations

from curv.surfaces import SURFACES, MongePatch
from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QIntValidator
from PySide6.QtWidgets import (
    QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QGroupBox, QHBoxLayout, QLabel, QPushButton,
    QSpinBox, QVBoxLayout, QWidget,
)
from superqt import QLabeledDoubleSlider
from superqt.utils import qdebounced

from app.model.inputs import can_sample_points, samplings
from app.model.sources import HEXAGON_SIZES, FileSource, SurfaceSource, snap_hexagon_count

__all__ = ["SourcePanel"]

CLOSED_SIZES = (642, 2562, 10242, 40962)
"""Resolutions offered for closed surfaces (icosphere-like counts)."""

POINT_COUNTS = (1000, 3169, 10000, 40000, 200000)
"""Point counts offered when a surface is sampled as points (any count is allowed)."""

MESH = "mesh"
"""The Sample control's first entry: mesh the surface (the other entries sample it as points)."""


class SourcePanel(QWidget):
    """Edits a :class:`SurfaceSource`; emits ``source_requested`` with the new one."""

    source_requested = Signal(object)
    open_requested = Signal()

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.surfaces = SURFACES
        self.showing = QLabel()
        self.showing.setWordWrap(True)
        self.showing.setTextFormat(Qt.TextFormat.RichText)
        self.surface = QComboBox()
        for name, cls in self.surfaces.items():
            self.surface.addItem(getattr(cls, "title", name), name)
        self.params_box = QWidget()
        self.params_form = QFormLayout(self.params_box)
        self.params_form.setContentsMargins(0, 0, 0, 0)
        self.param_spins: dict[str, QDoubleSpinBox] = {}
        self.sampling = QComboBox()
        self.sampling.addItem("Mesh (triangles)", MESH)
        for name, words in samplings().items():
            self.sampling.addItem(f"Points: {words}", name)
        self.sampling.setToolTip("Mesh the surface, or sample it as a point cloud (uniform random, blue noise, "
                                 "or rows like a scanner's); the exact curvature comes with either")
        self.random = QCheckBox("Random parameters, seed")
        self.seed = QSpinBox()
        self.seed.setRange(0, 2**31 - 1)
        self.density = QComboBox()
        self.density.setEditable(True)
        self.density.setValidator(QIntValidator(20, 5_000_000, self))
        self.irregularity = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
        self.irregularity.setRange(0.0, 25.0)
        self.irregularity.setDecimals(1)
        self.irregularity.setSingleStep(1.0)  # arrow keys: 1 degree; page keys: 5
        self.irregularity.setPageStep(5.0)
        self.noise = QDoubleSpinBox()
        self.noise.setRange(0.0, 1.0)
        self.noise.setSingleStep(0.01)
        self.noise.setDecimals(3)
        self.noise.setSuffix(" × edge")
        self.generate = QPushButton("Generate")
        self.open_file = QPushButton("Open file…")

        self.density.setToolTip("Hexagon patches take 3 s (s + 1) + 1 vertices (217, 817, 3169, 12481); "
                                "a typed count snaps to the nearest one")
        self.group = QGroupBox("Synthetic surface")
        form = QFormLayout(self.group)
        form.addRow("Surface", self.surface)
        form.addRow(self.params_box)
        seed_row = QHBoxLayout()
        seed_row.addWidget(self.random)
        seed_row.addWidget(self.seed)
        form.addRow(seed_row)
        form.addRow("Sample", self.sampling)
        form.addRow("Vertices", self.density)
        self.density_label = form.labelForField(self.density)
        form.addRow("Irregularity °", self.irregularity)
        form.addRow("Noise", self.noise)
        lay = QVBoxLayout(self)
        lay.addWidget(self.showing)
        lay.addWidget(self.group)
        buttons = QHBoxLayout()
        buttons.addWidget(self.generate)
        buttons.addWidget(self.open_file)
        lay.addLayout(buttons)
        lay.addStretch(1)
        for combo in self.findChildren(QComboBox):
            combo.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
            combo.setMinimumContentsLength(6)

        self._syncing = False
        self._debounced = qdebounced(self._emit, timeout=400)
        self.surface.currentIndexChanged.connect(self._surface_changed)
        self.random.toggled.connect(self._random_toggled)
        self.sampling.currentIndexChanged.connect(self._sampling_changed)
        for sig in (self.seed.valueChanged, self.density.currentTextChanged,
                    self.irregularity.valueChanged, self.noise.valueChanged):
            sig.connect(self._apply_later)
        self.generate.clicked.connect(self._emit)
        self.open_file.clicked.connect(self.open_requested)
        self._build_params(self.surface.currentData())

    # -- model <-> widgets ----------------------------------------------------------------------
    def current_source(self) -> SurfaceSource:
        """The surface described by the widgets."""
        name = self.surface.currentData()
        params = {} if self.random.isChecked() else {k: s.value() for k, s in self.param_spins.items()}
        text = self.density.currentText().strip()
        n = int(text) if text.isdigit() else self._sizes(name)[1]
        sampling = self.sampling.currentData()
        sampling = None if sampling == MESH else sampling
        if sampling is None and issubclass(self.surfaces[name], MongePatch) and n != snap_hexagon_count(n):
            n = snap_hexagon_count(n)  # the hexagon takes only 3 s (s + 1) + 1 vertices: snap, say so
            self._syncing, was = True, self._syncing
            self.density.setEditText(str(n))
            self._syncing = was
        return SurfaceSource(name=name, params=params, n_vertices=n,
                             irregularity=float(self.irregularity.value()), noise=float(self.noise.value()),
                             seed=int(self.seed.value()), random_params=self.random.isChecked(), sampling=sampling)

    def show_current(self, source) -> None:
        """Say what the window shows: a file (the surface controls then only generate a new one) or a surface."""
        if isinstance(source, FileSource):
            self.showing.setText(f"Showing file <b>{source.label}</b>")
            self.group.setTitle("Synthetic surface (Generate replaces the file)")
        elif source is not None:
            self.showing.setText(f"Showing surface <b>{source.label}</b>")
            self.group.setTitle("Synthetic surface")

    def set_source(self, source: SurfaceSource) -> None:
        """Show ``source`` in the widgets without emitting anything."""
        self._syncing = True
        try:
            self.surface.setCurrentIndex(max(self.surface.findData(source.name), 0))
            self.sampling.setCurrentIndex(max(self.sampling.findData(source.sampling or MESH), 0))
            self._build_params(source.name)
            for k, v in source.params.items():
                if k in self.param_spins:
                    self.param_spins[k].setValue(float(v))
            self.random.setChecked(source.random_params)
            self.params_box.setEnabled(not source.random_params)
            self.seed.setValue(int(source.seed or 0))
            self.density.setEditText(str(source.n_vertices))
            self.irregularity.setValue(source.irregularity)
            self.noise.setValue(source.noise)
        finally:
            self._syncing = False

    def _sizes(self, name: str) -> tuple[int, ...]:
        if self.sampling.currentData() != MESH:
            return POINT_COUNTS
        return CLOSED_SIZES if getattr(self.surfaces[name], "closed", False) else HEXAGON_SIZES

    def _show_sampling(self) -> None:
        """Words and controls of a mesh or of points: irregularity is a mesh's, noise in spacings on points."""
        points = self.sampling.currentData() != MESH
        self.density_label.setText("Points" if points else "Vertices")
        self.noise.setSuffix(" × spacing" if points else " × edge")
        closed = getattr(self.surfaces[self.surface.currentData()], "closed", False)
        self.irregularity.setEnabled(not closed and not points)
        self.density.setToolTip("Any number of points" if points else
                                "Hexagon patches take 3 s (s + 1) + 1 vertices (217, 817, 3169, 12481); "
                                "a typed count snaps to the nearest one")

    def _sampling_changed(self) -> None:
        if self._syncing:
            return
        self._fill_sizes(self.surface.currentData())
        self._show_sampling()
        self._emit()

    def _fill_sizes(self, name: str) -> None:
        self.density.blockSignals(True)
        self.density.clear()
        sizes = self._sizes(name)
        self.density.addItems([str(s) for s in sizes])
        self.density.setCurrentIndex(min(2, len(sizes) - 1))
        self.density.blockSignals(False)

    def _build_params(self, name: str) -> None:
        while self.params_form.rowCount():
            self.params_form.removeRow(0)
        self.param_spins = {}
        for p in getattr(self.surfaces[name], "params", ()):
            spin = QDoubleSpinBox()
            span = max(abs(p.low), abs(p.high), 1e-3)
            spin.setRange(min(p.low, -10 * span), max(p.high, 10 * span))
            spin.setDecimals(3)
            spin.setSingleStep(span / 20)
            spin.setValue(p.default)
            spin.setToolTip(p.doc)
            spin.valueChanged.connect(self._apply_later)
            self.params_form.addRow(p.name, spin)
            self.param_spins[p.name] = spin
        self.params_box.setEnabled(not self.random.isChecked())
        points_ok = can_sample_points(self.surfaces[name])
        for i in range(1, self.sampling.count()):  # the creased solids cannot be sampled as points
            self.sampling.model().item(i).setEnabled(points_ok)
        if not points_ok and self.sampling.currentData() != MESH:
            self.sampling.blockSignals(True)
            self.sampling.setCurrentIndex(0)
            self.sampling.blockSignals(False)
        self._fill_sizes(name)
        self._show_sampling()
        can_random = issubclass(self.surfaces[name], MongePatch)
        if not can_random:
            self.random.setChecked(False)
        self.random.setEnabled(can_random)

    def _apply_later(self, *args) -> None:
        """A field changed: apply after a short pause, unless the change came from :meth:`set_source`."""
        if not self._syncing:
            self._debounced()

    def _surface_changed(self) -> None:
        if self._syncing:
            return
        self._build_params(self.surface.currentData())
        self._emit()

    def _random_toggled(self, on: bool) -> None:
        self.params_box.setEnabled(not on)
        self._apply_later()

    def _emit(self) -> None:
        self._debounced.cancel()
        self.source_requested.emit(self.current_source())
