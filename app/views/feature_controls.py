"""The Feature angle control of the active pane: off, or an angle in degrees (``estimate(..., features=)``)."""

from __future__ import annotations

from dataclasses import replace

from PySide6.QtCore import Signal
from PySide6.QtWidgets import QCheckBox, QDoubleSpinBox, QHBoxLayout, QWidget

from app.model import Document
from app.model.features import DEFAULT_FEATURE_ANGLE, FEATURE_TIP

from .inspect_panel import blocked

__all__ = ["FeatureControl"]


class FeatureControl(QWidget):
    """A check box (off by default) and an angle for the active pane's feature edges.

    Switching it or changing the angle sets the active pane's ``features`` (a new result key) and so
    computes that estimate unless it is known; a failure or cancel of the same setting is retried.

    Signals
    -------
    angle_changed(float)
        The angle offered while off changed (for the persisted settings).
    """

    angle_changed = Signal(float)

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.enabled = QCheckBox("Feature angle")
        self.angle = QDoubleSpinBox()
        self.angle.setRange(0.0, 180.0)
        self.angle.setDecimals(1)
        self.angle.setSingleStep(5.0)
        self.angle.setSuffix("°")
        self.angle.setValue(DEFAULT_FEATURE_ANGLE)
        self.angle.setKeyboardTracking(False)  # one estimate per typed angle, not per digit
        for w in (self, self.enabled, self.angle):
            w.setToolTip(FEATURE_TIP)
        lay = QHBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.enabled)
        lay.addWidget(self.angle, 1)
        self.enabled.toggled.connect(lambda _on: self._edited())
        self.angle.valueChanged.connect(self._angle_edited)
        doc.panes_changed.connect(self.sync)
        doc.pane_changed.connect(lambda i: self.sync())
        doc.mesh_changed.connect(lambda change: self.sync())
        self.sync()

    def set_offered_angle(self, angle: float) -> None:
        """The angle shown while the control is off (e.g. the one persisted from the last session)."""
        if not self.enabled.isChecked():
            self.angle.setValue(float(angle))

    def _angle_edited(self, value: float) -> None:
        self.angle_changed.emit(float(value))
        if self.enabled.isChecked():
            self._edited()

    def _edited(self) -> None:
        doc = self.doc
        features = float(self.angle.value()) if self.enabled.isChecked() else None
        pane = doc.panes[doc.active]
        if pane.features == features:
            return
        doc.retry(replace(pane, features=features).key)
        doc.set_pane(doc.active, features=features)

    def sync(self) -> None:
        """Show the active pane's feature angle without feeding it back."""
        features = self.doc.panes[self.doc.active].features
        self.setEnabled(not self.doc.is_points)  # creases are between faces: a point cloud has none
        with blocked(self.enabled, self.angle):
            self.enabled.setChecked(features is not None)
            if features is not None:
                self.angle.setValue(features)
