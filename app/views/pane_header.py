"""A pane's header: the estimator and its setting, elided with "…" when the pane is narrow, and beside
it, always whole, the field the colours show, the direction legend and the status."""

from __future__ import annotations

from html import escape

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QFrame, QHBoxLayout, QLabel, QSizePolicy

__all__ = ["PaneHeader", "STATUS_CHARS"]

STATUS_CHARS = 48
"""A status longer than this is cut in the header (the tooltip and the status bar have it whole)."""


class _Title(QLabel):
    """The estimator part: its full form (with the estimator's long name) where the label has room, else
    the short form elided to the label's width (the label never asks for room: it takes what is left)."""

    def __init__(self, parent) -> None:
        super().__init__(parent)
        self.setTextFormat(Qt.TextFormat.PlainText)
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        self.setMinimumWidth(0)
        self._forms = ("", "")

    def set_forms(self, full: str, short: str) -> None:
        self._forms = (full, short)
        # never wider than its full text: the header centres what it shows, the rest beside it
        self.setMaximumWidth(self.fontMetrics().horizontalAdvance(full) + 2 + self.contentsMargins().left()
                             + self.contentsMargins().right())
        self._fit()

    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt API)
        super().resizeEvent(event)
        self._fit()

    def _fit(self) -> None:
        full, short = self._forms
        room = self.contentsRect().width()
        metrics = self.fontMetrics()
        self.setText(full if metrics.horizontalAdvance(full) <= room
                     else metrics.elidedText(short, Qt.TextElideMode.ElideRight, max(room, 0)))


class PaneHeader(QFrame):
    """The header above pane ``index`` (its background in the pane's colour while active)."""

    def __init__(self, index: int, parent=None) -> None:
        super().__init__(parent)
        self.index = index
        self.setObjectName(f"header{index}")
        self.title = _Title(self)
        self.rest = QLabel(self)
        self.rest.setTextFormat(Qt.TextFormat.RichText)
        self.rest.setSizePolicy(QSizePolicy.Policy.Maximum, QSizePolicy.Policy.Preferred)
        lay = QHBoxLayout(self)
        lay.setContentsMargins(2, 1, 2, 1)
        lay.setSpacing(0)
        lay.addStretch(1)
        lay.addWidget(self.title, 100)  # it takes the room first (to its full text's width), eliding below it
        lay.addWidget(self.rest, 0)
        lay.addStretch(1)

    def show_parts(self, text: str, *, detail: str = "", field: str = "", legend: str = "", status: str = "") -> None:
        """``text`` (``A: mru R2 ...``) with ``detail`` (the estimator's long name) where it fits, then the
        ``field`` name, the glyph ``legend`` (rich text) and the ``status`` in red; all of it whole in
        the tooltip."""
        cut = status if len(status) <= STATUS_CHARS else status[:STATUS_CHARS - 1] + "…"
        shown_field = f" &nbsp;·&nbsp; <b>{escape(field)}</b>" if field else ""
        shown_status = f" &nbsp;<span style='color:#b00020'>{escape(cut)}</span>" if status else ""
        self.rest.setText(f"{shown_field}{legend}{shown_status}")
        self.title.set_forms(f"{text} — {detail}" if detail else text, text)
        tip = " — ".join(x for x in (text, detail) if x) + (f" · {field}" if field else "") \
            + (f"\n{status}" if status else "")
        for widget in (self, self.title, self.rest):
            widget.setToolTip(tip)

    def set_active(self, colour: str | None) -> None:
        """Fill the header with ``colour`` (white text), or leave it clear (None)."""
        self.setStyleSheet(f"#header{self.index} {{ background: {colour or 'transparent'}; }}")
        for label in (self.title, self.rest):
            label.setStyleSheet(f"color: {'white' if colour else 'black'}; background: transparent;")

    def html(self) -> str:
        """What the header shows: the estimator part (plain, perhaps elided), then the rich-text rest."""
        return self.title.text() + self.rest.text()
