"""The picked vertex's marker drawn by Qt over a pane, for inputs whose every VTK frame is expensive:
moving it costs a repaint of a few pixels, not a frame of millions of points."""

from __future__ import annotations

from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QColor, QPainter, QPen
from PySide6.QtWidgets import QWidget

__all__ = ["MarkerOverlay"]


class MarkerOverlay(QWidget):
    """A transparent child of a 3D view that draws one filled circle, ``diameter`` pixels wide, at a
    position in the view's pixels; clicks go through it to the view."""

    def __init__(self, parent: QWidget) -> None:
        super().__init__(parent)
        self.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self.setAttribute(Qt.WidgetAttribute.WA_NoSystemBackground)
        self.setAttribute(Qt.WidgetAttribute.WA_TranslucentBackground)
        self.centre: QPointF | None = None
        self.diameter = 16.0
        self.colour = QColor(255, 208, 0)
        self.hide()

    def place(self, x: float | None, y: float | None, *, diameter: float, colour) -> None:
        """Draw the marker centred at (x, y) (the parent's pixels), or hide it (None, or outside)."""
        self.setGeometry(self.parentWidget().rect())
        inside = x is not None and 0 <= x <= self.width() and 0 <= y <= self.height()
        self.centre = QPointF(x, y) if inside else None
        self.diameter, self.colour = float(diameter), QColor(*colour)
        self.setVisible(inside)
        self.update()

    def paintEvent(self, event) -> None:  # noqa: N802 (Qt API)
        if self.centre is None:
            return
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.setPen(QPen(QColor(20, 20, 20), 1.5))
        p.setBrush(self.colour)
        r = 0.5 * self.diameter
        p.drawEllipse(QRectF(self.centre.x() - r, self.centre.y() - r, 2 * r, 2 * r))
        p.end()
