"""Cohen-Steiner & Morvan (2003): the normal-cycle curvature tensor averaged over a ball (R1-R4).

For vertex p and the ball B of radius ``r(p)`` around it (``k * mesh.longest_edge[p]`` at range
Rk, or a fixed radius: :func:`curv.ranges.ball_radii`)::

    T(p) = 1 / area(B ∩ mesh) * sum_e beta(e) |e ∩ B| ê êᵀ

with ``beta(e)`` the signed dihedral angle of edge e (positive on convex edges for outward normals),
``|e ∩ B|`` the exact length of the edge inside the ball and ê its unit direction. The eigenvector
of T closest to the vertex normal is dropped; the other two eigenvalues are the principal
curvatures, each with the *other* eigenvector as its direction (the edge tensor of a cylinder has
its eigenvalue 1/r along the axis, the direction of zero curvature).

What is approximated
--------------------
The edges and faces considered are those touching p or a vertex of its support
(:func:`curv.neighbourhood.ball_support`: vertices reachable from p along edges without leaving
B). Edges and faces whose vertices all lie outside that support are ignored even when they graze B
(e.g. a long edge passing through the rim of the ball, or a part of the surface that re-enters the
ball without a path inside it). Everything else is exact: ``|e ∩ B|`` is the segment/sphere
intersection and ``area(B ∩ face)`` the exact area of the triangle within the disc
``B ∩ plane of the face`` (circular sectors plus triangles, per edge).

How it runs
-----------
One parallel kernel per chunk of vertices (:func:`curv.jit.iter_chunks`); per vertex it searches
the support and visits every edge and face touching it once (per-thread stamps over edges and
faces, like the search's own visited stamps over vertices), so no (centre, edge) pairs are stored.
The per-edge ``beta(e) / |e|`` and the per-face frames and areas are computed once per mesh.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import iter_chunks, jit, jit_parallel, launch, prange, threads
from ..mesh import Mesh
from ..neighbourhood import (QUEUE_START, all_centres, ball_support, blocked_vertices, coordinate_columns,
                             expansion_adjacency, new_scratch)
from ..validity import Reason
from ._small_linalg import sym3_eigen
from .registry import EstimatorSpec, empty_principal, register

__all__ = ["iter_csm", "segment_in_ball", "disc_triangle_area", "triangle_in_ball_area", "face_geometry",
           "face_frames", "face_in_ball_area",
           "edge_beta_scale", "support_flags"]

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


# ---------------------------------------------------------------------------- clipping helpers
@jit
def segment_in_ball(sx, sy, sz, dx, dy, dz, radius2):
    """Fraction of the segment ``s + t d``, t in [0, 1], inside the ball of squared radius ``radius2`` at 0.

    Solves ``|s + t d|^2 = radius2`` for t and clips the root interval to [0, 1]; 0 when the line
    misses the ball.
    """
    a = dx * dx + dy * dy + dz * dz
    b = dx * sx + dy * sy + dz * sz
    c = sx * sx + sy * sy + sz * sz - radius2
    disc = b * b - a * c
    if not (disc > 0.0 and a > 0.0):
        return 0.0
    sq = math.sqrt(disc)
    t1 = min(max((-b - sq) / a, 0.0), 1.0)
    t2 = min(max((-b + sq) / a, 0.0), 1.0)
    return t2 - t1


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


@jit
def triangle_in_ball_area(ox, oy, oz, radius2, ex, ey, ez, fx, fy, fz, nx, ny, nz):
    """Exact area of a triangle inside a ball: triangle ∩ (ball ∩ plane of the triangle).

    Parameters
    ----------
    ox, oy, oz : float
        Ball centre minus corner 0 of the triangle.
    radius2 : float
        Squared ball radius.
    ex, ey, ez, fx, fy, fz : float
        Corners 1 and 2 minus corner 0.
    nx, ny, nz : float
        Unit normal of the triangle (``e x f`` direction).

    Returns
    -------
    float
        The area; 0 where the plane misses the ball.
    """
    # frame of the face: u along corner 0 -> 1, v = n x u; corner 1 is (x1, 0), corner 2 (x2, y2)
    x1 = math.sqrt(ex * ex + ey * ey + ez * ez)
    ux, uy, uz = ex / x1, ey / x1, ez / x1
    vx = ny * uz - nz * uy
    vy = nz * ux - nx * uz
    vz = nx * uy - ny * ux
    x2 = fx * ux + fy * uy + fz * uz
    y2 = fx * vx + fy * vy + fz * vz
    # foot of the centre (cu, cv) and its height h over the plane: the disc has radius^2 r^2 - h^2
    cu = ox * ux + oy * uy + oz * uz
    cv = ox * vx + oy * vy + oz * vz
    h = ox * nx + oy * ny + oz * nz
    rho2 = radius2 - h * h
    if not rho2 > 0.0:
        return 0.0
    return disc_triangle_area(-cu, -cv, x1 - cu, -cv, x2 - cu, y2 - cv, rho2)


# ---------------------------------------------------------------------------- eigen
@jit
def _principal_from_normal_cycle(tensor, nx, ny, nz, vectors, out):
    """Curvatures and directions of a normal-cycle tensor T at a vertex with unit normal n.

    Drops the eigenvector closest to n; of the other two (ascending), each eigenvector is the
    principal direction of the *other* eigenvalue. ``tensor`` (3, 3) is overwritten, ``vectors``
    (4, 3) is scratch for :func:`sym3_eigen`. Writes ``out[:] = ka, kb, da (3), db (3)`` with
    ``ka <= kb``, ``db`` the tangent-projected eigenvector of ka and ``da = n x db``.
    """
    sym3_eigen(tensor, vectors)  # vectors[:3, j]: eigenvector of the eigenvalue vectors[3, j]
    drop = 0
    best = -1.0
    for j in range(3):
        along = abs(vectors[0, j] * nx + vectors[1, j] * ny + vectors[2, j] * nz)
        if along > best:
            best = along
            drop = j
    ia = 1 if drop == 0 else 0
    ib = 1 if drop == 2 else 2
    bx, by, bz = vectors[0, ia], vectors[1, ia], vectors[2, ia]
    dn = bx * nx + by * ny + bz * nz
    bx -= dn * nx
    by -= dn * ny
    bz -= dn * nz
    norm = math.sqrt(bx * bx + by * by + bz * bz)
    bx /= norm
    by /= norm
    bz /= norm
    out[0] = vectors[3, ia]
    out[1] = vectors[3, ib]
    out[2] = ny * bz - nz * by
    out[3] = nz * bx - nx * bz
    out[4] = nx * by - ny * bx
    out[5] = bx
    out[6] = by
    out[7] = bz


# ---------------------------------------------------------------------------- per-mesh arrays
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


def face_frames(mesh: Mesh, face_normal: np.ndarray) -> np.ndarray:
    """(m, 12) per triangle: its frame u, v, n (u along corner 0 -> 1, v = n x u) and its corners in it.

    Columns ``ux uy uz vx vy vz nx ny nz x1 x2 y2``: corner 0 is the origin, corner 1 ``(x1, 0)``,
    corner 2 ``(x2, y2)``. ``face_normal`` is the first output of :func:`face_geometry`. Once per
    mesh, so that clipping a face to a ball needs no square root or division.
    """
    tri = np.ascontiguousarray(mesh.triangles, dtype=np.int64)
    x, y, z = _columns(mesh)
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


@jit_parallel
def _edge_beta_scale(edges, edge_faces, two, x, y, z, face_normal, out):
    for e in prange(edges.shape[0]):
        out[e] = 0.0
        f0, f1 = edge_faces[e, 0], edge_faces[e, 1]
        if not two[e] or f1 < 0:
            continue
        a, b = edges[e, 0], edges[e, 1]
        dx, dy, dz = x[b] - x[a], y[b] - y[a], z[b] - z[a]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        n0x, n0y, n0z = face_normal[f0, 0], face_normal[f0, 1], face_normal[f0, 2]
        n1x, n1y, n1z = face_normal[f1, 0], face_normal[f1, 1], face_normal[f1, 2]
        zero0 = n0x == 0.0 and n0y == 0.0 and n0z == 0.0
        zero1 = n1x == 0.0 and n1y == 0.0 and n1z == 0.0
        if zero0 or zero1 or not length > 0.0:
            continue  # next to a degenerate face: its vertices are invalid anyway
        # beta = signed angle from n0 to n1 about the edge (slot 0: the face where it runs a -> b)
        sx = n0y * n1z - n0z * n1y
        sy = n0z * n1x - n0x * n1z
        sz = n0x * n1y - n0y * n1x
        beta = math.atan2((sx * dx + sy * dy + sz * dz) / length, n0x * n1x + n0y * n1y + n0z * n1z)
        scale = beta / length  # beta |e| ê êᵀ = beta / |e| d dᵀ
        if math.isfinite(scale):
            out[e] = scale


def edge_beta_scale(mesh: Mesh, face_normal: np.ndarray) -> np.ndarray:
    """(e,) ``beta(e) / |e|`` per edge, so that ``beta |e| ê êᵀ = scale * d dᵀ`` with d the edge vector.

    Zero for edges without exactly two faces or next to a degenerate face (their vertices are
    invalid anyway). ``face_normal`` is the first output of :func:`face_geometry`.
    """
    out = np.empty(mesh.edges.shape[0])
    x, y, z = _columns(mesh)
    two = mesh.edge_face_count == 2
    launch(_edge_beta_scale, mesh.edges, mesh.edge_faces, two, x, y, z, face_normal, out)
    return out


def support_flags(mesh: Mesh) -> np.ndarray:
    """(n,) uint8 per-vertex bits a support may hit: border, non-manifold, on a degenerate face."""
    flags = mesh.border_vertices.astype(np.uint8) * BORDER_BIT
    flags |= mesh.nonmanifold_vertices.astype(np.uint8) * NONMANIFOLD_BIT
    degenerate = mesh.degenerate_faces
    if degenerate.any():
        flags[mesh.triangles[degenerate].reshape(-1)] |= DEGENERATE_BIT
    return flags


def _columns(mesh: Mesh):
    return tuple(np.ascontiguousarray(mesh.vertices[:, c]) for c in range(3))


def _csr(matrix) -> tuple[np.ndarray, np.ndarray]:
    return matrix.indptr.astype(np.int64), matrix.indices.astype(np.int64)


# ---------------------------------------------------------------------------- the kernel
@jit_parallel
def _csm_chunk(centres, lo, hi, radius2, indptr, indices, x, y, z, ve_ptr, ve_idx, edges, beta_scale,
               vf_ptr, vf_idx, tri, frames, face_area, flags, other_side, normals,
               vstamps, estamps, fstamps, k1, k2, d1, d2, reason):
    parts = vstamps.shape[0]
    for t in prange(parts):
        queue = np.empty(QUEUE_START, np.int64)
        vectors = np.empty((4, 3))
        tensor = np.empty((3, 3))
        res = np.empty(8)
        vstamp, estamp, fstamp = vstamps[t], estamps[t], fstamps[t]
        for k in range(lo + (t * (hi - lo)) // parts, lo + ((t + 1) * (hi - lo)) // parts):
            p = centres[k]
            mark = p + 1  # the stamps start zeroed
            r2 = radius2[p]
            count, queue = ball_support(p, r2, indptr, indices, x, y, z, vstamp, queue)
            px, py, pz = x[p], y[p], z[p]
            hit = 0
            # T = sum_e beta(e) |e ∩ B| ê êᵀ (upper triangle); area(B ∩ mesh)
            t00 = t01 = t02 = t11 = t12 = t22 = 0.0
            area = 0.0
            for i in range(count):
                v = queue[i]
                hit |= flags[v]
                if other_side[v]:
                    # a crease vertex: its edges and faces are reached from the centre's side, if
                    # they are on it; the crease's own edges are left out
                    continue
                for j in range(ve_ptr[v], ve_ptr[v + 1]):
                    e = ve_idx[j]
                    if estamp[e] == mark:
                        continue
                    estamp[e] = mark
                    s = beta_scale[e]
                    if s == 0.0:
                        continue
                    a, b = edges[e, 0], edges[e, 1]
                    ax, ay, az = x[a] - px, y[a] - py, z[a] - pz
                    dx, dy, dz = x[b] - x[a], y[b] - y[a], z[b] - z[a]
                    bx, by, bz = ax + dx, ay + dy, az + dz
                    frac = 1.0  # both ends in the (convex) ball: all of e
                    if ax * ax + ay * ay + az * az > r2 or bx * bx + by * by + bz * bz > r2:
                        frac = segment_in_ball(ax, ay, az, dx, dy, dz, r2)
                    w = s * frac
                    t00 += w * dx * dx
                    t01 += w * dx * dy
                    t02 += w * dx * dz
                    t11 += w * dy * dy
                    t12 += w * dy * dz
                    t22 += w * dz * dz
                for j in range(vf_ptr[v], vf_ptr[v + 1]):
                    f = vf_idx[j]
                    if fstamp[f] == mark:
                        continue
                    fstamp[f] = mark
                    if face_area[f] == 0.0:
                        continue  # degenerate: flagged at its vertices
                    c0 = tri[f, 0]
                    area += face_in_ball_area(frames, f, px - x[c0], py - y[c0], pz - z[c0], r2, face_area[f])
            nx, ny, nz = normals[p, 0], normals[p, 1], normals[p, 2]
            normal_ok = math.isfinite(nx) and math.isfinite(ny) and math.isfinite(nz)
            singular = not (area > 0.0 and math.isfinite(t00 + t01 + t02 + t11 + t12 + t22))
            if not singular and normal_ok:
                inv = 1.0 / area
                tensor[0, 0], tensor[1, 1], tensor[2, 2] = t00 * inv, t11 * inv, t22 * inv
                tensor[0, 1] = tensor[1, 0] = t01 * inv
                tensor[0, 2] = tensor[2, 0] = t02 * inv
                tensor[1, 2] = tensor[2, 1] = t12 * inv
                _principal_from_normal_cycle(tensor, nx, ny, nz, vectors, res)
                k1[p], k2[p] = res[0], res[1]
                for c in range(3):
                    d1[p, c] = res[2 + c]
                    d2[p, c] = res[5 + c]
                if not (math.isfinite(res[2]) and math.isfinite(res[3]) and math.isfinite(res[4])):
                    singular = True
            reason[p] = support_reason(singular, hit, normal_ok)


def iter_csm(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
             centres: np.ndarray | None = None, features=None):
    """Normal-cycle tensor over the ball of radius ``radii[p]`` around every vertex p.

    Parameters
    ----------
    mesh : Mesh
        Closed, consistently oriented triangle mesh (vertices whose support reaches a border,
        a non-manifold vertex or a degenerate face are marked invalid).
    normals : (n, 3) float64
        Unit vertex normals; they only pick which eigenvector of T is the normal.
    radii : (n,) float64
        Ball radius of every vertex (:func:`curv.ranges.ball_radii` with ``uses_normals=False``).
    chunk : int, optional
        Vertices per kernel call; default adaptive (:func:`curv.jit.iter_chunks`).
    centres : (c,) int64, optional
        The vertices to estimate (default all).
    features : curv.features.FeatureSet, optional
        The ball stops at creases: edges and faces come from the centre's side only, and the
        feature edges' dihedral terms are left out.

    Yields
    ------
    float
        Fraction done (the points where a caller may cancel).

    Returns
    -------
    Principal
        ``k1 <= k2`` as the tensor gives them; ``reason`` BORDER, DEGENERATE, NONMANIFOLD or
        SINGULAR where the estimate is not usable.
    """
    tri = np.ascontiguousarray(mesh.triangles, dtype=np.int64)  # MeshError on polygons
    n = mesh.n_vertices
    centres = all_centres(n, centres)
    x, y, z = coordinate_columns(mesh)
    # the mesh's connectivity may not be built yet: one piece per step, so that cancel stays prompt
    for name in ("degenerate_faces", "face_normals", "edges", "edge_faces", "adjacency", "vertex_edges", "vertex_faces",
                 "border_vertices", "nonmanifold_vertices"):
        getattr(mesh, name)
        yield 0.0
    face_normal, face_area = face_geometry(mesh)
    beta_scale = edge_beta_scale(mesh, face_normal)
    frames = face_frames(mesh, face_normal)
    del face_normal
    flags = support_flags(mesh)
    yield 0.0
    blocked = blocked_vertices(features)
    indptr, indices = expansion_adjacency(mesh, blocked)
    other_side = np.zeros(n, np.bool_) if blocked is None else blocked
    ve_ptr, ve_idx = _csr(mesh.vertex_edges)
    vf_ptr, vf_idx = _csr(mesh.vertex_faces)
    radius2 = np.ascontiguousarray(radii, dtype=np.float64) ** 2
    normals = np.ascontiguousarray(normals, dtype=np.float64)
    edges = np.ascontiguousarray(mesh.edges, dtype=np.int64)
    parts = max(1, min(threads(), centres.size))
    vstamps = new_scratch(n, parts)
    estamps = np.zeros((parts, edges.shape[0]), np.int32)  # vertex ids fit; half the cache lines
    fstamps = np.zeros((parts, tri.shape[0]), np.int32)
    out = empty_principal(n)

    def run(lo: int, hi: int) -> None:
        launch(_csm_chunk, centres, lo, hi, radius2, indptr, indices, x, y, z, ve_ptr, ve_idx, edges, beta_scale,
               vf_ptr, vf_idx, tri, frames, face_area, flags, other_side, normals, vstamps, estamps, fstamps,
               out.k1, out.k2, out.d1, out.d2, out.reason)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return out


register(EstimatorSpec(
    name="csm", title="Cohen-Steiner & Morvan normal cycle", ranges=(1, 2, 3, 4), function=iter_csm,
    triangles_only=True, uses_normals=False, closed_ring=True,
    reference="Cohen-Steiner & Morvan 2003, Restricted Delaunay triangulations and normal cycle",
    summary="signed dihedral angle x clipped edge length x ê êᵀ summed in a ball, over the area in it",
    kernels=(_edge_beta_scale, _face_frames, _csm_chunk),
))
