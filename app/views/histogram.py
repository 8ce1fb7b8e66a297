"""Histogram of the shown values, bars in the colour map, with colour limits draggable on it."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QPainter, QPen
from PySide6.QtWidgets import QSizePolicy, QWidget

from app.model.colors import format_limit
from app.model.picture import histogram_counts

__all__ = ["Histogram"]

_MARGIN = 8
_LABEL_H = 16


class Histogram(QWidget):
    """Draws a histogram and two limit lines; dragging a line emits ``limits_edited(lo, hi)``."""

    limits_edited = Signal(float, float)

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.setMinimumHeight(130)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.setMouseTracking(True)
        self.counts = np.zeros(0, int)
        self.edges = np.array([0.0, 1.0])
        self.clim = (0.0, 1.0)
        self.table = np.zeros((1, 3), np.uint8)
        self.n_nan = 0
        self._drag: int | None = None

    def set_data(self, values: np.ndarray | None, clim, table: np.ndarray) -> None:
        """Show ``values`` binned, the limits ``clim`` and bars coloured with ``table`` (k, 3) uint8."""
        self.set_counts(None if values is None else histogram_counts(values, clim), clim, table)

    def set_counts(self, histogram, clim, table: np.ndarray) -> None:
        """Show ``histogram`` (``(counts, edges, n_nan)`` of :func:`app.model.picture.histogram_counts`,
        or None), the limits ``clim`` and bars coloured with ``table`` (k, 3) uint8."""
        if histogram is None:
            self.counts, self.n_nan = np.zeros(0, int), 0
        else:
            self.counts, self.edges, self.n_nan = histogram
        self.clim, self.table = (float(clim[0]), float(clim[1])), table
        self.update()

    # -- coordinates ----------------------------------------------------------------------------
    def _plot_rect(self) -> QRectF:
        """The bars' area: a text row above it (invalid count) and one below (the limits)."""
        top = _MARGIN + _LABEL_H
        return QRectF(_MARGIN, top, self.width() - 2 * _MARGIN, self.height() - top - _MARGIN - _LABEL_H)

    def x_of(self, value: float) -> float:
        """Widget x of a data value."""
        r = self._plot_rect()
        lo, hi = self.edges[0], self.edges[-1]
        return r.left() + (value - lo) / (hi - lo) * r.width()

    def value_of(self, x: float) -> float:
        r = self._plot_rect()
        lo, hi = self.edges[0], self.edges[-1]
        return lo + (x - r.left()) / r.width() * (hi - lo)

    # -- painting -------------------------------------------------------------------------------
    def paintEvent(self, event) -> None:  # noqa: N802 (Qt API)
        p = QPainter(self)
        p.fillRect(self.rect(), QColor("white"))
        r = self._plot_rect()
        p.setPen(QPen(QColor("#999999")))
        p.drawRect(r)
        if self.counts.size == 0 or self.counts.max() == 0:
            p.drawText(r, Qt.AlignmentFlag.AlignCenter, "no values")
            return
        top = float(self.counts.max())
        lo, hi = self.clim
        n_col = self.table.shape[0]
        p.setPen(Qt.PenStyle.NoPen)
        from curv.colors import CLIP_MARGIN, CLIP_SHADE

        for c, a, b in zip(self.counts, self.edges[:-1], self.edges[1:]):
            t = ((a + b) / 2 - lo) / (hi - lo)
            rgb = self.table[int(round(np.clip(t, 0, 1) * (n_col - 1)))]
            if t < -CLIP_MARGIN or t > 1 + CLIP_MARGIN:  # clipped on the mesh: drawn darkened there too
                rgb = (rgb * CLIP_SHADE).astype(np.uint8)
            p.setBrush(QColor(int(rgb[0]), int(rgb[1]), int(rgb[2])))
            x0, x1 = self.x_of(a), self.x_of(b)
            h = r.height() * (np.sqrt(c / top) if c else 0.0)  # sqrt: keeps tails visible
            p.drawRect(QRectF(x0, r.bottom() - h, max(x1 - x0 - 0.5, 0.5), h))
        p.setPen(QPen(QColor("#202020"), 2))
        for v in self.clim:
            x = self.x_of(v)
            p.drawLine(QPointF(x, r.top()), QPointF(x, r.bottom()))
        p.setPen(QPen(QColor("#202020")))
        width = 70.0  # each limit's label sits beside its line (outside the span if it fits)
        left_align, right_align = Qt.AlignmentFlag.AlignLeft, Qt.AlignmentFlag.AlignRight
        x_lo, x_hi = self.x_of(self.clim[0]), self.x_of(self.clim[1])
        lo_rect = (QRectF(x_lo - width - 3, r.bottom() + 2, width, _LABEL_H), right_align) if x_lo - width - 3 >= 0 \
            else (QRectF(x_lo + 3, r.bottom() + 2, width, _LABEL_H), left_align)
        hi_rect = (QRectF(x_hi + 3, r.bottom() + 2, width, _LABEL_H), left_align) if x_hi + width + 3 <= self.width() \
            else (QRectF(x_hi - width - 3, r.bottom() + 2, width, _LABEL_H), right_align)
        for (rect, align), v in zip((lo_rect, hi_rect), self.clim):
            p.drawText(rect, align, format_limit(v))
        if self.n_nan:  # in its own row above the bars: never under a bar or a limit line
            p.drawText(QRectF(r.left(), _MARGIN - 2, r.width(), _LABEL_H), Qt.AlignmentFlag.AlignRight,
                       f"{self.n_nan} invalid (not shown)")

    # -- dragging -------------------------------------------------------------------------------
    def _near(self, x: float) -> int | None:
        d = [abs(x - self.x_of(v)) for v in self.clim]
        i = int(np.argmin(d))
        return i if d[i] <= 6 else None

    def mousePressEvent(self, event) -> None:  # noqa: N802
        if self.counts.size:
            self._drag = self._near(event.position().x())

    def mouseMoveEvent(self, event) -> None:  # noqa: N802
        x = event.position().x()
        if self._drag is None:
            cursor = Qt.CursorShape.SizeHorCursor if self.counts.size and self._near(x) is not None else Qt.CursorShape.ArrowCursor
            self.setCursor(cursor)
            return
        lims = list(self.clim)
        lims[self._drag] = self.value_of(x)
        if lims[0] < lims[1]:
            self.clim = (lims[0], lims[1])
            self.update()

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802
        if self._drag is not None:
            self._drag = None
            self.limits_edited.emit(*self.clim)
