"""The triangle at a corner, seen from the corner's vertex: the shared helpers of meyer and ru.

A corner of triangle (a, b, c) at vertex ``a`` has the edges ``ab = b - a`` and ``ac = c - a``
(b and c the next and previous vertices of its face). Everything a 1-ring estimator needs from
the triangle follows from them and their three dot products; the kernels loop over the corners
of each vertex (:attr:`curv.Mesh.vertex_corners`) and call :func:`corner_triangle`.

Kernels compiled with numba's default error model raise on a float division by zero (and a
parallel kernel may then stop without a word), so every division here is guarded.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.connectivity import next_corner, prev_corner
from ..core.jit import jit
from ..core.mesh import Mesh
from ..core.result import Principal
from ..core.validity import OK, precedence
from ..geometry.neighbourhood import all_centres

__all__ = ["corner_triangle", "turn_by_corner", "angle_sum", "ring_reason", "ring_flag", "unset_principal"]

@jit
def corner_triangle(x, a, b, c, degenerate):
    """Edges, cotangents and mixed Voronoi area of the corner at ``a`` of triangle (a, b, c).

    Parameters
    ----------
    x : (n, 3) float64
        Vertex positions.
    a, b, c : int
        The corner's vertex, the next and the previous vertex of its face.
    degenerate : bool
        The face is degenerate (:attr:`curv.Mesh.degenerate_faces`).

    Returns
    -------
    abx, aby, abz, acx, acy, acz : float
        ``ab = b - a``, ``ac = c - a``.
    nx, ny, nz : float
        ``ab x ac``, the face normal times twice the area.
    ab2, ac2 : float
        ``|ab|^2``, ``|ac|^2``.
    twice_area : float
        ``|ab x ac|``.
    cos_a : float
        ``ab . ac`` (cosine of the angle at a times both edge lengths).
    cot_b, cot_c : float
        Cotangents at b and c (0 on a degenerate face).
    mixed_area : float
        The corner's share of Meyer's ``A_mixed`` (0 on a degenerate face): its Voronoi area in a
        non-obtuse triangle, half the triangle at an obtuse corner a, a quarter when b or c is obtuse.
    """
    abx, aby, abz = x[b, 0] - x[a, 0], x[b, 1] - x[a, 1], x[b, 2] - x[a, 2]
    acx, acy, acz = x[c, 0] - x[a, 0], x[c, 1] - x[a, 1], x[c, 2] - x[a, 2]
    nx = aby * acz - abz * acy
    ny = abz * acx - abx * acz
    nz = abx * acy - aby * acx
    twice_area = math.sqrt(nx * nx + ny * ny + nz * nz)
    ab2 = abx * abx + aby * aby + abz * abz
    ac2 = acx * acx + acy * acy + acz * acz
    cos_a = abx * acx + aby * acy + abz * acz
    if degenerate or twice_area == 0.0:  # (the second never happens on a face that is not degenerate)
        return abx, aby, abz, acx, acy, acz, nx, ny, nz, ab2, ac2, twice_area, cos_a, 0.0, 0.0, 0.0
    # (a - b).(c - b) and (a - c).(b - c), from the dot products at hand
    cos_b = ab2 - cos_a
    cos_c = ac2 - cos_a
    cot_b = cos_b / twice_area
    cot_c = cos_c / twice_area
    if cos_a < 0:
        area = 0.25 * twice_area
    elif cos_b < 0 or cos_c < 0:
        area = 0.125 * twice_area
    else:
        # edge ab faces corner c, edge ac faces corner b
        area = 0.125 * (cot_c * ab2 + cot_b * ac2)
    return abx, aby, abz, acx, acy, acz, nx, ny, nz, ab2, ac2, twice_area, cos_a, cot_b, cot_c, area


@jit
def turn_by_corner(re, im, turns, twice_area, cos_a, degenerate):
    """Add the corner angle ``atan2(|ab x ac|, ab . ac)`` to an angle sum kept as a complex number.

    The sum of the angles of a vertex's corners is the argument of the product of the complex
    numbers ``ab . ac + i |ab x ac|`` (each of argument in [0, pi]), plus 2 pi for every time the
    product passed the positive real axis: one multiplication per corner instead of an ``atan2``.
    :func:`angle_sum` reads the sum off. A degenerate corner adds nothing (angle 0).

    Parameters
    ----------
    re, im : float
        The product so far (start with 1, 0).
    turns : int
        Completed turns so far (start with 0).

    Returns
    -------
    re, im, turns
    """
    if degenerate:
        return re, im, turns
    below = im < 0.0 or (im == 0.0 and re < 0.0)  # argument in [pi, 2 pi)
    re, im = re * cos_a - im * twice_area, re * twice_area + im * cos_a
    if below and im >= 0.0:  # an angle below pi took the argument past 2 pi
        turns += 1
    # keep the magnitude (a product of edge lengths squared) in range; powers of two scale exactly
    size = max(abs(re), abs(im))
    if size > 2.0**500:
        re, im = re * 2.0**-500, im * 2.0**-500
    elif 0.0 < size < 2.0**-500:
        re, im = re * 2.0**500, im * 2.0**500
    return re, im, turns


@jit
def angle_sum(re, im, turns):
    """The angle sum accumulated by :func:`turn_by_corner`: ``arg(re + i im)`` in [0, 2 pi) plus the turns."""
    angle = math.atan2(im, re)
    if angle < 0.0:
        angle += 2.0 * math.pi
    return angle + 2.0 * math.pi * turns


@jit
def ring_flag(p, lo, hi, corners, indices, corner_next, corner_prev, flags):
    """Whether ``flags`` is set at p or at an edge neighbour of p (the next and previous vertices
    of the corners ``corners[lo:hi]`` at p); an empty ``flags`` is set nowhere."""
    if flags.size == 0:
        return False
    if flags[p]:
        return True
    for i in range(lo, hi):
        c = corners[i]
        if flags[indices[next_corner(c, corner_next)]] or flags[indices[prev_corner(c, corner_prev)]]:
            return True
    return False


@jit
def ring_reason(singular, border, degenerate, nonmanifold):
    """Reason code of a vertex for an estimator that needs a closed, clean 1-ring, in the one
    precedence (:func:`curv.core.validity.precedence`): NONMANIFOLD, then DEGENERATE (a degenerate
    face around it, or no finite normal), BORDER (on or next to a border), SINGULAR, else OK.
    """
    return precedence(nonmanifold, degenerate, border, singular)


def ring_run(mesh: Mesh, centres: np.ndarray | None) -> tuple:
    """What a 1-ring estimator on triangles starts from: ``(centres, out, ring)``.

    ``centres`` (c,) int64 (every vertex when None), ``out`` the unset outputs
    (:func:`unset_principal`) and ``ring`` the mesh's corner arrays the ring kernels read, in their
    order: vertex corners (indptr, corners), face indices, next and previous corner
    (:attr:`curv.Mesh.corner_steps`: empty, the kernels step by arithmetic), vertex positions, and
    the degenerate-face, border (empty when no vertex is on a border: nothing to look up) and
    non-manifold vertex flags (the face of corner c is c // 3: no corner-to-face array is built). A
    :class:`~curv.core.errors.MeshError` naming the polygon sizes when the mesh is not all triangles.
    """
    n = mesh.n_vertices
    if not mesh.is_triangular:
        mesh.triangles  # raises the MeshError that names the polygon sizes
    indptr, corners = mesh.vertex_corners
    border = mesh.border_vertices
    ring = (indptr, corners, mesh.face_indices, *mesh.corner_steps, mesh.vertices,
            mesh.degenerate_faces, border if border.any() else border[:0], mesh.nonmanifold_vertices)
    return all_centres(n, centres), unset_principal(n), ring


def unset_principal(n: int) -> Principal:
    """Uninitialised (n,) and (n, 3) outputs of a 1-ring kernel, which writes every row it estimates.

    Unlike a NaN-filled result, allocating them costs nothing until a row is written, so an estimate
    over a small region of a large mesh touches only the region's rows.
    """
    return Principal(k1=np.empty(n), k2=np.empty(n), d1=np.empty((n, 3)), d2=np.empty((n, 3)),
                     reason=np.empty(n, np.uint8))
