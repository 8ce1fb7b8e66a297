"""The two input kinds the viewer shows, a mesh or a point cloud, and the words and lengths that
differ between them (every fact comes from the library)."""

from __future__ import annotations

import weakref

import numpy as np
from curv import PointCloud

__all__ = ["is_points", "unit_length", "item_word", "items_word", "samplings", "POINT_SIZES", "DEFAULT_POINT_SIZE", "DEFAULT_KNN"]

POINT_SIZES = (1, 40)
"""The point-size control's range, in pixels."""

DEFAULT_POINT_SIZE = 6
"""Pixels per point when a cloud first shows."""

DEFAULT_KNN = 20
"""The K the Nearest control offers first (about the support of R2 on an even sampling)."""


def is_points(obj) -> bool:
    """Whether ``obj`` (the document's input) is a :class:`curv.PointCloud` (no faces)."""
    return isinstance(obj, PointCloud)


_UNITS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def unit_length(obj) -> float:
    """The input's own length unit, for default radii and glyph lengths: a mesh's mean edge length, a
    point cloud's median spacing (the unit of its range, :func:`curv.ranges.point_spacing`).

    Remembered per input (a cloud's spacing is a neighbour search): the source worker asks first, so
    the GUI thread's later questions cost nothing.
    """
    if not is_points(obj):
        return float(obj.mean_edge_length)
    unit = _UNITS.get(obj)
    if unit is None:
        from curv.ranges import point_spacing

        unit = _UNITS[obj] = float(np.median(point_spacing(obj)))
    return unit


def samplings() -> dict[str, str]:
    """How the library samples a surface as points: ``{name: words}`` (``curv.surfaces.SAMPLINGS``)."""
    from curv.surfaces import SAMPLINGS

    return dict(SAMPLINGS)


def item_word(obj) -> str:
    """``point`` or ``vertex``: what one element of the input is called."""
    return "point" if is_points(obj) else "vertex"


def items_word(obj) -> str:
    """``points`` or ``vertices``."""
    return "points" if is_points(obj) else "vertices"
