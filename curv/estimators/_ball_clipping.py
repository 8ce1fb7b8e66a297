"""The clipping of an edge or a triangle by a ball: the exact part of it inside.

A sum over the ball B of radius r around a centre p holds every edge and face inside B whole; the
elements that cross the sphere count with their exact part inside:

- an edge a -> b with a inside leaves B at the fraction ``t`` of :func:`exit_fraction` (the root
  of ``|a + t (b - a)|² = r²``), and any segment has the part :func:`segment_in_ball` inside;
- a face meets B in the disc of radius ``sqrt(r² - h²)`` where B cuts its plane (h: the plane's
  distance from p). Its area inside is the fan from the disc's centre over the boundary of the
  clipped face: a straight triangle over each chord (the part of an edge inside), a circular
  sector over each arc between where the boundary leaves the disc and where it comes back
  (:func:`face_in_ball_area`; :func:`disc_triangle_area` in the face's own plane).

Points travel as 3-tuples of offsets from the ball's centre. Which faces of a mesh cross the
sphere is :mod:`curv.estimators._ball_mesh`'s question; this module clips one element at a time.
"""

from __future__ import annotations

import math

from ..core.jit import jit, jit_inlined

__all__ = ["segment_in_ball", "exit_fraction", "disc_triangle_area", "face_in_ball_area", "crossing_area", "offset",
           "dot3"]

# ---------------------------------------------------------------------------- points as 3-tuples
@jit_inlined
def offset(mesh, v, centre):
    """Vertex v's offset from ``centre`` (a 3-tuple; ``mesh.x``, ``mesh.y``, ``mesh.z`` the coordinates)."""
    return mesh.x[v] - centre[0], mesh.y[v] - centre[1], mesh.z[v] - centre[2]


@jit
def dot3(a, b):
    """``a . b`` of two 3-tuples."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@jit
def _triple(n, a, b):
    """``n . (a x b)``: for points a, b of a plane with unit normal n, offsets from any point off it,
    the 2-D cross product of their in-plane parts (the offset along n drops out)."""
    return n[0] * (a[1] * b[2] - a[2] * b[1]) + n[1] * (a[2] * b[0] - a[0] * b[2]) + n[2] * (a[0] * b[1] - a[1] * b[0])


@jit
def _along(a, b, t):
    """The point ``a + t (b - a)``."""
    return a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])


# ---------------------------------------------------------------------------- edges
@jit
def segment_in_ball(s, d, radius2):
    """Fraction of the segment ``s + t d``, t in [0, 1], inside the ball of squared radius ``radius2`` at 0.

    Solves ``|s + t d|^2 = radius2`` for t and clips the root interval to [0, 1]; 0 when the line
    misses the ball. ``s``, ``d``: 3-tuples.
    """
    a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    b = d[0] * s[0] + d[1] * s[1] + d[2] * s[2]
    c = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] - radius2
    disc = b * b - a * c
    if not (disc > 0.0 and a > 0.0):
        return 0.0
    sq = math.sqrt(disc)
    t1 = min(max((-b - sq) / a, 0.0), 1.0)
    t2 = min(max((-b + sq) / a, 0.0), 1.0)
    return t2 - t1


@jit
def exit_fraction(a, qa, b, radius2):
    """Parameter t in [0, 1] where the segment a -> b (a inside the ball around 0, b outside) leaves it.

    ``qa`` is ``|a|^2``. The same root as :func:`disc_triangle_area`'s, in 3-D (the offset of the
    plane drops out of it).
    """
    dx, dy, dz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    q = dx * dx + dy * dy + dz * dz
    half = dx * a[0] + dy * a[1] + dz * a[2]
    disc = max(half * half - q * (qa - radius2), 0.0)
    return min(max((-half + math.sqrt(disc)) / q, 0.0), 1.0)


# ---------------------------------------------------------------------------- a triangle in its plane
ARC_SPLIT = 1e-3
"""Below this ratio |sin| / cos an arc's angle is near 0 or 2 pi, where one ``atan2`` cannot tell which."""


@jit
def _angle(a, b):
    """Signed angle from 2-D direction a to direction b, in (-pi, pi]."""
    return math.atan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1])


@jit
def _corner(k, corners):
    """Corner ``k % 3`` of the 2-D triangle ``corners``."""
    k = k % 3
    if k == 0:
        return corners[0]
    if k == 1:
        return corners[1]
    return corners[2]


@jit
def _arc(e, exit_edge, n, entry_edge, corners):
    """Angle in (0, 2 pi) of the counter-clockwise arc from the exit point e to the entry point n.

    The triangle's boundary leaves the disc at e (on edge ``exit_edge``) and comes back at n (on
    ``entry_edge``); the arc from e to n closes the part of the triangle inside the disc, so it
    turns counter-clockwise. One ``atan2`` and the side of the chord e -> n (the disc centre lies
    to its right exactly when the arc is longer than pi) give the angle, except where e and n
    nearly coincide (an angle near 0 or 2 pi): there the angles of the fan from e over the outside
    corners to n, each less than pi, are summed.
    """
    cross = e[0] * n[1] - e[1] * n[0]
    dot = e[0] * n[0] + e[1] * n[1]
    if dot <= 0.0 or abs(cross) > ARC_SPLIT * dot:
        angle = math.atan2(cross, dot)
        return angle if angle > 0.0 else angle + 2.0 * math.pi
    angle = 0.0
    a = e
    k = exit_edge + 1
    for _ in range(3):
        c = _corner(k, corners)
        angle += _angle(a, c)
        a = c
        if k % 3 == entry_edge:
            break
        k += 1
    return angle + _angle(a, n)


@jit
def disc_triangle_area(p0x, p0y, p1x, p1y, p2x, p2y, rho2):
    """Area of a counter-clockwise 2-D triangle inside the disc of squared radius ``rho2`` at 0.

    The region's boundary is the parts of the edges inside the disc (chords) and arcs of the
    circle; its area is the fan from the disc centre over it: a straight triangle over each chord
    (``(t2 - t1) * (corner x edge) / 2`` for the part ``t1..t2`` of an edge), a sector of
    ``rho2 * angle / 2`` over each arc (from where the boundary leaves the disc to where it comes
    back, :func:`_arc`). No crossing at all: the disc lies inside the triangle or outside it.
    """
    corners = ((p0x, p0y), (p1x, p1y), (p2x, p2y))
    straight = 0.0
    sectors = 0.0
    first_entry = -1  # an entry met before any exit closes the arc of the last exit
    first = (0.0, 0.0)
    open_exit = -1
    leave = (0.0, 0.0)
    touched = False
    for i in range(3):
        ax, ay = _corner(i, corners)
        bx, by = _corner(i + 1, corners)
        dx, dy = bx - ax, by - ay
        # |a + t d|^2 = rho2  <=>  qa t^2 + 2 qb t + qc = 0
        qa = dx * dx + dy * dy
        qb = dx * ax + dy * ay
        qc = ax * ax + ay * ay - rho2
        a_in = qc <= 0.0
        b_in = bx * bx + by * by <= rho2
        if a_in and b_in:
            straight += ax * dy - ay * dx
            touched = True
            continue
        if not qa > 0.0:
            continue  # a point outside
        disc = qb * qb - qa * qc
        if a_in or b_in:
            disc = max(disc, 0.0)  # one end in, one out: the roots are real
        elif not disc > 0.0:
            continue  # both ends outside, and the line misses the disc (or touches it)
        sq = math.sqrt(disc)
        t1 = 0.0 if a_in else min(max((-qb - sq) / qa, 0.0), 1.0)
        t2 = 1.0 if b_in else min(max((-qb + sq) / qa, 0.0), 1.0)
        if not a_in and not b_in and not (0.0 < t1 < t2 < 1.0):
            continue  # both ends outside and the chord is not between them
        straight += (t2 - t1) * (ax * dy - ay * dx)
        touched = True
        if not a_in:  # enters at t1
            enter = (ax + t1 * dx, ay + t1 * dy)
            if open_exit >= 0:
                sectors += _arc(leave, open_exit, enter, i, corners)
                open_exit = -1
            elif first_entry < 0:
                first_entry, first = i, enter
        if not b_in:  # leaves at t2
            leave = (ax + t2 * dx, ay + t2 * dy)
            open_exit = i
    if open_exit >= 0 and first_entry >= 0:
        sectors += _arc(leave, open_exit, first, first_entry, corners)
    if not touched:
        # no corner inside and no edge through the disc: the disc is inside the triangle or apart
        inside = ((p0x * p1y - p0y * p1x) >= 0.0 and (p1x * p2y - p1y * p2x) >= 0.0
                  and (p2x * p0y - p2y * p0x) >= 0.0)
        return math.pi * rho2 if inside else 0.0
    return 0.5 * (straight + rho2 * sectors)


# ---------------------------------------------------------------------------- a triangle in 3-D
@jit
def _arc3(e, f, plane, c, g, corners):
    """Angle in (0, 2 pi) of the counter-clockwise arc from the exit point e to the entry point f.

    :func:`_arc` for 3-D offsets from the ball centre of points of a plane ``(n, h2)`` (unit normal
    n, squared distance h2): the in-plane dot product is ``e . f - h2``, the cross product
    ``n . (e x f)``. Where one ``atan2`` cannot tell an angle near 0 from one near 2 pi, the fan over
    the outside corners between them (``corners`` of them: c, then g) is summed instead.
    """
    n, h2 = plane
    cross = _triple(n, e, f)
    dot = dot3(e, f) - h2
    if dot <= 0.0 or abs(cross) > ARC_SPLIT * dot:
        angle = math.atan2(cross, dot)
        return angle if angle > 0.0 else angle + 2.0 * math.pi
    angle = math.atan2(_triple(n, e, c), dot3(e, c) - h2)
    if corners == 2:
        angle += math.atan2(_triple(n, c, g), dot3(c, g) - h2)
        c = g
    return angle + math.atan2(_triple(n, c, f), dot3(c, f) - h2)


@jit
def _two_inside(i, qi, j, k, plane, radius2, twice_area, tp):
    """Twice the area inside the ball of a triangle (i, j, k), counter-clockwise about the plane's
    normal, whose corners i and j are inside (offsets from the centre; ``qi`` the squared length of i).

    The boundary inside is i -> j -> p (where j -> k leaves, at ``tp``: :func:`exit_fraction`) and q -> i
    (where k -> i comes back), closed by the arc p -> q: the whole triangle's fan less the parts of
    the two edges beyond the circle, plus the sector of the arc.
    """
    n, h2 = plane
    tq = 1.0 - exit_fraction(i, qi, k, radius2)  # k -> i enters where i -> k leaves
    p = _along(j, k, tp)
    q = _along(k, i, tq)
    straight = twice_area - (1.0 - tp) * _triple(n, j, k) - tq * _triple(n, k, i)
    rho2 = radius2 - h2
    return straight + rho2 * _arc3(p, q, plane, k, k, 1)


@jit
def _one_inside(i, qi, j, qj, k, plane, radius2, tp, tk):
    """Twice the area inside the ball of a triangle (i, j, k), counter-clockwise about the plane's
    normal, whose only corner inside is i (``qi``, ``qj``: the squared lengths of i and j).

    The boundary inside leaves along i -> j at p (at ``tp``: :func:`exit_fraction`) and comes back along
    k -> i at q (where i -> k leaves, at ``tk``); the edge j -> k, both ends outside, may pass
    through the disc between them (a second chord, two arcs).
    """
    n, h2 = plane
    tq = 1.0 - tk
    p = _along(i, j, tp)
    q = _along(k, i, tq)
    straight = tp * _triple(n, i, j) + (1.0 - tq) * _triple(n, k, i)
    rho2 = radius2 - h2
    dx, dy, dz = k[0] - j[0], k[1] - j[1], k[2] - j[2]
    qa = dx * dx + dy * dy + dz * dz
    qb = dx * j[0] + dy * j[1] + dz * j[2]
    disc = qb * qb - qa * (qj - radius2)
    # the line meets the sphere (disc > 0) nearest the centre between j and k (0 < -qb < qa):
    # otherwise both roots fall outside (0, 1) and the test below would fail after a square root
    if disc > 0.0 and 0.0 < -qb < qa:
        sq = math.sqrt(disc)
        t1 = min(max((-qb - sq) / qa, 0.0), 1.0)
        t2 = min(max((-qb + sq) / qa, 0.0), 1.0)
        if 0.0 < t1 < t2 < 1.0:  # j -> k enters at t1 and leaves at t2
            straight += (t2 - t1) * _triple(n, j, k)
            sectors = _arc3(p, _along(j, k, t1), plane, j, j, 1) + _arc3(_along(j, k, t2), q, plane, k, k, 1)
            return straight + rho2 * sectors
    return straight + rho2 * _arc3(p, q, plane, j, k, 2)


@jit
def _face_plane(vector_area, area, f, a):
    """The plane of face f as :func:`_arc3` takes it, ``(unit normal, h2)``, from a corner's offset a."""
    return _plane((vector_area[f, 0], vector_area[f, 1], vector_area[f, 2]), area[f], a)


@jit
def _plane(vector_area, area, a):
    """:func:`_face_plane` of a face's vector area (3-tuple) and area."""
    inv = 1.0 / area
    n = (vector_area[0] * inv, vector_area[1] * inv, vector_area[2] * inv)
    h = a[0] * n[0] + a[1] * n[1] + a[2] * n[2]
    return n, h * h


@jit
def face_in_ball_area(mesh, f, centre, radius2):
    """Exact area of triangle f inside the ball of squared radius ``radius2`` around ``centre``.

    Parameters
    ----------
    mesh : BallMesh
        The triangles, the coordinates and the face areas (area > 0: callers skip degenerate faces):
        :class:`curv.estimators._ball_mesh.BallMesh`.
    f : int
        The triangle.
    centre : 3-tuple of float
    radius2 : float

    Notes
    -----
    One test decides most faces: all three corners inside the (convex) ball, the whole area.
    Otherwise the face crosses the sphere, and its part inside is the triangle clipped to the disc
    where the ball meets its plane. With one or two corners inside (every face a support reaches:
    it has a corner in the support) the boundary inside is known from which corners are in, and
    it is summed directly in 3-D, with offsets from the centre (the fan of
    :func:`disc_triangle_area`: chords and arcs; no frame of the face, one ``atan2`` per arc).
    A face with no corner inside is clipped by :func:`disc_triangle_area` in a frame of the face.
    """
    a0 = offset(mesh, mesh.tri[f, 0], centre)
    a1 = offset(mesh, mesh.tri[f, 1], centre)
    a2 = offset(mesh, mesh.tri[f, 2], centre)
    q0, q1, q2 = dot3(a0, a0), dot3(a1, a1), dot3(a2, a2)
    in0, in1, in2 = q0 <= radius2, q1 <= radius2, q2 <= radius2
    if in0 and in1 and in2:
        return mesh.area[f]
    plane = _face_plane(mesh.vector_area, mesh.area, f, a0)
    n, h2 = plane
    if not radius2 - h2 > 0.0:
        return 0.0  # the plane misses the ball (or touches it)
    inside = int(in0) + int(in1) + int(in2)
    if inside == 2:
        twice = 2.0 * mesh.area[f]
        if not in0:
            part = _two_inside(a1, q1, a2, a0, plane, radius2, twice, exit_fraction(a2, q2, a0, radius2))
        elif not in1:
            part = _two_inside(a2, q2, a0, a1, plane, radius2, twice, exit_fraction(a0, q0, a1, radius2))
        else:
            part = _two_inside(a0, q0, a1, a2, plane, radius2, twice, exit_fraction(a1, q1, a2, radius2))
        part *= 0.5
    elif inside == 1:
        if in0:
            part = _one_inside(a0, q0, a1, q1, a2, plane, radius2, exit_fraction(a0, q0, a1, radius2),
                               exit_fraction(a0, q0, a2, radius2))
        elif in1:
            part = _one_inside(a1, q1, a2, q2, a0, plane, radius2, exit_fraction(a1, q1, a2, radius2),
                               exit_fraction(a1, q1, a0, radius2))
        else:
            part = _one_inside(a2, q2, a0, q0, a1, plane, radius2, exit_fraction(a2, q2, a0, radius2),
                               exit_fraction(a2, q2, a1, radius2))
        part *= 0.5
    else:
        # frame of the face: u along corner 0 -> 1, v = n x u; the corners' in-plane coordinates
        # relative to the foot are their offsets from the centre dotted with u and v
        ux, uy, uz = a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2]
        inv = 1.0 / math.sqrt(ux * ux + uy * uy + uz * uz)
        u = (ux * inv, uy * inv, uz * inv)
        v = (n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0])
        part = disc_triangle_area(dot3(a0, u), dot3(a0, v), dot3(a1, u), dot3(a1, v), dot3(a2, u), dot3(a2, v),
                                  radius2 - h2)
    return part if math.isfinite(part) else 0.0


@jit
def crossing_area(face, v, w, u, tp, tu, radius2):
    """Exact area inside the ball of a triangle (v, w, u) whose corner v is inside and w outside.

    Parameters
    ----------
    face : (vector area 3-tuple, area)
        The triangle's row of :attr:`curv.Mesh.face_vector_areas` and its area
        (:attr:`curv.Mesh.face_areas`); counter-clockwise (v, w, u): w follows v in it.
    v, w, u : (offset 3-tuple, squared length)
        The corners' offsets from the ball's centre and their squared lengths (v's at most
        ``radius2``, w's above it).
    tp, tu : float
        Where v -> w and, if u is outside, v -> u leave the ball (:func:`exit_fraction`): the caller
        has them for those edges already (``tu`` is not read when u is inside).

    Notes
    -----
    The same boundary as :func:`face_in_ball_area`'s for a face with one or two corners inside,
    without its three-way test of which corners are in: u decides it.
    """
    (a, qv), (b, qw), (c, qu) = v, w, u
    vector_area, area = face
    plane = _plane(vector_area, area, a)
    if not radius2 - plane[1] > 0.0:
        return 0.0
    if qu <= radius2:
        part = _two_inside(c, qu, a, b, plane, radius2, 2.0 * area, tp)
    else:
        part = _one_inside(a, qv, b, qw, c, plane, radius2, tp, tu)
    part *= 0.5
    return part if math.isfinite(part) else 0.0
