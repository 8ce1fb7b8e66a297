"""The picked-vertex readout: position, curvatures, directions and status in every pane, A − B,
truth and error (rows from :mod:`app.model.readout`)."""

from __future__ import annotations

from html import escape

from PySide6.QtWidgets import QTextBrowser, QTextEdit

from app.model import Document, pane_letter, readout_columns, readout_rows
from app.model.inputs import item_word
from app.model.readout import fmt_vec

COMPACT_AFTER = 2
"""With more columns than this the headers are pane letters and vectors stack their components."""

NOWRAP = "white-space: nowrap"

__all__ = ["Readout"]


def _cell(value: str, compact: bool) -> str:
    """A readout value as a table cell: its lines as given, the ``± 2σ`` on a line of its own when
    ``compact``."""
    if compact:
        value = value.replace(" ± ", "\n± ")
    return "<br>".join(escape(line) for line in value.split("\n"))


class Readout(QTextBrowser):
    """Shows the document's picked vertex as a table; follows pane, result and display changes."""

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.setMinimumHeight(150)
        # text lines wrap; a table cell never wraps inside a value (a table wider than the dock scrolls
        # sideways): with many columns a value's uncertainty goes on a line of its own (see COMPACT_AFTER)
        self.setLineWrapMode(QTextEdit.LineWrapMode.WidgetWidth)
        self.document().setDocumentMargin(2)
        doc.picked_changed.connect(lambda i: self.refresh())
        doc.mesh_changed.connect(lambda change: self.refresh())
        doc.result_changed.connect(lambda key: self.refresh())
        doc.pane_changed.connect(lambda i: self.refresh())
        doc.panes_changed.connect(self.refresh)
        doc.display.changed.connect(lambda names: self.refresh())
        self.refresh()

    def refresh(self) -> None:
        doc, i = self.doc, self.doc.picked
        if i is None or doc.mesh is None:
            self.setHtml(f"<i>Click on the {'point cloud' if doc.is_points else 'mesh'} to pick a "
                         f"{'point' if doc.is_points else 'vertex'}.</i>")
            return
        p = doc.mesh.vertices[i]
        compact = len(readout_columns(doc)) > COMPACT_AFTER  # narrow columns: no sideways scrolling
        html = [f"<b>{item_word(doc.mesh)} {i}</b> at {fmt_vec(p)}"]
        if compact:  # the panes' names once above the table (a region shared by all of them once too)
            regions = {pane.region for pane in doc.panes}
            shared = next(iter(regions)) if len(regions) == 1 else None
            html.append("<br>" + " · ".join(f"<b>{pane_letter(j)}:</b> {escape((pane.whole if shared else pane).title)}"
                                            for j, pane in enumerate(doc.panes)))
            if shared is not None:
                html.append(f"<br>all in the {escape(shared.title)}")
        html.append(f"<table cellspacing={2 if compact else 4}><tr><th></th>")
        html += [f"<th>{h}</th>" for h in readout_columns(doc, short=compact)] + ["</tr>"]
        for label, vals in readout_rows(doc, i, stacked=compact):
            html.append(f"<tr><td style='{NOWRAP}'><b>{label}</b></td>"
                        + "".join(f"<td style='{NOWRAP}'>{_cell(v, compact)}</td>" for v in vals) + "</tr>")
        html.append("</table>")
        self.setHtml("".join(html))
