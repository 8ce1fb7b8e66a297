"""The picked-vertex readout: position, curvatures and directions in every pane, truth and error."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from PySide6.QtWidgets import QTextBrowser

from app.model import Document
from app.model.errors import relative_error

__all__ = ["Readout", "readout_rows"]


def _f(x) -> str:
    return "—" if x is None or not np.isfinite(x) else f"{x:.5g}"


def _vec(v) -> str:
    return "—" if not np.all(np.isfinite(v)) else "(" + ", ".join(f"{c:+.3f}" for c in v) + ")"


def readout_rows(doc: Document, index: int) -> list[tuple[str, list[str]]]:
    """Rows ``(label, [value per column])`` for vertex ``index``; columns are the panes (+ exact)."""
    cols = [doc.result(i) for i in range(len(doc.panes))]
    truth = doc.truth
    if truth is not None:
        cols.append(truth)
    rows = []
    for label, get in [("k1", lambda r: _f(r.k1[index])), ("k2", lambda r: _f(r.k2[index])),
                       ("H", lambda r: _f(r.mean[index])), ("K", lambda r: _f(r.gaussian[index])),
                       ("d1", lambda r: _vec(r.d1[index])), ("d2", lambda r: _vec(r.d2[index])),
                       ("valid", lambda r: "yes" if r.valid[index] else "no")]:
        rows.append((label, [get(r) if r is not None else "…" for r in cols]))
    if truth is not None:
        errs = []
        for r in cols[:-1]:
            errs.append(_f(relative_error(_at(r, index), _at(truth, index))[0]) if r is not None else "…")
        rows.append(("e_rel", errs + [""]))
    return rows


def _at(res, i) -> SimpleNamespace:
    """The principal curvatures of one vertex, shaped like a one-vertex result."""
    return SimpleNamespace(k1=res.k1[i:i + 1], k2=res.k2[i:i + 1])


class Readout(QTextBrowser):
    """Shows :func:`readout_rows` of the document's picked vertex as a table."""

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.setMinimumHeight(150)
        doc.picked_changed.connect(lambda i: self.refresh())
        doc.mesh_changed.connect(self.refresh)
        doc.result_changed.connect(lambda key: self.refresh())
        doc.pane_changed.connect(lambda i: self.refresh())
        doc.panes_changed.connect(self.refresh)
        self.refresh()

    def refresh(self) -> None:
        doc, i = self.doc, self.doc.picked
        if i is None or doc.mesh is None:
            self.setHtml("<i>Click on the mesh to pick a vertex.</i>")
            return
        p = doc.mesh.vertices[i]
        heads = [f"{chr(65 + j)}: {pane.method} R{pane.range}" for j, pane in enumerate(doc.panes)]
        if doc.truth is not None:
            heads.append("exact")
        html = [f"<b>vertex {i}</b> at {_vec(p)}<table cellspacing=4><tr><th></th>"]
        html += [f"<th>{h}</th>" for h in heads] + ["</tr>"]
        for label, vals in readout_rows(doc, i):
            html.append(f"<tr><td><b>{label}</b></td>" + "".join(f"<td>{v}</td>" for v in vals) + "</tr>")
        html.append("</table>")
        self.setHtml("".join(html))
