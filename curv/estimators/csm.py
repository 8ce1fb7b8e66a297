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
from ._ball_clipping import (BORDER_BIT, DEGENERATE_BIT, NONMANIFOLD_BIT, disc_triangle_area, face_frames,
                             face_geometry, face_in_ball_area, face_frames_kernel, support_flags, support_reason)
from ._small_linalg import sym3_eigen
from .registry import EstimatorSpec, empty_principal, register

__all__ = ["iter_csm", "segment_in_ball", "edge_beta_scale"]


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
    x, y, z = coordinate_columns(mesh)
    two = mesh.edge_face_count == 2
    launch(_edge_beta_scale, mesh.edges, mesh.edge_faces, two, x, y, z, face_normal, out)
    return out


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
    extra_bytes_per_unit=500.0,  # at 1M vertices csm peaked 0.96 GB above the fits (benchmarks/bench_estimators.py)
    triangles_only=True, uses_normals=False, closed_ring=True,
    reference="Cohen-Steiner & Morvan 2003, Restricted Delaunay triangulations and normal cycle",
    summary="signed dihedral angle x clipped edge length x ê êᵀ summed in a ball, over the area in it",
    kernels=(_edge_beta_scale, face_frames_kernel, _csm_chunk),
))
