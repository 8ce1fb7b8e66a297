"""Which point of a cloud is drawn under a pixel: the nearest the viewer of those whose sphere covers
it. Plain numpy over a snapshot of the camera, so that it can run off the GUI thread (5M points)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PointPick", "drawn_point_at", "clip_coordinates"]


def clip_coordinates(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """(n, 4) homogeneous clip coordinates of ``points`` (n, 3) through the 4x4 composite projection
    ``matrix`` (x, y, z in [-w, w] inside the view, z growing away from the viewer)."""
    return points @ matrix[:, :3].T + matrix[:, 3]


@dataclass(frozen=True)
class PointPick:
    """A click on a drawn cloud, with what the picture looked like.

    Attributes
    ----------
    points : (n, 3) float64
        The cloud's points (read only).
    matrix : (4, 4) float64
        The camera's composite projection matrix at the click.
    viewport : (x0, y0, x1, y1)
        The renderer's viewport in the window (fractions).
    window : (width, height)
        The render window's size in device pixels.
    x, y : float
        The click in device pixels, bottom-left origin.
    radius : float
        Half the drawn width of a point, in device pixels.
    """

    points: np.ndarray
    matrix: np.ndarray
    viewport: tuple
    window: tuple
    x: float
    y: float
    radius: float


def drawn_point_at(pick: PointPick) -> int | None:
    """The point drawn under the click of ``pick`` (None where no point covers it); numpy only."""
    clip = clip_coordinates(pick.points, pick.matrix)
    w = clip[:, 3]
    front = w > 0
    ndc = clip[:, :3] / np.where(front, w, 1.0)[:, None]
    x0, y0, x1, y1 = pick.viewport
    width, height = pick.window
    px = (x0 + 0.5 * (ndc[:, 0] + 1.0) * (x1 - x0)) * width
    py = (y0 + 0.5 * (ndc[:, 1] + 1.0) * (y1 - y0)) * height
    r = pick.radius
    hit = np.flatnonzero(front & ((px - pick.x) ** 2 + (py - pick.y) ** 2 <= r * r) & (np.abs(ndc[:, 2]) <= 1.0))
    if hit.size == 0:
        return None
    return int(hit[np.argmin(ndc[hit, 2])])
