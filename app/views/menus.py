"""The window's menus and their actions: File (open, recent, samples, exports, quit), View (camera,
standard views, up axis, docks), Estimate and Help; and the event filter that keeps the window's
Ctrl shortcuts working while a text field has the focus."""

from __future__ import annotations

from PySide6.QtCore import QEvent, QObject, Qt
from PySide6.QtGui import QAction, QActionGroup, QKeySequence

from app.model.camera import UpAxis, View
from app.packaged import resource, sample_names

__all__ = ["build_menus", "WindowShortcuts", "ADVISE_TIP", "ADVISE_POINTS_TIP", "UP_AXIS_TITLES"]

ADVISE_TIP = ("Measure this mesh's noise, irregularity and density and rank the estimators and ranges by the "
              "error the paper's study predicts; Apply in the Advice panel uses one (Ctrl+Shift+A)")
ADVISE_POINTS_TIP = "The advisor ranks estimators for meshes (its table comes from the study's meshes), not point clouds"
UP_AXIS_TITLES = {UpAxis.Y: "+y up (MeshLab, most mesh files)", UpAxis.Z: "+z up (scans, CAD, terrain)"}


def build_menus(win) -> None:
    """Add the menus to ``win`` (a :class:`~app.views.main_window.MainWindow`) and keep their actions
    as its ``action_*`` attributes (``view_actions``: :class:`View` -> action, ``up_actions``:
    :class:`UpAxis` -> action)."""
    file_menu = win.menuBar().addMenu("&File")
    win.action_open = QAction("&Open…", win, shortcut=QKeySequence.StandardKey.Open, triggered=win.open_dialog)
    win.recent_menu = file_menu.addMenu("Open &Recent")
    win.sample_menu = file_menu.addMenu("Open &Sample")
    for name in sample_names():
        win.sample_menu.addAction(name, lambda n=name: win.open_path(str(resource(f"samples/{n}"))))
    win.action_export_ply = QAction("Export coloured &PLY…", win, shortcut="Ctrl+E",
                                    triggered=win.exports.export_ply_dialog)
    win.action_export_vtu = QAction("Export &VTK (.vtu) for ParaView…", win, shortcut="Ctrl+Shift+E",
                                    triggered=win.exports.export_vtu_dialog)
    win.action_export_png = QAction("Export &screenshot (PNG)…", win, shortcut="Ctrl+Shift+S",
                                    triggered=win.exports.export_png_dialog)
    win.action_quit = QAction("&Quit", win, shortcut=QKeySequence.StandardKey.Quit, triggered=win.close)
    file_menu.insertAction(win.recent_menu.menuAction(), win.action_open)
    file_menu.addSeparator()
    file_menu.addActions([win.action_export_ply, win.action_export_vtu, win.action_export_png])
    file_menu.addSeparator()
    file_menu.addAction(win.action_quit)

    view_menu = win.menuBar().addMenu("&View")
    win.action_reset_camera = QAction("&Reset camera", win, shortcut="R", triggered=win.grid.reset_camera)
    win.action_reset_camera.setToolTip("Frame the whole input from the current standard view")
    view_menu.addAction(win.action_reset_camera)
    views = view_menu.addMenu("Standard &views")
    win.view_actions = {}
    for view in View:
        action = QAction(view.title, win, triggered=lambda _=False, v=view: win.set_view(v))
        views.addAction(action)
        win.view_actions[view] = action
    up_menu = view_menu.addMenu("&Up axis")
    group = QActionGroup(win)
    win.up_actions = {}
    for up in UpAxis:
        action = QAction(UP_AXIS_TITLES[up], win, checkable=True, triggered=lambda _=False, u=up: win.set_up_axis(u))
        group.addAction(action)
        up_menu.addAction(action)
        win.up_actions[up] = action
    view_menu.addSeparator()
    for dock in win.docks.values():
        view_menu.addAction(dock.toggleViewAction())

    est_menu = win.menuBar().addMenu("&Estimate")
    win.action_recompute = QAction("&Recompute active pane", win, shortcut="F5",
                                   triggered=lambda: win.controller.recompute(win.doc.panes[win.doc.active].key))
    win.action_cancel = QAction("&Cancel", win, shortcut="Esc", triggered=win.controller.cancel)
    win.action_advise = QAction("&Advise estimator and range", win, shortcut="Ctrl+Shift+A", triggered=win.advise)
    win.action_advise.setIconText("Advise")
    win.action_advise.setToolTip(ADVISE_TIP)
    win.action_advise.setStatusTip("Rank the estimators and ranges for this mesh")
    est_menu.addActions([win.action_recompute, win.action_advise, win.action_cancel])
    win.inspect.advise_button.setDefaultAction(win.action_advise)
    win.advice_panel.advise_button.setDefaultAction(win.action_advise)

    help_menu = win.menuBar().addMenu("&Help")
    help_menu.addAction(QAction("Estimators and ranges…", win, shortcut=QKeySequence.StandardKey.HelpContents,
                                triggered=win.show_guide))
    help_menu.addAction(QAction("&About curvlab", win, triggered=win.show_about))


class WindowShortcuts(QObject):
    """An application event filter: a Ctrl shortcut of one of ``window``'s actions goes to the action
    even where the focused widget has a binding of its own for the key (a line edit takes Ctrl+E as
    "end of line", so the export's Ctrl+E did nothing while a number field had the focus)."""

    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = window

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 (Qt API)
        if event.type() != QEvent.Type.ShortcutOverride or not event.modifiers() & Qt.KeyboardModifier.ControlModifier:
            return False
        top = getattr(obj, "window", None)
        if not callable(top) or top() is not self.window:  # a widget of another window, or not a widget
            return False
        pressed = QKeySequence(event.keyCombination())
        for action in self.window.findChildren(QAction):
            if action.isEnabled() and any(s.matches(pressed) == QKeySequence.SequenceMatch.ExactMatch
                                          for s in action.shortcuts()):
                event.ignore()  # not overridden: the shortcut map delivers it to the action
                return True
        return False
