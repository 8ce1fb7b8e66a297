"""The picked-vertex readout: position, curvatures, directions and status in every pane, A − B,
truth and error (rows from :mod:`app.model.readout`)."""

from __future__ import annotations

from html import escape

from PySide6.QtGui import QFont, QFontMetrics
from PySide6.QtWidgets import QTextBrowser, QTextEdit

from app.model import Document, pane_letter, readout_columns, readout_rows
from app.model.inputs import item_word
from app.model.readout import fmt_vec

COMPACT_AFTER = 2
"""With more columns than this the headers are pane letters and vectors stack their components."""

NOWRAP = "white-space: nowrap"

__all__ = ["Readout"]


class Readout(QTextBrowser):
    """Shows the document's picked vertex as a table; follows pane, result and display changes.

    A value never wraps inside itself, and the table never scrolls sideways: when its columns do not
    fit the dock's width they are shown as several tables one under the other, each with the row
    labels, as many columns each as fit.
    """

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.setMinimumHeight(150)
        self.setLineWrapMode(QTextEdit.LineWrapMode.WidgetWidth)  # the text above the tables wraps
        self.document().setDocumentMargin(2)
        self._width = 0
        doc.picked_changed.connect(lambda i: self.refresh())
        doc.mesh_changed.connect(lambda change: self.refresh())
        doc.result_changed.connect(lambda key: self.refresh())
        doc.pane_changed.connect(lambda i: self.refresh())
        doc.panes_changed.connect(self.refresh)
        doc.display.changed.connect(lambda names: self.refresh())
        self.refresh()

    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt API)
        super().resizeEvent(event)
        if self.viewport().width() != self._width:
            self.refresh()

    def refresh(self) -> None:
        doc, i = self.doc, self.doc.picked
        self._width = self.viewport().width()
        if i is None or doc.mesh is None:
            self.setHtml(f"<i>Click on the {'point cloud' if doc.is_points else 'mesh'} to pick a "
                         f"{'point' if doc.is_points else 'vertex'}.</i>")
            return
        p = doc.mesh.vertices[i]
        compact = len(readout_columns(doc)) > COMPACT_AFTER  # narrow columns: letters for headers
        html = [f"<b>{item_word(doc.mesh)} {i}</b> at {fmt_vec(p)}"]
        if compact:  # the panes' names once above the table (a region shared by all of them once too)
            regions = {pane.region for pane in doc.panes}
            shared = next(iter(regions)) if len(regions) == 1 else None
            html.append("<br>" + " · ".join(f"<b>{pane_letter(j)}:</b> {escape((pane.whole if shared else pane).title)}"
                                            for j, pane in enumerate(doc.panes)))
            if shared is not None:
                html.append(f"<br>all in the {escape(shared.title)}")
        heads = readout_columns(doc, short=compact)
        rows = [(label, [_lines(v, compact) for v in vals]) for label, vals in readout_rows(doc, i, stacked=compact)]
        spacing = 2 if compact else 4
        for group in self._column_groups(heads, rows, spacing):
            html.append(f"<table cellspacing={spacing}><tr><th></th>"
                        + "".join(f"<th style='{NOWRAP}'>{escape(heads[j])}</th>" for j in group) + "</tr>")
            for label, vals in rows:
                html.append(f"<tr><td style='{NOWRAP}'><b>{escape(label)}</b></td>"
                            + "".join(f"<td style='{NOWRAP}'>{'<br>'.join(map(escape, vals[j]))}</td>" for j in group)
                            + "</tr>")
            html.append("</table>")
        self.setHtml("".join(html))

    def _column_groups(self, heads, rows, spacing: int) -> list[list[int]]:
        """The columns in groups whose tables fit the viewport's width (at least one column each)."""
        metrics, bold = self.fontMetrics(), QFont(self.font())
        bold.setBold(True)
        wide = QFontMetrics(bold)
        pad = 2 * spacing + 4  # cell spacing and padding, both sides
        label = max(wide.horizontalAdvance(lab) for lab, _ in rows) + pad
        widths = [max([wide.horizontalAdvance(heads[j])] + [metrics.horizontalAdvance(line) for _, vals in rows
                                                    for line in vals[j]]) + pad for j in range(len(heads))]
        room = self.viewport().width() - 2 * self.document().documentMargin() - label - 4
        groups, used = [[]], 0
        for j, w in enumerate(widths):
            if groups[-1] and used + w > room:
                groups.append([])
                used = 0
            groups[-1].append(j)
            used += w
        return groups


def _lines(value: str, compact: bool) -> list[str]:
    """A readout value's lines: as given, and the ``± 2σ`` on a line of its own when ``compact``."""
    if compact:
        value = value.replace(" ± ", "\n± ")
    return value.split("\n")
