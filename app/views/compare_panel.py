"""Compare controls: number of panes, the difference pane, camera linking."""

from __future__ import annotations

from PySide6.QtCore import Signal
from PySide6.QtWidgets import QCheckBox, QFormLayout, QSpinBox, QWidget

from app.model import Document
from app.model.document import MAX_PANES

from .inspect_panel import blocked

__all__ = ["ComparePanel"]


class ComparePanel(QWidget):
    """Bound to the document's panes; ``link_toggled`` switches camera linking in the views."""

    link_toggled = Signal(bool)

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.count = QSpinBox()
        self.count.setRange(1, MAX_PANES)
        self.difference = QCheckBox("Difference pane (A − B)")
        self.link = QCheckBox("Link cameras")
        self.link.setChecked(True)
        form = QFormLayout(self)
        form.addRow("Panes", self.count)
        form.addRow(self.difference)
        form.addRow(self.link)
        self.count.valueChanged.connect(doc.set_pane_count)
        self.difference.toggled.connect(doc.set_difference)
        self.link.toggled.connect(self.link_toggled)
        doc.panes_changed.connect(self.sync)
        self.sync()

    def sync(self) -> None:
        with blocked(self.count, self.difference):
            self.count.setValue(len(self.doc.panes))
            self.difference.setChecked(self.doc.difference)
            self.difference.setEnabled(len(self.doc.panes) >= 2)
