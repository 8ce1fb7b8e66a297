"""Max (1999) vertex normal terms of the corners around a vertex, as numba helpers.

The corner pass of a fresh mesh (:func:`curv.core.connectivity.corner_pass`), the normals
(:mod:`curv.geometry.normals`, which owns the weighting and exposes these) and meyer call them; they sit
below the mesh model so that the connectivity kernels may use them.
"""

from __future__ import annotations

import math

from .jit import jit

__all__ = ["max_normal", "max_weight", "corner_term", "corner_terms", "unit"]


@jit
def max_normal(p, lo, hi, corners, indices, corner_next, corner_prev, x):
    """Max (1999) normal of vertex p, unnormalised: sum over its corners of ``(a x b) / (|a|^2 |b|^2)``.

    a and b are the edges from p to the next and to the previous vertex of the corner's face; a
    corner with a zero-length edge gives nothing. ``corners[lo:hi]`` are the corners at p.

    Returns
    -------
    sx, sy, sz : float
    """
    sx, sy, sz = 0.0, 0.0, 0.0
    for i in range(lo, hi):
        c = corners[i]
        wx, wy, wz = corner_term(x, p, indices[corner_next[c]], indices[corner_prev[c]])
        sx += wx
        sy += wy
        sz += wz
    return sx, sy, sz


@jit
def corner_term(x, p, b, q):
    """The Max normal term of the corner at p whose face's next vertex is b and previous vertex q:
    ``(a x b) / (|a|^2 |b|^2)`` with the edges ``a = x[b] - x[p]``, ``b = x[q] - x[p]``.

    Returns
    -------
    wx, wy, wz : float
    """
    wx, wy, wz, _ = corner_terms(x, p, b, q)
    return wx, wy, wz


@jit
def corner_terms(x, p, b, q):
    """:func:`corner_term` and ``|a|^2``, the squared edge from p to the next vertex b (the corner
    pass takes the longest edge from it).

    Returns
    -------
    wx, wy, wz, a2 : float
    """
    ax, ay, az = x[b, 0] - x[p, 0], x[b, 1] - x[p, 1], x[b, 2] - x[p, 2]
    bx, by, bz = x[q, 0] - x[p, 0], x[q, 1] - x[p, 1], x[q, 2] - x[p, 2]
    a2 = ax * ax + ay * ay + az * az
    wx, wy, wz = max_weight(ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx, a2, bx * bx + by * by + bz * bz)
    return wx, wy, wz, a2


@jit
def max_weight(cx, cy, cz, a2, b2):
    """One corner's term of the Max normal: ``(a x b) / (|a|^2 |b|^2)`` from ``c = a x b``, ``|a|^2``,
    ``|b|^2``; 0 where an edge has (almost) zero length."""
    denominator = a2 * b2
    if denominator == 0.0:
        return 0.0, 0.0, 0.0
    inv = 1.0 / denominator
    if not math.isfinite(inv):
        return 0.0, 0.0, 0.0
    return cx * inv, cy * inv, cz * inv


@jit
def unit(sx, sy, sz):
    """``s / |s|``; NaN when ``|s|`` is (near) zero (as :func:`curv.geometry.normals.normalize_rows`)."""
    norm = math.sqrt(sx * sx + sy * sy + sz * sz)
    if not norm > 1e-300:
        return math.nan, math.nan, math.nan
    return sx / norm, sy / norm, sz / norm
