"""Where the camera looks from: the standard views, the up axis and the first view of an input.

The first view of an input (:func:`first_view`):

- an analytic surface: isometric with +z up (its height axis is z by construction);
- a georeferenced point cloud (:func:`is_georeferenced`: much wider than tall, or far from the
  origin, as aerial and terrestrial scans in map coordinates are): from above, +z up, north (+y) at
  the top, as a map;
- any other mesh or cloud: the front view with the chosen up axis, +y by default as in MeshLab (most
  mesh files, the Stanford bunny among them, are modelled with +y up); the View menu changes the up
  axis and the choice is remembered.
"""

from __future__ import annotations

import enum

import numpy as np

__all__ = ["View", "UpAxis", "view_vectors", "first_view", "is_georeferenced", "WIDE_RATIO", "FAR_RATIO"]

WIDE_RATIO = 5.0
"""A cloud whose horizontal extent (the larger of x and y) is at least this many times its height (z)
is seen from above first."""
FAR_RATIO = 100.0
"""So is a cloud whose centre lies farther from the origin than this many times its size (map
coordinates: a 1 km scan at UTM easting 500 km)."""


class View(enum.Enum):
    """A standard view: where the camera stands, seen with the up axis up."""

    FRONT = "front"
    BACK = "back"
    LEFT = "left"
    RIGHT = "right"
    TOP = "top"
    BOTTOM = "bottom"
    ISOMETRIC = "isometric"

    @property
    def title(self) -> str:
        return self.value.capitalize()


class UpAxis(enum.Enum):
    """The axis drawn upwards in the standard views."""

    Y = "+y"
    Z = "+z"


_UP = {UpAxis.Y: np.array([0.0, 1.0, 0.0]), UpAxis.Z: np.array([0.0, 0.0, 1.0])}
_FRONT = {UpAxis.Y: np.array([0.0, 0.0, 1.0]), UpAxis.Z: np.array([0.0, -1.0, 0.0])}
"""Where the camera stands for the front view: on +z with +y up (MeshLab, OpenGL), on -y with +z up
(the engineering convention: x to the right in both)."""


def view_vectors(view: View, up: UpAxis) -> tuple[np.ndarray, np.ndarray]:
    """``(position, view_up)``: the direction from the focal point to the camera and the screen's up.

    Parameters
    ----------
    view : View
    up : UpAxis

    Returns
    -------
    position, view_up : (3,) float64
        Unit vectors; the right-hand side of the screen is ``cross(-position, view_up)``.
    """
    u, f = _UP[up], _FRONT[up]
    right = np.cross(u, f)  # x in both conventions
    position, view_up = {
        View.FRONT: (f, u),
        View.BACK: (-f, u),
        View.RIGHT: (right, u),
        View.LEFT: (-right, u),
        View.TOP: (u, -f),  # from above, the front at the bottom of the screen
        View.BOTTOM: (-u, f),
        View.ISOMETRIC: ((f + right + u) / np.sqrt(3.0), u),
    }[view]
    return np.array(position, float), np.array(view_up, float)


def is_georeferenced(points: np.ndarray) -> bool:
    """Whether a cloud's points (n, 3) look like a scan in map coordinates: their horizontal extent is
    at least :data:`WIDE_RATIO` times their height, or their centre is farther from the origin than
    :data:`FAR_RATIO` times their size."""
    points = np.asarray(points)
    if points.shape[0] == 0:
        return False
    lo, hi = points.min(axis=0), points.max(axis=0)
    extent = hi - lo
    size = float(np.linalg.norm(extent))
    if size == 0.0:
        return False
    wide = max(extent[0], extent[1]) >= WIDE_RATIO * extent[2]
    far = float(np.linalg.norm(0.5 * (lo + hi))) > FAR_RATIO * size
    return bool(wide or far)


def first_view(*, points: bool, analytic: bool, georeferenced: bool, up: UpAxis) -> tuple[View, UpAxis]:
    """The view and up axis an input opens in (module notes).

    Parameters
    ----------
    points : bool
        The input is a point cloud.
    analytic : bool
        It is an analytic surface (z up by construction).
    georeferenced : bool
        :func:`is_georeferenced` of its points (asked of clouds only).
    up : UpAxis
        The chosen up axis, for the other inputs.
    """
    if analytic:
        return View.ISOMETRIC, UpAxis.Z
    if points and georeferenced:
        return View.TOP, UpAxis.Z
    return View.FRONT, up
