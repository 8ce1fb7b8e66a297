"""What the ball-clipping estimators (``csm``, ``icc``) share: exact face areas inside a ball,
per-face frames, and the reason code of a support from the vertex flags it touched.

Estimator modules do not import each other (an import-linter contract); shared kernels live in
underscore modules like this one.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import jit, jit_parallel, launch, prange
from ..mesh import Mesh
from ..neighbourhood import coordinate_columns
from ..validity import Reason

__all__ = ["BORDER_BIT", "NONMANIFOLD_BIT", "DEGENERATE_BIT", "support_reason", "disc_triangle_area",
           "face_geometry", "face_frames", "face_frames_kernel", "face_in_ball_area", "support_flags"]

BORDER_BIT, NONMANIFOLD_BIT, DEGENERATE_BIT = 1, 2, 4
"""Bits of the per-vertex flags a support may hit (:func:`support_flags`)."""

_OK, _BORDER, _SINGULAR = int(Reason.OK), int(Reason.BORDER), int(Reason.SINGULAR)
_DEGENERATE, _NONMANIFOLD = int(Reason.DEGENERATE), int(Reason.NONMANIFOLD)

@jit
def support_reason(singular, hit, normal_ok):
    """Reason code of an estimate over a ball, from what its support touched.

    ``hit`` holds the flags of the support's vertices (BORDER_BIT, NONMANIFOLD_BIT, DEGENERATE_BIT:
    a degenerate face touches it). The most fundamental cause wins: NONMANIFOLD, then DEGENERATE
    (also for a missing normal), BORDER, SINGULAR, else OK.
    """
    if hit & NONMANIFOLD_BIT:
        return _NONMANIFOLD
    if hit & DEGENERATE_BIT or not normal_ok:
        return _DEGENERATE
    if hit & BORDER_BIT:
        return _BORDER
    if singular:
        return _SINGULAR
    return _OK


@jit
def _chord(ax, ay, bx, by, rho2):
    """Parameters ``t1 <= t2`` in [0, 1] of the part of edge a -> b inside the disc of squared radius ``rho2``.

    ``(0, 1)`` for an edge inside the disc, ``(0, 0)`` where its line misses the disc.
    """
    dx = bx - ax
    dy = by - ay
    if ax * ax + ay * ay <= rho2 and bx * bx + by * by <= rho2:
        return 0.0, 1.0
    a = dx * dx + dy * dy
    b = dx * ax + dy * ay
    c = ax * ax + ay * ay - rho2
    disc = b * b - a * c
    if not (disc > 0.0 and a > 0.0):
        return 0.0, 0.0
    sq = math.sqrt(disc)
    return min(max((-b - sq) / a, 0.0), 1.0), min(max((-b + sq) / a, 0.0), 1.0)


@jit
def _angle(ax, ay, bx, by):
    """Signed angle from direction a to direction b."""
    return math.atan2(ax * by - ay * bx, ax * bx + ay * by)


@jit
def _corner_sectors(ex, ey, t_exit, cx, cy, nx, ny, t_entry):
    """Signed angle of the circular sectors at corner c of the fan from the disc centre.

    The edge into c leaves the disc at e (``t_exit < 1``: a sector from e to c), the edge out of
    c enters it at n (``t_entry > 0``: a sector from c to n). Where both are true crossings of the
    circle (0 < t < 1) the two sectors are one, from e to n: each part is less than pi/2 (from a
    point of the circle outwards along a line), so their sum is one ``atan2``.
    """
    out_of = t_exit < 1.0
    into = t_entry > 0.0
    if out_of and into and t_exit > 0.0 and t_entry < 1.0:
        return _angle(ex, ey, nx, ny)
    angle = 0.0
    if out_of:
        angle += _angle(ex, ey, cx, cy)
    if into:
        angle += _angle(cx, cy, nx, ny)
    return angle


@jit
def disc_triangle_area(p0x, p0y, p1x, p1y, p2x, p2y, rho2):
    """Area of a counter-clockwise 2-D triangle inside the disc of squared radius ``rho2`` at 0.

    Summed as the fan from the disc centre over the boundary: a straight triangle over the part
    of each edge inside the disc (its chord), circular sectors of radius ``sqrt(rho2)`` where the
    boundary is outside (before and after each chord; a missed edge is one sector end to end).
    """
    # chord of edge i (corner i -> corner i + 1): from a_i = corner + s_i d to b_i = corner + t_i d
    s0, t0 = _chord(p0x, p0y, p1x, p1y, rho2)
    s1, t1 = _chord(p1x, p1y, p2x, p2y, rho2)
    s2, t2 = _chord(p2x, p2y, p0x, p0y, rho2)
    a0x, a0y = p0x + s0 * (p1x - p0x), p0y + s0 * (p1y - p0y)
    b0x, b0y = p0x + t0 * (p1x - p0x), p0y + t0 * (p1y - p0y)
    a1x, a1y = p1x + s1 * (p2x - p1x), p1y + s1 * (p2y - p1y)
    b1x, b1y = p1x + t1 * (p2x - p1x), p1y + t1 * (p2y - p1y)
    a2x, a2y = p2x + s2 * (p0x - p2x), p2y + s2 * (p0y - p2y)
    b2x, b2y = p2x + t2 * (p0x - p2x), p2y + t2 * (p0y - p2y)
    straight = 0.5 * ((a0x * b0y - a0y * b0x) + (a1x * b1y - a1y * b1x) + (a2x * b2y - a2y * b2x))
    # sectors around each corner: after the chord of the edge into it, before that of the edge out
    angle = (_corner_sectors(b2x, b2y, t2, p0x, p0y, a0x, a0y, s0)
             + _corner_sectors(b0x, b0y, t0, p1x, p1y, a1x, a1y, s1)
             + _corner_sectors(b1x, b1y, t1, p2x, p2y, a2x, a2y, s2))
    return straight + 0.5 * rho2 * angle


def face_geometry(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (m, 3) and areas (m,) of the triangles; zeros on degenerate faces."""
    degenerate = mesh.degenerate_faces
    normal = np.where(degenerate[:, None], 0.0, mesh.face_normals)
    area = np.where(degenerate, 0.0, mesh.face_areas)
    return normal, area


@jit_parallel
def _face_frames(tri, x, y, z, face_normal, out):
    for f in prange(tri.shape[0]):
        c0, c1, c2 = tri[f, 0], tri[f, 1], tri[f, 2]
        ex, ey, ez = x[c1] - x[c0], y[c1] - y[c0], z[c1] - z[c0]
        fx, fy, fz = x[c2] - x[c0], y[c2] - y[c0], z[c2] - z[c0]
        nx, ny, nz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
        x1 = math.sqrt(ex * ex + ey * ey + ez * ez)
        if not x1 > 0.0:
            x1 = 1.0  # degenerate: never clipped (zero area)
        ux, uy, uz = ex / x1, ey / x1, ez / x1
        vx = ny * uz - nz * uy
        vy = nz * ux - nx * uz
        vz = nx * uy - ny * ux
        out[f, 0], out[f, 1], out[f, 2] = ux, uy, uz
        out[f, 3], out[f, 4], out[f, 5] = vx, vy, vz
        out[f, 6], out[f, 7], out[f, 8] = nx, ny, nz
        out[f, 9] = x1
        out[f, 10] = fx * ux + fy * uy + fz * uz
        out[f, 11] = fx * vx + fy * vy + fz * vz


face_frames_kernel = _face_frames
"""The numba dispatcher behind :func:`face_frames` (for first-run compile announcements)."""


def face_frames(mesh: Mesh, face_normal: np.ndarray) -> np.ndarray:
    """(m, 12) per triangle: its frame u, v, n (u along corner 0 -> 1, v = n x u) and its corners in it.

    Columns ``ux uy uz vx vy vz nx ny nz x1 x2 y2``: corner 0 is the origin, corner 1 ``(x1, 0)``,
    corner 2 ``(x2, y2)``. ``face_normal`` is the first output of :func:`face_geometry`. Once per
    mesh, so that clipping a face to a ball needs no square root or division.
    """
    tri = np.ascontiguousarray(mesh.triangles, dtype=np.int64)
    x, y, z = coordinate_columns(mesh)
    out = np.empty((tri.shape[0], 12))
    launch(_face_frames, tri, x, y, z, face_normal, out)
    return out


@jit
def face_in_ball_area(frames, f, ox, oy, oz, radius2, area):
    """Exact area of triangle f (:func:`face_frames` row, full area ``area``) inside a ball.

    ``o`` is the ball centre minus corner 0 of the face. The whole area where all three corners
    are inside (the ball is convex), else :func:`disc_triangle_area` in the plane of the face.
    """
    cu = ox * frames[f, 0] + oy * frames[f, 1] + oz * frames[f, 2]
    cv = ox * frames[f, 3] + oy * frames[f, 4] + oz * frames[f, 5]
    h = ox * frames[f, 6] + oy * frames[f, 7] + oz * frames[f, 8]
    x1, x2, y2 = frames[f, 9], frames[f, 10], frames[f, 11]
    rho2 = radius2 - h * h  # squared radius of the disc B ∩ plane, around the foot (cu, cv)
    if not rho2 > 0.0:
        return 0.0
    if cu * cu + cv * cv <= rho2 and (x1 - cu) ** 2 + cv * cv <= rho2 and (x2 - cu) ** 2 + (y2 - cv) ** 2 <= rho2:
        return area
    part = disc_triangle_area(-cu, -cv, x1 - cu, -cv, x2 - cu, y2 - cv, rho2)
    return part if math.isfinite(part) else 0.0


def support_flags(mesh: Mesh) -> np.ndarray:
    """(n,) uint8 per-vertex bits a support may hit: border, non-manifold, on a degenerate face."""
    flags = mesh.border_vertices.astype(np.uint8) * BORDER_BIT
    flags |= mesh.nonmanifold_vertices.astype(np.uint8) * NONMANIFOLD_BIT
    degenerate = mesh.degenerate_faces
    if degenerate.any():
        flags[mesh.triangles[degenerate].reshape(-1)] |= DEGENERATE_BIT
    return flags
