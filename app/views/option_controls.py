"""The Options rows of the active pane: one combo per option its estimator declares, and on a mesh
where the normals come from (:mod:`app.model.options` says what the rows are). A header button
names the options and folds the rows away (folded by default, so the histogram below stays in view
on small screens)."""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import QComboBox, QFormLayout, QLabel, QToolButton, QWidget

from app.model import Pane
from app.model.options import OptionRow, option_rows, options_with

__all__ = ["OptionControls"]


class OptionControls(QWidget):
    """The combos of the active pane's options (this widget), rebuilt when the estimator or the kind
    of input changes, and :attr:`header`, a fold-out button reading ``Options: defaults`` or
    ``Options: degree 4`` that the panel places where it likes; both hidden when there is nothing
    to choose.

    Signals
    -------
    options_edited(tuple)
        The pane's options with the edited row's new value (defaults left out, sorted by name).
    """

    options_edited = Signal(tuple)

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.rows: list[OptionRow] = []
        self.combos: dict[str, QComboBox] = {}
        self._shown: tuple | None = None  # (method, points) the combos were built for
        self._options: tuple = ()
        self.header = QToolButton()
        self.header.setCheckable(True)
        self.header.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
        self.header.setAutoRaise(True)
        self.header.setToolTip("Show or hide the options of the active pane's estimator")
        self.form = QFormLayout(self)
        self.form.setContentsMargins(0, 0, 0, 0)
        self.header.toggled.connect(lambda on: self._fold())
        self._fold()

    def _fold(self) -> None:
        unfolded = self.header.isChecked()
        self.header.setArrowType(Qt.ArrowType.DownArrow if unfolded else Qt.ArrowType.RightArrow)
        self.setVisible(unfolded and bool(self.rows))

    def show_pane(self, pane: Pane, *, points: bool) -> None:
        """Show ``pane``'s options; rebuild the rows first if its estimator or the input kind changed."""
        if self._shown != (pane.method, points):
            self._build(option_rows(pane.method, points=points))
            self._shown = (pane.method, points)
        self._options = pane.options
        self.header.setText(f"Options: {pane.options_label or 'defaults'}")
        for row in self.rows:
            combo, value = self.combos[row.name], row.current(pane.options)
            combo.blockSignals(True)
            if value not in row.choices and combo.findText(row.text_of(value)) < 0:
                combo.addItem(row.text_of(value), value)  # offered from now on for this estimator
            combo.setCurrentIndex(combo.findText(row.text_of(value)))
            combo.blockSignals(False)

    def _build(self, rows: list[OptionRow]) -> None:
        while self.form.rowCount():
            self.form.removeRow(0)
        self.rows, self.combos = rows, {}
        for row in rows:
            combo = QComboBox()
            for value, text in zip(row.choices, row.texts):
                combo.addItem(text, value)
            combo.setToolTip(row.tooltip)
            combo.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
            combo.setMinimumContentsLength(6)
            combo.activated.connect(lambda i, r=row, c=combo: self._edited(r, c.itemData(i)))
            label = QLabel(row.label)
            label.setToolTip(row.tooltip)
            label.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
            self.form.addRow(label, combo)
            self.combos[row.name] = combo
        self.header.setVisible(bool(rows))
        self._fold()

    def _edited(self, row: OptionRow, value) -> None:
        new = options_with(self._options, row, value)
        if new != self._options:
            self.options_edited.emit(new)
