"""The mesh report (components, borders, non-manifold, isolated, degenerate) of the open mesh, with
the opt-in repairs of ``curv estimate`` for a file."""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import QCheckBox, QLabel, QPushButton, QVBoxLayout, QWidget

from app.model import Document, FileSource, pane_letter
from app.model.inputs import result_report

__all__ = ["MeshPanel", "REPAIRS"]

REPAIRS = (
    ("merge_vertices", "Merge vertices at identical positions"),
    ("remove_degenerate", "Remove degenerate faces"),
    ("orient", "Orient faces consistently"),
    ("remove_unreferenced", "Remove unreferenced (isolated) vertices"),
)
"""``curv.load`` flags offered as repairs, with their labels (the CLI's --merge-vertices, ...)."""


class MeshPanel(QWidget):
    """Shows :attr:`Document.report`; ``reload_requested(FileSource)`` reopens the file with repairs."""

    reload_requested = Signal(object)

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.text = QLabel()
        self.text.setWordWrap(True)
        self.text.setTextFormat(Qt.TextFormat.RichText)
        self.repairs = {}
        lay = QVBoxLayout(self)
        lay.addWidget(self.text)
        self.repair_label = QLabel("<b>Repairs</b> (reload the file with):")
        lay.addWidget(self.repair_label)
        for key, label in REPAIRS:
            box = QCheckBox(label)
            self.repairs[key] = box
            lay.addWidget(box)
        self.reload = QPushButton("Reload with repairs")
        self.reload.clicked.connect(self._reload)
        lay.addWidget(self.reload)
        lay.addStretch(1)
        doc.mesh_changed.connect(lambda change: self.refresh())
        doc.report_changed.connect(self.refresh)
        doc.result_changed.connect(lambda key: self.refresh())
        doc.panes_changed.connect(self.refresh)
        doc.pane_changed.connect(lambda i: self.refresh())
        self.refresh()

    def refresh(self) -> None:
        doc = self.doc
        if doc.mesh is None:
            self.text.setText("<i>No mesh or point cloud yet.</i>")
        else:
            lines = [f"<b>{doc.source.label}</b>"] + (
                ["<i>Checking the mesh (after its estimates)…</i>"] if doc.report is None else list(doc.report))
            lines += [f"repair: {r}" for r in doc.repairs]
            res = doc.result(doc.active) if doc.is_points else None
            if res is not None:  # what the active pane's estimate found: its normals, the border points
                lines += [f"<b>Pane {pane_letter(doc.active)}</b> ({doc.panes[doc.active].title}):"]
                lines += result_report(res)
            self.text.setText("<br>".join(lines))
        is_file = isinstance(doc.source, FileSource) and not doc.is_points  # the repairs mend faces
        for key, box in self.repairs.items():
            box.setEnabled(is_file)
            box.setChecked(is_file and key in doc.source.repairs)
        self.reload.setEnabled(is_file)
        self.repair_label.setEnabled(is_file)

    def _reload(self) -> None:
        if isinstance(self.doc.source, FileSource):
            chosen = tuple(k for k, box in self.repairs.items() if box.isChecked())
            self.reload_requested.emit(FileSource(self.doc.source.path, chosen))
