"""The export dialogs: a name suggested from the input and the active pane, then the controller writes
the file (PLY, VTU) in the background; the screenshot is the window's own."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6.QtWidgets import QFileDialog

from app.model.export import export_name

__all__ = ["Exports"]


class Exports:
    """What the File menu's exports do in ``window`` (a :class:`~app.views.main_window.MainWindow`)."""

    def __init__(self, window) -> None:
        self.window = window

    def colours(self) -> np.ndarray:
        """A copy of the active pane's colours as shown."""
        win = self.window
        return np.array(win.grid.viewports[win.doc.active].colours, dtype=np.uint8)

    def export_png(self, path) -> Path:
        """Save an image of the viewports (all panes) as PNG."""
        grid = self.window.grid
        grid.render_all()
        if not grid.grab().save(str(path), "PNG"):
            raise OSError(f"could not write {path}")
        return Path(path)

    def export_ply_dialog(self) -> None:
        self._dialog("Export coloured PLY", "PLY (*.ply)", ".ply")

    def export_vtu_dialog(self) -> None:
        self._dialog("Export VTK unstructured grid", "VTK XML (*.vtu)", ".vtu")

    def export_png_dialog(self) -> None:
        self._dialog("Export screenshot", "PNG (*.png)", ".png")

    def suggested_path(self, suffix: str) -> str:
        """The last export folder and :func:`~app.model.export.export_name` of the active pane."""
        win = self.window
        folder = Path(str(win.settings.value("export_dir", "") or win.settings.value("last_dir", "") or "."))
        return str(folder / export_name(win.doc, suffix)) if win.doc.source is not None else str(folder)

    def _dialog(self, title, filt, suffix) -> None:
        win = self.window
        if win.doc.mesh is None or (suffix != ".png" and win.doc.result(win.doc.active) is None):
            win.show_status("Nothing to export yet: the active pane has no result", error=True)
            return
        path, _ = QFileDialog.getSaveFileName(win, title, self.suggested_path(suffix), filt)
        if not path:
            return
        path = path if path.lower().endswith(suffix) else path + suffix
        win.settings.setValue("export_dir", str(Path(path).parent))
        if suffix == ".png":
            try:
                self.export_png(path)
            except OSError as exc:
                win.show_error(f"Export failed: {exc}")
                return
            win.show_status(f"Wrote {path}")
            return
        win.controller.export_later(path, self.colours())
