"""Coordinates stored on a coarse grid (module notes, 7): the narrowest support whose fit is trusted.

:attr:`curv.PointCloud.coordinate_step` finds the grid; a fit over fewer than
:data:`MIN_SUPPORT_STEPS` of its steps (in radius) sees its stairs, not the surface.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.pointcloud import PointCloud
from ..core.ranges import point_spacing

__all__ = ["MIN_SUPPORT_STEPS", "support_floor", "quantised_supports", "range_above_grid"]

MIN_SUPPORT_STEPS = 10
"""A support must be at least this many coordinate steps wide (in radius) for its fit to be trusted
(:func:`support_floor`). On coordinates stored on a grid of step q (a LAS file's scale; ``plane.laz``
in laspy's samples: a plane on a 1 cm grid with 1.4 cm spacing), a fit over a ball of radius r sees
the grid's stairs: measured on that plane and on a sphere of radius 1 rounded to 1 cm (0.5 cm
spacing), the error in H that the grid alone causes is about q / r² in the median (0.7-1.0 x at
r = 6-16 q, qs and jet) and up to about 10 x that at the extremes. Below r = 10 q that reaches 1 / r,
the largest curvature a support of radius r can hold: the value can be anything (qs on the plane at
R2, r = 2.8 q: |H| up to 1.1e5 where the truth is 0). Such estimates are ``SINGULAR`` (ill-conditioned
at the coordinates' resolution), and the normals are fitted over at least this radius
(:func:`.normals.point_normals`): with R2 normals qs on the plane at R8 still reached |H| 506, with normals
over 10 q at most 4.7."""


def support_floor(cloud: PointCloud) -> float:
    """The narrowest support radius trusted on this cloud: :data:`MIN_SUPPORT_STEPS` steps of the
    grid its coordinates are stored on (:attr:`curv.PointCloud.coordinate_step`; about 1e-5 of the
    spacing for coordinates of full precision, where it changes nothing)."""
    return MIN_SUPPORT_STEPS * cloud.coordinate_step


def range_above_grid(cloud: PointCloud, *, uses_normals: bool = False) -> int:
    """The smallest whole range Rk whose supports reach :func:`support_floor` at 95 % of the points
    (those with the 5 % smallest spacings may stay below), and at least the normals' default range:
    what to ask for on a coarse grid."""
    from .normals import NORMAL_RANGE

    spacing = point_spacing(cloud)
    low = float(np.percentile(spacing[np.isfinite(spacing)], 5)) if np.isfinite(spacing).any() else 0.0
    if not low > 0.0:
        return NORMAL_RANGE
    k = max(NORMAL_RANGE, math.ceil(support_floor(cloud) / low - 1e-9))
    return k + 1 if uses_normals else k


def quantised_supports(cloud: PointCloud, radii: np.ndarray) -> np.ndarray:
    """(n,) bool: the supports of these radii (n,) narrower than :func:`support_floor`, whose fits
    see the coordinates' grid rather than the surface (``SINGULAR`` in an estimate)."""
    return np.asarray(radii) < support_floor(cloud)
