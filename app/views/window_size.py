"""Sizing the window to the screen it opens on."""

from __future__ import annotations

from PySide6.QtGui import QGuiApplication

__all__ = ["screen_room", "fit_to_screen", "FIRST_LAUNCH_SHARE", "LARGEST_FIRST_SIZE"]

FIRST_LAUNCH_SHARE = (0.94, 0.92)
"""Share of the screen's available width and height a first launch takes."""
LARGEST_FIRST_SIZE = (1680, 1050)


def _available(window):
    screen = window.screen() or QGuiApplication.primaryScreen()
    return None if screen is None else screen.availableGeometry()


def screen_room(window, w: int, h: int) -> tuple[int, int]:
    """``w`` x ``h`` shrunk to what the available geometry of ``window``'s screen holds (the frame the
    window manager adds counted when the window is shown); unchanged without a screen."""
    avail = _available(window)
    if avail is None:
        return int(w), int(h)
    frame_w = max(window.frameGeometry().width() - window.geometry().width(), 0)
    frame_h = max(window.frameGeometry().height() - window.geometry().height(), 0)
    return int(min(w, avail.width() - frame_w)), int(min(h, avail.height() - frame_h))


def fit_to_screen(window) -> None:
    """First launch: most of the available screen (:data:`FIRST_LAUNCH_SHARE`, at most
    :data:`LARGEST_FIRST_SIZE`), centred; ``window.fit_to`` shares it among the docks."""
    avail = _available(window)
    if avail is None:
        window.fit_to(1400, 860)
        return
    w = int(min(avail.width() * FIRST_LAUNCH_SHARE[0], LARGEST_FIRST_SIZE[0]))
    h = int(min(avail.height() * FIRST_LAUNCH_SHARE[1], LARGEST_FIRST_SIZE[1]))
    window.fit_to(w, h)
    window.move(avail.x() + (avail.width() - w) // 2, avail.y() + (avail.height() - h) // 2)
