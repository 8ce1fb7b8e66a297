"""What the ball-clipping estimators (``csm``, ``icc``) share: exact face areas inside a ball, the
reason code of a support from the flags it touched, and the triangles and edges a region reads.

Estimator modules do not import each other (an import-linter contract); shared kernels live in
underscore modules like this one.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit, jit_parallel, launch, prange
from ..core.mesh import Mesh
from ..geometry.neighbourhood import (all_centres, ball_support, blocked_vertices, cached_with_mesh, coordinate_columns,
                                      expansion_adjacency, start_ball_support,
                                      widen_ball_support)
from ..core.jit import jit_inlined
from ..core.validity import precedence

__all__ = ["BORDER_BIT", "NONMANIFOLD_BIT", "DEGENERATE_BIT", "support_reason", "disc_triangle_area", "clipping_inputs",
           "face_in_ball_area", "crossing_area", "exit_fraction", "vertex_bits", "touches", "touched_elements", "element_list",
           "corner_width", "corner_rings", "crossing_scratch", "may_leave", "crossing_faces", "add_row",
           "vertex_normal", "level_radii", "start_ball_support", "widen_ball_support", "add_star_rows",
           "level_mark", "LevelOutputs"]

REGION_WALK_SHARE = 0.05
"""A region of fewer vertices than this share of the mesh walks its supports first, so that the
per-triangle and per-vertex terms are computed only where its supports read them. For a larger
region the walk (a second search per centre) costs more than the terms it saves, and the terms
are computed for the whole mesh (the same values). Measured at R4, one thread, a slab of a torus:
at 1M vertices the walk wins up to 3 % (csm 0.20 s against 0.54 s at 1 %) and loses at 10 %
(1.85 s against 1.72 s); at 12k vertices it already loses at 10 % (0.022 s against 0.019 s)."""

BORDER_BIT, NONMANIFOLD_BIT, DEGENERATE_BIT = 1, 2, 4
"""Bits of what a support may hit: a border or non-manifold vertex (:func:`vertex_bits`), a degenerate triangle."""


@jit
def support_reason(singular, hit, normal_ok):
    """Reason code of an estimate over a ball, from what its support touched.

    ``hit`` holds the flags of the support's vertices (BORDER_BIT, NONMANIFOLD_BIT, DEGENERATE_BIT:
    a degenerate face touches it), in the one precedence (:func:`curv.core.validity.precedence`):
    NONMANIFOLD, then DEGENERATE (also for a missing normal), BORDER, SINGULAR, else OK.
    """
    return precedence(hit & NONMANIFOLD_BIT != 0, hit & DEGENERATE_BIT != 0 or not normal_ok,
                      hit & BORDER_BIT != 0, singular)


@jit
def _angle(ax, ay, bx, by):
    """Signed angle from direction a to direction b, in (-pi, pi]."""
    return math.atan2(ax * by - ay * bx, ax * bx + ay * by)


@jit
def _corner(k, p0x, p0y, p1x, p1y, p2x, p2y):
    """Corner ``k % 3`` of the triangle."""
    k = k % 3
    if k == 0:
        return p0x, p0y
    if k == 1:
        return p1x, p1y
    return p2x, p2y


ARC_SPLIT = 1e-3
"""Below this ratio |sin| / cos an arc's angle is near 0 or 2 pi, where one ``atan2`` cannot tell which."""


@jit
def _arc(ex, ey, exit_edge, nx, ny, entry_edge, p0x, p0y, p1x, p1y, p2x, p2y):
    """Angle in (0, 2 pi) of the counter-clockwise arc from the exit point e to the entry point n.

    The triangle's boundary leaves the disc at e (on edge ``exit_edge``) and comes back at n (on
    ``entry_edge``); the arc from e to n closes the part of the triangle inside the disc, so it
    turns counter-clockwise. One ``atan2`` and the side of the chord e -> n (the disc centre lies
    to its right exactly when the arc is longer than pi) give the angle, except where e and n
    nearly coincide (an angle near 0 or 2 pi): there the angles of the fan from e over the outside
    corners to n, each less than pi, are summed.
    """
    cross = ex * ny - ey * nx
    dot = ex * nx + ey * ny
    if dot <= 0.0 or abs(cross) > ARC_SPLIT * dot:
        angle = math.atan2(cross, dot)
        return angle if angle > 0.0 else angle + 2.0 * math.pi
    angle = 0.0
    ax, ay = ex, ey
    k = exit_edge + 1
    for _ in range(3):
        cx, cy = _corner(k, p0x, p0y, p1x, p1y, p2x, p2y)
        angle += _angle(ax, ay, cx, cy)
        ax, ay = cx, cy
        if k % 3 == entry_edge:
            break
        k += 1
    return angle + _angle(ax, ay, nx, ny)


@jit
def disc_triangle_area(p0x, p0y, p1x, p1y, p2x, p2y, rho2):
    """Area of a counter-clockwise 2-D triangle inside the disc of squared radius ``rho2`` at 0.

    The region's boundary is the parts of the edges inside the disc (chords) and arcs of the
    circle; its area is the fan from the disc centre over it: a straight triangle over each chord
    (``(t2 - t1) * (corner x edge) / 2`` for the part ``t1..t2`` of an edge), a sector of
    ``rho2 * angle / 2`` over each arc (from where the boundary leaves the disc to where it comes
    back, :func:`_arc`). No crossing at all: the disc lies inside the triangle or outside it.
    """
    straight = 0.0
    sectors = 0.0
    first_entry = -1  # an entry met before any exit closes the arc of the last exit
    fx = fy = 0.0
    open_exit = -1
    ex = ey = 0.0
    touched = False
    for i in range(3):
        ax, ay = _corner(i, p0x, p0y, p1x, p1y, p2x, p2y)
        bx, by = _corner(i + 1, p0x, p0y, p1x, p1y, p2x, p2y)
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
            nx, ny = ax + t1 * dx, ay + t1 * dy
            if open_exit >= 0:
                sectors += _arc(ex, ey, open_exit, nx, ny, i, p0x, p0y, p1x, p1y, p2x, p2y)
                open_exit = -1
            elif first_entry < 0:
                first_entry, fx, fy = i, nx, ny
        if not b_in:  # leaves at t2
            ex, ey = ax + t2 * dx, ay + t2 * dy
            open_exit = i
    if open_exit >= 0 and first_entry >= 0:
        sectors += _arc(ex, ey, open_exit, fx, fy, first_entry, p0x, p0y, p1x, p1y, p2x, p2y)
    if not touched:
        # no corner inside and no edge through the disc: the disc is inside the triangle or apart
        inside = ((p0x * p1y - p0y * p1x) >= 0.0 and (p1x * p2y - p1y * p2x) >= 0.0
                  and (p2x * p0y - p2y * p0x) >= 0.0)
        return math.pi * rho2 if inside else 0.0
    return 0.5 * (straight + rho2 * sectors)


@jit
def _dot(ax, ay, az, bx, by, bz):
    return ax * bx + ay * by + az * bz


@jit
def _triple(nx, ny, nz, ax, ay, az, bx, by, bz):
    """``n . (a x b)``: for points a, b of a plane with unit normal n, offsets from any point off it,
    the 2-D cross product of their in-plane parts (the offset along n drops out)."""
    return nx * (ay * bz - az * by) + ny * (az * bx - ax * bz) + nz * (ax * by - ay * bx)


@jit
def exit_fraction(ax, ay, az, qa_in, bx, by, bz, radius2):
    """Parameter t in [0, 1] where the segment a -> b (a inside the ball around 0, b outside) leaves it.

    ``qa_in`` is ``|a|^2``. The same root as :func:`disc_triangle_area`'s, in 3-D (the offset of the
    plane drops out of it).
    """
    dx, dy, dz = bx - ax, by - ay, bz - az
    qa = dx * dx + dy * dy + dz * dz
    qb = dx * ax + dy * ay + dz * az
    disc = max(qb * qb - qa * (qa_in - radius2), 0.0)
    return min(max((-qb + math.sqrt(disc)) / qa, 0.0), 1.0)


@jit
def _arc3(ex, ey, ez, fx, fy, fz, nx, ny, nz, h2, cx, cy, cz, gx, gy, gz, corners):
    """Angle in (0, 2 pi) of the counter-clockwise arc from the exit point e to the entry point f.

    :func:`_arc` for 3-D offsets from the ball centre of points of a plane with unit normal n at
    squared distance ``h2``: the in-plane dot product is ``e . f - h2``, the cross product
    ``n . (e x f)``. Where one ``atan2`` cannot tell an angle near 0 from one near 2 pi, the fan over
    the outside corners between them (``corners`` of them: c, then g) is summed instead.
    """
    cross = _triple(nx, ny, nz, ex, ey, ez, fx, fy, fz)
    dot = _dot(ex, ey, ez, fx, fy, fz) - h2
    if dot <= 0.0 or abs(cross) > ARC_SPLIT * dot:
        angle = math.atan2(cross, dot)
        return angle if angle > 0.0 else angle + 2.0 * math.pi
    angle = math.atan2(_triple(nx, ny, nz, ex, ey, ez, cx, cy, cz), _dot(ex, ey, ez, cx, cy, cz) - h2)
    if corners == 2:
        angle += math.atan2(_triple(nx, ny, nz, cx, cy, cz, gx, gy, gz), _dot(cx, cy, cz, gx, gy, gz) - h2)
        cx, cy, cz = gx, gy, gz
    return angle + math.atan2(_triple(nx, ny, nz, cx, cy, cz, fx, fy, fz), _dot(cx, cy, cz, fx, fy, fz) - h2)


@jit
def _two_inside(ix, iy, iz, qi, jx, jy, jz, qj, kx, ky, kz, nx, ny, nz, h2, radius2, twice_area, tp):
    """Twice the area inside the ball of a triangle (i, j, k), counter-clockwise about n, whose
    corners i and j are inside (offsets from the centre; ``qi``, ``qj`` their squared lengths).

    The boundary inside is i -> j -> p (where j -> k leaves, at ``tp``: :func:`exit_fraction`) and q -> i
    (where k -> i comes back), closed by the arc p -> q: the whole triangle's fan less the parts of
    the two edges beyond the circle, plus the sector of the arc.
    """
    tq = 1.0 - exit_fraction(ix, iy, iz, qi, kx, ky, kz, radius2)  # k -> i enters where i -> k leaves
    px, py, pz = jx + tp * (kx - jx), jy + tp * (ky - jy), jz + tp * (kz - jz)
    qx, qy, qz = kx + tq * (ix - kx), ky + tq * (iy - ky), kz + tq * (iz - kz)
    straight = (twice_area - (1.0 - tp) * _triple(nx, ny, nz, jx, jy, jz, kx, ky, kz)
                - tq * _triple(nx, ny, nz, kx, ky, kz, ix, iy, iz))
    rho2 = radius2 - h2
    return straight + rho2 * _arc3(px, py, pz, qx, qy, qz, nx, ny, nz, h2, kx, ky, kz, kx, ky, kz, 1)


@jit
def _one_inside(ix, iy, iz, qi, jx, jy, jz, qj, kx, ky, kz, nx, ny, nz, h2, radius2, tp, tk):
    """Twice the area inside the ball of a triangle (i, j, k), counter-clockwise about n, whose
    only corner inside is i.

    The boundary inside leaves along i -> j at p (at ``tp``: :func:`exit_fraction`) and comes back along
    k -> i at q (where i -> k leaves, at ``tk``); the edge j -> k, both ends outside, may pass
    through the disc between them (a second chord, two arcs).
    """
    tq = 1.0 - tk
    px, py, pz = ix + tp * (jx - ix), iy + tp * (jy - iy), iz + tp * (jz - iz)
    qx, qy, qz = kx + tq * (ix - kx), ky + tq * (iy - ky), kz + tq * (iz - kz)
    straight = tp * _triple(nx, ny, nz, ix, iy, iz, jx, jy, jz) + (1.0 - tq) * _triple(nx, ny, nz, kx, ky, kz,
                                                                                        ix, iy, iz)
    rho2 = radius2 - h2
    dx, dy, dz = kx - jx, ky - jy, kz - jz
    qa = dx * dx + dy * dy + dz * dz
    qb = dx * jx + dy * jy + dz * jz
    disc = qb * qb - qa * (qj - radius2)
    # the line meets the sphere (disc > 0) nearest the centre between j and k (0 < -qb < qa):
    # otherwise both roots fall outside (0, 1) and the test below would fail after a square root
    if disc > 0.0 and 0.0 < -qb < qa:
        sq = math.sqrt(disc)
        t1 = min(max((-qb - sq) / qa, 0.0), 1.0)
        t2 = min(max((-qb + sq) / qa, 0.0), 1.0)
        if 0.0 < t1 < t2 < 1.0:  # j -> k enters at t1 and leaves at t2
            ex, ey, ez = jx + t1 * dx, jy + t1 * dy, jz + t1 * dz
            fx, fy, fz = jx + t2 * dx, jy + t2 * dy, jz + t2 * dz
            straight += (t2 - t1) * _triple(nx, ny, nz, jx, jy, jz, kx, ky, kz)
            sectors = (_arc3(px, py, pz, ex, ey, ez, nx, ny, nz, h2, jx, jy, jz, jx, jy, jz, 1)
                       + _arc3(fx, fy, fz, qx, qy, qz, nx, ny, nz, h2, kx, ky, kz, kx, ky, kz, 1))
            return straight + rho2 * sectors
    return straight + rho2 * _arc3(px, py, pz, qx, qy, qz, nx, ny, nz, h2, jx, jy, jz, kx, ky, kz, 2)


@jit
def face_in_ball_area(tri, f, x, y, z, vector_area, area, px, py, pz, radius2):
    """Exact area of triangle f inside the ball of squared radius ``radius2`` around ``(px, py, pz)``.

    Parameters
    ----------
    tri : (m, 3) int
        Triangles.
    f : int
        The triangle.
    x, y, z : (n,) float64
        Vertex coordinates.
    vector_area, area : (m, 3), (m,) float64
        ``Mesh.face_vector_areas`` and ``Mesh.face_areas`` (area > 0: callers skip degenerate faces).

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
    c0, c1, c2 = tri[f, 0], tri[f, 1], tri[f, 2]
    a0x, a0y, a0z = x[c0] - px, y[c0] - py, z[c0] - pz
    a1x, a1y, a1z = x[c1] - px, y[c1] - py, z[c1] - pz
    a2x, a2y, a2z = x[c2] - px, y[c2] - py, z[c2] - pz
    q0 = a0x * a0x + a0y * a0y + a0z * a0z
    q1 = a1x * a1x + a1y * a1y + a1z * a1z
    q2 = a2x * a2x + a2y * a2y + a2z * a2z
    in0, in1, in2 = q0 <= radius2, q1 <= radius2, q2 <= radius2
    if in0 and in1 and in2:
        return area[f]
    inv = 1.0 / area[f]
    nx, ny, nz = vector_area[f, 0] * inv, vector_area[f, 1] * inv, vector_area[f, 2] * inv
    h = a0x * nx + a0y * ny + a0z * nz
    h2 = h * h
    if not radius2 - h2 > 0.0:
        return 0.0  # the plane misses the ball (or touches it)
    inside = int(in0) + int(in1) + int(in2)
    if inside == 2:
        twice = 2.0 * area[f]
        if not in0:
            part = _two_inside(a1x, a1y, a1z, q1, a2x, a2y, a2z, q2, a0x, a0y, a0z, nx, ny, nz, h2, radius2, twice,
                               exit_fraction(a2x, a2y, a2z, q2, a0x, a0y, a0z, radius2))
        elif not in1:
            part = _two_inside(a2x, a2y, a2z, q2, a0x, a0y, a0z, q0, a1x, a1y, a1z, nx, ny, nz, h2, radius2, twice,
                               exit_fraction(a0x, a0y, a0z, q0, a1x, a1y, a1z, radius2))
        else:
            part = _two_inside(a0x, a0y, a0z, q0, a1x, a1y, a1z, q1, a2x, a2y, a2z, nx, ny, nz, h2, radius2, twice,
                               exit_fraction(a1x, a1y, a1z, q1, a2x, a2y, a2z, radius2))
        part *= 0.5
    elif inside == 1:
        if in0:
            part = _one_inside(a0x, a0y, a0z, q0, a1x, a1y, a1z, q1, a2x, a2y, a2z, nx, ny, nz, h2, radius2,
                               exit_fraction(a0x, a0y, a0z, q0, a1x, a1y, a1z, radius2),
                               exit_fraction(a0x, a0y, a0z, q0, a2x, a2y, a2z, radius2))
        elif in1:
            part = _one_inside(a1x, a1y, a1z, q1, a2x, a2y, a2z, q2, a0x, a0y, a0z, nx, ny, nz, h2, radius2,
                               exit_fraction(a1x, a1y, a1z, q1, a2x, a2y, a2z, radius2),
                               exit_fraction(a1x, a1y, a1z, q1, a0x, a0y, a0z, radius2))
        else:
            part = _one_inside(a2x, a2y, a2z, q2, a0x, a0y, a0z, q0, a1x, a1y, a1z, nx, ny, nz, h2, radius2,
                               exit_fraction(a2x, a2y, a2z, q2, a0x, a0y, a0z, radius2),
                               exit_fraction(a2x, a2y, a2z, q2, a1x, a1y, a1z, radius2))
        part *= 0.5
    else:
        # frame of the face: u along corner 0 -> 1, v = n x u; the corners' in-plane coordinates
        # relative to the foot are their offsets from the centre dotted with u and v
        ux, uy, uz = a1x - a0x, a1y - a0y, a1z - a0z
        inv = 1.0 / math.sqrt(ux * ux + uy * uy + uz * uz)
        ux, uy, uz = ux * inv, uy * inv, uz * inv
        vx, vy, vz = ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux
        part = disc_triangle_area(a0x * ux + a0y * uy + a0z * uz, a0x * vx + a0y * vy + a0z * vz,
                                  a1x * ux + a1y * uy + a1z * uz, a1x * vx + a1y * vy + a1z * vz,
                                  a2x * ux + a2y * uy + a2z * uz, a2x * vx + a2y * vy + a2z * vz, radius2 - h2)
    return part if math.isfinite(part) else 0.0


@jit
def crossing_area(f, vx, vy, vz, qv, wx, wy, wz, qw, ux, uy, uz, qu, tp, tu, vector_area, area, radius2):
    """Exact area inside the ball of a triangle f = (v, w, u) whose corner v is inside and w outside.

    Parameters
    ----------
    f : int
        The triangle, counter-clockwise (v, w, u): w follows v in it.
    vx, vy, vz, wx, wy, wz, ux, uy, uz : float
        The corners' offsets from the ball's centre; ``qv``, ``qw``, ``qu`` their squared lengths
        (``qv <= radius2 < qw``).
    tp, tu : float
        Where v -> w and, if u is outside, v -> u leave the ball (:func:`exit_fraction`): the caller
        has them for those edges already (``tu`` is not read when u is inside).
    vector_area, area : (m, 3), (m,) float64
        ``Mesh.face_vector_areas`` and ``Mesh.face_areas`` (area > 0).

    Notes
    -----
    The same boundary as :func:`face_in_ball_area`'s for a face with one or two corners inside,
    without its three-way test of which corners are in: u decides it.
    """
    inv = 1.0 / area[f]
    nx, ny, nz = vector_area[f, 0] * inv, vector_area[f, 1] * inv, vector_area[f, 2] * inv
    h = vx * nx + vy * ny + vz * nz
    h2 = h * h
    if not radius2 - h2 > 0.0:
        return 0.0
    if qu <= radius2:
        part = _two_inside(ux, uy, uz, qu, vx, vy, vz, qv, wx, wy, wz, nx, ny, nz, h2, radius2, 2.0 * area[f], tp)
    else:
        part = _one_inside(vx, vy, vz, qv, wx, wy, wz, qw, ux, uy, uz, nx, ny, nz, h2, radius2, tp, tu)
    part *= 0.5
    return part if math.isfinite(part) else 0.0


@jit_parallel
def _corner_rings(ids, vc_ptr, vc, tri, after, link):
    for i in prange(ids.size):
        v = ids[i]
        first, last = vc_ptr[v], vc_ptr[v + 1]
        for j in range(first, last):
            h = vc[j]
            f = h // 3
            c = h - 3 * f
            after[j] = tri[f, c + 1 if c < 2 else 0]
        for j in range(first, last):
            h = vc[j]
            f = h // 3
            c = h - 3 * f
            u = tri[f, c - 1 if c > 0 else 2]
            m = -1
            for k in range(first, last):
                if after[k] == u:
                    m = k - first
                    break
            link[j] = m


def corner_rings(mesh: Mesh, ids: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The far end of each corner's outgoing edge and the corner that shares its face's other edge.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    ids : (k,) int64, optional
        Fill only the corners of these vertices (a region's supports); the other entries are unset.

    Returns
    -------
    after : (3 m,) int32 (int64 beyond 2**31 vertices)
        Aligned with ``mesh.vertex_corners[1]``: for corner slot j of vertex v (halfedge v -> w of
        face f), w.
    link : (3 m,) int32
        For the same slot, the slot (counted from v's first) whose ``after`` is u, the third corner
        of f (so the face's edge v -> u is that slot's edge); -1 where there is none (the edge v -> u
        is a border edge). The first such slot where several are (a non-manifold vertex).

    Notes
    -----
    With them :func:`crossing_faces` reads a vertex's ring once: each neighbour's offset from the
    centre, its squared distance and its exit are computed once and shared by the two faces at the
    edge, without looking up the triangles.
    """
    vc_ptr, vc = mesh.vertex_corners
    kind = np.int32 if mesh.n_vertices < 2**31 else np.int64
    after = np.empty(vc.size, kind)
    link = np.empty(vc.size, np.int32)
    launch(_corner_rings, element_list(mesh.n_vertices, ids), vc_ptr, vc, np.ascontiguousarray(mesh.triangles), after,
           link)
    return after, link


@jit
def crossing_scratch(width):
    """Per-thread scratch of :func:`crossing_faces` for vertices of at most ``width`` corners:
    ``(out_h, out_w, out_t, out_area, out_in, ring)``, ``ring`` (5, width) float64."""
    return (np.empty(width, np.int64), np.empty(width, np.int64), np.empty(width), np.empty(width),
            np.empty(width, np.int64), np.empty((5, width)))


@jit
def may_leave(v, px, py, pz, radius, x, y, z, longest):
    """Whether an edge at vertex v may leave the ball of centre (px, py, pz) and radius ``radius``:
    not when ``|v - p| + longest[v] <= radius`` (less rounding). A test cheap enough to run at every
    support vertex before the call of :func:`crossing_faces`."""
    vx, vy, vz = x[v] - px, y[v] - py, z[v] - pz
    reach = radius * (1.0 - 1e-12) - longest[v]
    return not (reach > 0.0 and vx * vx + vy * vy + vz * vz <= reach * reach)


@jit_inlined
def crossing_faces(v, px, py, pz, radius, x, y, z, vc_ptr, vc, after, link, tri, vector_area, area, out_h, out_w,
                   out_t, out_area, out_in, ring):
    """The faces that cross the sphere along a halfedge leaving it from support vertex v, each found
    once (its one halfedge from inside to outside), with what the star sums must trade for them.

    Parameters
    ----------
    v : int
        A vertex inside the ball of centre (px, py, pz) and radius ``radius`` whose edges may leave
        it (:func:`may_leave`).
    x, y, z : (n,) float64
        Vertex coordinates.
    vc_ptr, vc : (n+1,), (3 m,) int64
        :attr:`curv.Mesh.vertex_corners`.
    after, link : (3 m,) int
        :func:`corner_rings`.
    tri, vector_area, area :
        The mesh (:func:`crossing_area`).
    out_h, out_w, out_t, out_area, out_in, ring :
        :func:`crossing_scratch`. Entry a of the result: the halfedge ``out_h[a]`` (face
        ``out_h[a] // 3``) leaving towards ``out_w[a]`` at the fraction ``out_t[a]``
        (:func:`exit_fraction`), the face's exact area inside the ball ``out_area[a]``
        (:func:`crossing_area`) and how many of its corners are inside, ``out_in[a]`` (1 or 2: the
        thirds of it a sum of per-vertex thirds holds). ``ring`` holds v's neighbours' offsets,
        squared distances and exits.

    Returns
    -------
    int
        How many faces.

    Notes
    -----
    v's ring is read once: each neighbour w's offset, squared distance and (outside) exit along
    v -> w. A face (v, w, u) leaving along v -> w finds u's in the slot ``link`` names; only where
    v -> u is a border edge are they computed from u itself.
    """
    radius2 = radius ** 2
    vx, vy, vz = x[v] - px, y[v] - py, z[v] - pz
    qv = vx * vx + vy * vy + vz * vz
    first = vc_ptr[v]
    corners = vc_ptr[v + 1] - first
    for a in range(corners):
        w = after[first + a]
        wx, wy, wz = x[w] - px, y[w] - py, z[w] - pz
        qw = wx * wx + wy * wy + wz * wz
        ring[0, a], ring[1, a], ring[2, a], ring[3, a] = wx, wy, wz, qw
        if qw > radius2:
            ring[4, a] = exit_fraction(vx, vy, vz, qv, wx, wy, wz, radius2)
    leaving = 0
    for a in range(corners):
        qw = ring[3, a]
        if not qw > radius2:
            continue
        j = first + a
        h = vc[j]
        f = h // 3
        wx, wy, wz, tp = ring[0, a], ring[1, a], ring[2, a], ring[4, a]
        m = link[j]
        if m >= 0:
            ux, uy, uz, qu = ring[0, m], ring[1, m], ring[2, m], ring[3, m]
            tu = ring[4, m] if qu > radius2 else 0.0
        else:  # v -> u is a border edge: no slot of v has u
            c = h - 3 * f
            u = tri[f, c - 1 if c > 0 else 2]
            ux, uy, uz = x[u] - px, y[u] - py, z[u] - pz
            qu = ux * ux + uy * uy + uz * uz
            tu = exit_fraction(vx, vy, vz, qv, ux, uy, uz, radius2) if qu > radius2 else 0.0
        out_h[leaving] = h
        out_w[leaving] = after[j]
        out_t[leaving] = tp
        out_area[leaving] = crossing_area(f, vx, vy, vz, qv, wx, wy, wz, qw, ux, uy, uz, qu, tp, tu, vector_area, area,
                                          radius2)
        out_in[leaving] = 2 if qu <= radius2 else 1
        leaving += 1
    return leaving


@jit
def add_star_rows(queue, lo, hi, border, nonmanifold, clean, star, hit, exact, sums):
    """Add the support rows ``queue[lo:hi]`` (:func:`~curv.geometry.neighbourhood.widen_ball_support`:
    the vertices a level added) to the support's flags and star sums.

    Parameters
    ----------
    queue : (>= hi,) int64
    lo, hi : int
    border, nonmanifold, clean : (n,) bool
    star : (n, K) float64
        Per-vertex shares of the elements around each vertex, exact for the elements inside the ball.
    hit : int
        The :func:`vertex_bits` of ``queue[:lo]``.
    exact : bool
        Every vertex of ``queue[:lo]`` is ``clean``.
    sums : (k,) float64, 7 <= k <= min(K, 9)
        The sum of ``star[v, :k]`` over ``queue[:lo]`` while ``exact``; added to in queue order,
        row by row (each row one cache line or two), every column in a register of its own.
        From the first vertex that is not clean it is no longer read (the caller walks face by face).

    Returns
    -------
    hit, exact :
        For ``queue[:hi]``.
    """
    for i in range(lo, hi):
        v = queue[i]
        hit |= vertex_bits(v, border, nonmanifold)
        if not clean[v]:
            exact = False
    if exact:
        k = sums.size
        s0, s1, s2, s3, s4, s5, s6 = sums[0], sums[1], sums[2], sums[3], sums[4], sums[5], sums[6]
        s7 = sums[7] if k > 7 else 0.0
        s8 = sums[8] if k > 8 else 0.0
        for i in range(lo, hi):
            v = queue[i]
            s0 += star[v, 0]
            s1 += star[v, 1]
            s2 += star[v, 2]
            s3 += star[v, 3]
            s4 += star[v, 4]
            s5 += star[v, 5]
            s6 += star[v, 6]
            if k > 7:
                s7 += star[v, 7]
                if k > 8:
                    s8 += star[v, 8]
        sums[0], sums[1], sums[2], sums[3], sums[4], sums[5], sums[6] = s0, s1, s2, s3, s4, s5, s6
        if k > 7:
            sums[7] = s7
        if k > 8:
            sums[8] = s8
    return hit, exact


@jit
def level_mark(p, level, levels):
    """The face (and edge) stamp of centre p's walk at ``level`` of ``levels`` radii: a new mark per
    level (``p + 1`` with one level)."""
    return p * levels + level + 1


def level_radii(radii: np.ndarray) -> np.ndarray:
    """``radii`` as (levels, n) float64, C-contiguous: a (n,) array is one level."""
    radii = np.asarray(radii, dtype=np.float64)
    return np.ascontiguousarray(radii[None] if radii.ndim == 1 else radii)


class LevelOutputs:
    """A clipping kernel's outputs for ``levels`` radii: ``k1, k2`` (levels, n), ``d1, d2``
    (levels, n, 3), ``reason`` (levels, n) uint8, uninitialised (the kernel writes every centre's
    rows); :meth:`principal` is one level's :class:`~curv.core.result.Principal` (views)."""

    def __init__(self, levels: int, n: int):
        self.k1, self.k2 = np.empty((levels, n)), np.empty((levels, n))
        self.d1, self.d2 = np.empty((levels, n, 3)), np.empty((levels, n, 3))
        self.reason = np.empty((levels, n), np.uint8)

    def principal(self, level: int):
        from ..core.result import Principal

        return Principal(k1=self.k1[level], k2=self.k2[level], d1=self.d1[level], d2=self.d2[level],
                         reason=self.reason[level])


@jit
def add_row(sums, weight, rows, r):
    """``sums += weight * rows[r, :sums.size]``."""
    for c in range(sums.size):
        sums[c] += weight * rows[r, c]


@jit
def vertex_normal(normals, p):
    """Row p of ``normals`` and whether it is finite: ``(nx, ny, nz, ok)``."""
    nx, ny, nz = normals[p, 0], normals[p, 1], normals[p, 2]
    return nx, ny, nz, math.isfinite(nx) and math.isfinite(ny) and math.isfinite(nz)



@jit
def vertex_bits(v, border, nonmanifold):
    """The flags vertex v adds to a support it lies in (BORDER_BIT, NONMANIFOLD_BIT)."""
    bits = 0
    if border[v]:
        bits |= BORDER_BIT
    if nonmanifold[v]:
        bits |= NONMANIFOLD_BIT
    return bits


@jit
def touches(crease, tri, f):
    """Whether triangle f has a corner on a crease (``crease`` (n,) bool)."""
    return crease[tri[f, 0]] or crease[tri[f, 1]] or crease[tri[f, 2]]


@jit
def _grow(a, count):
    if count < a.size:
        return a
    b = np.empty(2 * a.size, a.dtype)
    b[:a.size] = a
    return b


@jit
def _touched(centres, radii, indptr, indices, x, y, z, vc_ptr, vc, with_edges, halfedge_edge, vstamp, queue,
             vseen, fseen, eseen):
    vertices = np.empty(64, np.int64)
    faces = np.empty(64, np.int64)
    edges = np.empty(64, np.int64)
    nv = nf = ne = 0
    for p in centres:
        count, queue = ball_support(p, radii[p] ** 2, indptr, indices, x, y, z, vstamp, queue)
        for i in range(count):
            v = queue[i]
            if not vseen[v]:
                vseen[v] = True
                vertices = _grow(vertices, nv)
                vertices[nv] = v
                nv += 1
            for j in range(vc_ptr[v], vc_ptr[v + 1]):
                h = vc[j]
                f = h // 3
                if not fseen[f]:
                    fseen[f] = True
                    faces = _grow(faces, nf)
                    faces[nf] = f
                    nf += 1
                if not with_edges:
                    continue
                for g in (h, 3 * f + (h + 2) % 3):  # the edges out of and into v
                    e = halfedge_edge[g]
                    if e >= 0 and not eseen[e]:
                        eseen[e] = True
                        edges = _grow(edges, ne)
                        edges[ne] = e
                        ne += 1
    return vertices[:nv], faces[:nf], edges[:ne]


def touched_elements(mesh: Mesh, centres: np.ndarray, radii: np.ndarray, indptr: np.ndarray,
                     indices: np.ndarray, *, edges: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The vertices, triangles (and edges) the supports of ``centres`` touch: what a region's estimate reads.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    centres : (c,) int64
        The vertices to estimate.
    radii : (n,) float64
        Ball radius of every vertex.
    indptr, indices : (n+1,), (a,) int64
        :func:`curv.geometry.neighbourhood.expansion_adjacency`.
    edges : bool
        Collect the edges too (they need the mesh's edge table).

    Returns
    -------
    vertices : (j,) int64
        Every vertex of a support, once.
    faces : (k,) int64
        Every triangle with a corner in a support, once.
    edges : (l,) int64 or None
        Every edge of those corners, once (None unless asked).

    Notes
    -----
    A sequential walk over the supports: its cost follows the region, and the seen-masks are
    zeroed pages that only the region touches.
    """
    n = mesh.n_vertices
    vc_ptr, vc = mesh.vertex_corners
    halfedge = mesh.halfedge_edge if edges else np.empty(0, np.int64)
    eseen = np.zeros(mesh.edges.shape[0] if edges else 0, np.bool_)
    vertices, faces, edge_ids = _touched(centres, radii, indptr, indices, *coordinate_columns(mesh), vc_ptr, vc,
                                         edges, halfedge, np.zeros(n, np.int64), np.empty(n, np.int64),
                                         np.zeros(n, np.bool_), np.zeros(mesh.n_faces, np.bool_), eseen)
    return vertices, faces, (edge_ids if edges else None)


def clipping_inputs(mesh: Mesh, centres: np.ndarray | None, radii: np.ndarray, features):
    """What ``csm`` and ``icc`` read before their per-vertex sums, a generator: it yields 0.0 after
    each piece of connectivity the mesh builds (one per step, so that cancel stays prompt).

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh (:class:`~curv.core.errors.MeshError` on polygons).
    centres : (c,) int64 or None
        The vertices to estimate (None: all).
    radii : (n,) or (levels, n) float64
        Ball radius of every vertex, or of every vertex at each level (ascending per vertex).
    features : curv.core.features.FeatureSet or None
        The supports stop at its vertices.

    Returns
    -------
    tri : (m, 3) int64
    centres : (c,) int64
    x, y, z : (n,) float64
    indptr, indices : (n+1,), (a,) int64
        :func:`~curv.geometry.neighbourhood.expansion_adjacency` through the vertices not blocked.
    cut : bool
        Some vertices are blocked (creases).
    crease : (n,) bool
        The blocked vertices.
    radii : (levels, n) float64
        Contiguous (:func:`level_radii`).
    touched : tuple
        For a region of fewer than :data:`REGION_WALK_SHARE` of the vertices, :func:`touched_elements`
        without the edges; else ``(None, None, None)`` (every triangle's and vertex's terms).
    """
    tri = np.ascontiguousarray(mesh.triangles)
    n = mesh.n_vertices
    region = centres is not None
    centres = all_centres(n, centres)
    for name in ("degenerate_faces", "face_vector_areas", "adjacency", "vertex_corners", "border_vertices",
                 "nonmanifold_vertices"):
        getattr(mesh, name)
        yield 0.0
    x, y, z = coordinate_columns(mesh)
    blocked = blocked_vertices(features)
    indptr, indices = expansion_adjacency(mesh, blocked)
    crease = np.zeros(n, np.bool_) if blocked is None else blocked
    radii = level_radii(radii)
    small = region and centres.size < REGION_WALK_SHARE * n
    # the widest level's supports hold every narrower one's
    touched = touched_elements(mesh, centres, radii[-1], indptr, indices, edges=False) if small else (None, None, None)
    return tri, centres, x, y, z, indptr, indices, blocked is not None, crease, radii, touched


def element_list(count: int, touched: np.ndarray | None) -> np.ndarray:
    """(k,) int64 the elements a per-face or per-edge pass must compute: ``touched``, or all ``count``."""
    return np.arange(count, dtype=np.int64) if touched is None else touched


def corner_width(mesh: Mesh) -> int:
    """The most corners at one vertex (at least 1): the length of a kernel's per-thread row for a
    vertex's corners. Cached with the mesh, so a region's estimate does no O(n) work for it."""
    def build():
        indptr = mesh.vertex_corners[0]
        return max(1, int(np.diff(indptr).max(initial=0)))

    return cached_with_mesh(mesh, "corner width", build)
