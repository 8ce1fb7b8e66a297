"""Tangent frames: a vertex's normal N and an orthonormal tangent basis (U, V) with U x V = N, and
the offsets and normals of its neighbours read in that frame.

A fit's frame travels as the 9-tuple ``(ux, uy, uz, vx, vy, vz, n0, n1, n2)`` (:func:`normal_frame`);
:func:`tangent_frame` gives the 6-tuple (U, V) of any normal. The positions and normals the fits
read travel as one :class:`Geometry` bundle of (n,) columns.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..core.jit import jit

__all__ = ["Geometry", "geometry_of", "MIN_TANGENT_LENGTH", "tangent_frame", "normal_frame", "offset_in_frame",
           "scaled_offset", "normal_in_frame"]

Geometry = namedtuple("Geometry", ["x", "y", "z", "nx", "ny", "nz"])
"""The positions and the unit normals the fits read: six (n,) float64 columns (a NaN normal: no frame)."""

MIN_TANGENT_LENGTH = 1e-9
"""Neighbours whose tangent-plane offset is below this fraction of the ball radius carry no direction."""


def geometry_of(coordinates, normals: np.ndarray) -> Geometry:
    """The :class:`Geometry` of ``coordinates`` ((x, y, z) columns) and (n, 3) ``normals``."""
    x, y, z = coordinates
    nx, ny, nz = (np.ascontiguousarray(normals[:, c]) for c in range(3))
    return Geometry(x, y, z, nx, ny, nz)


@jit
def tangent_frame(nx, ny, nz):
    """Orthonormal tangent basis (U, V) with U x V = N, crossing N with its least-aligned axis.

    Returns
    -------
    ux, uy, uz, vx, vy, vz : float
        NaN where N is not finite.
    """
    ax, ay, az = abs(nx), abs(ny), abs(nz)
    # the coordinate axis least aligned with N (first on ties); N x axis is never near zero
    if ax <= ay and ax <= az:
        ux, uy, uz = 0.0, nz, -ny
    elif ay <= az:
        ux, uy, uz = -nz, 0.0, nx
    else:
        ux, uy, uz = ny, -nx, 0.0
    norm = math.sqrt(ux * ux + uy * uy + uz * uz)
    ux /= norm
    uy /= norm
    uz /= norm
    vx = ny * uz - nz * uy
    vy = nz * ux - nx * uz
    vz = nx * uy - ny * ux
    return ux, uy, uz, vx, vy, vz


@jit
def normal_frame(p, geometry):
    """Vertex p's frame (U, V, N) from its normal.

    Returns
    -------
    frame : 9-tuple of float
        ``(ux, uy, uz, vx, vy, vz, n0, n1, n2)``; NaN without a finite normal.
    ok : bool
        False without a finite normal (no frame to fit in).
    """
    n0, n1, n2 = geometry.nx[p], geometry.ny[p], geometry.nz[p]
    if not (math.isfinite(n0) and math.isfinite(n1) and math.isfinite(n2)):
        nan = math.nan
        return (nan, nan, nan, nan, nan, nan, nan, nan, nan), False
    ux, uy, uz, vx, vy, vz = tangent_frame(n0, n1, n2)
    return (ux, uy, uz, vx, vy, vz, n0, n1, n2), True


@jit
def offset_in_frame(p, q, geometry, frame):
    """The offset ``q - p`` in p's frame: ``(u, v, w)`` along U, V and N."""
    ux, uy, uz, vx, vy, vz, n0, n1, n2 = frame
    x, y, z = geometry.x, geometry.y, geometry.z
    dx, dy, dz = x[q] - x[p], y[q] - y[p], z[q] - z[p]
    return (dx * ux + dy * uy + dz * uz, dx * vx + dy * vy + dz * vz, dx * n0 + dy * n1 + dz * n2)


@jit
def scaled_offset(p, q, geometry, inv_r, frame):
    """The offset ``(q - p) / r`` in p's frame: ``(u, v, w)`` (``inv_r = 1 / r``)."""
    ux, uy, uz, vx, vy, vz, n0, n1, n2 = frame
    x, y, z = geometry.x, geometry.y, geometry.z
    dx, dy, dz = (x[q] - x[p]) * inv_r, (y[q] - y[p]) * inv_r, (z[q] - z[p]) * inv_r
    return dx * ux + dy * uy + dz * uz, dx * vx + dy * vy + dz * vz, dx * n0 + dy * n1 + dz * n2


@jit
def normal_in_frame(q, geometry, frame):
    """Vertex q's normal in p's frame: ``(a, b, c)`` along U, V and N."""
    ux, uy, uz, vx, vy, vz, n0, n1, n2 = frame
    mx, my, mz = geometry.nx[q], geometry.ny[q], geometry.nz[q]
    return mx * ux + my * uy + mz * uz, mx * vx + my * vy + mz * vz, mx * n0 + my * n1 + mz * n2
