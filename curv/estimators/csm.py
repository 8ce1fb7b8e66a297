"""Cohen-Steiner & Morvan (2003): the normal-cycle curvature tensor averaged over a ball (R1-R4).

For vertex p and the ball B of radius ``k * mesh.longest_edge[p]`` around it::

    T(p) = 1 / area(B ∩ mesh) * sum_e beta(e) |e ∩ B| ê êᵀ

with ``beta(e)`` the signed dihedral angle of edge e (positive on convex edges for outward normals),
``|e ∩ B|`` the exact length of the edge inside the ball and ê its unit direction. The eigenvector
of T closest to the vertex normal is dropped; the other two eigenvalues are the principal
curvatures, each with the *other* eigenvector as its direction (the edge tensor of a cylinder has
its eigenvalue 1/r along the axis, the direction of zero curvature).

What is approximated
--------------------
The edges and faces considered are those touching p or a vertex of its Rk support
(:func:`curv.neighbourhood.iter_neighbourhoods`: vertices reachable from p along edges without
leaving B). Edges and faces whose vertices all lie outside that support are ignored even when they
graze B (e.g. a long edge passing through the rim of the ball, or a part of the surface that
re-enters the ball without a path inside it). Everything else is exact: ``|e ∩ B|`` is the
segment/sphere intersection and ``area(B ∩ face)`` the exact area of the triangle within the disc
``B ∩ plane of the face`` (circular sectors plus triangles, per edge).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from .._legacy_neighbourhood import Neighbourhood, segment_ids
from ..validity import Reason
from .registry import EstimatorSpec, iter_blockwise, register

__all__ = ["iter_csm", "edge_tensors", "segment_ball", "triangle_ball_area"]

PAIR_CHUNK = 32768
"""(centre, edge or face) pairs clipped per vectorised step: temporaries stay in cache."""

_SYM = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
"""The six entries (i, j) of a symmetric 3x3 tensor stored as a row of 6."""


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def edge_tensors(mesh: Mesh) -> np.ndarray:
    """``beta(e) * |e| * ê êᵀ`` for every edge, as 6 symmetric entries.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh, consistently oriented.

    Returns
    -------
    (e, 6) float64
        Entries xx, xy, xz, yy, yz, zz; zero rows for edges without exactly two faces or next to a
        degenerate face (their vertices are invalid anyway).
    """
    ef = mesh.edge_faces
    nf = mesh.face_normals
    d = mesh.edge_vectors
    length = mesh.edge_lengths
    two = (mesh.edge_face_count == 2) & (ef[:, 1] >= 0)
    beta = np.zeros(d.shape[0])
    n0, n1 = nf[ef[two, 0]], nf[ef[two, 1]]
    # slot 0 is the face in which the edge runs edges[:, 0] -> edges[:, 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        beta[two] = np.arctan2(_dot(np.cross(n0, n1), d[two]) / length[two], _dot(n0, n1))
        scale = np.where(length > 0, beta / length, 0.0)
    beta[~np.isfinite(beta)] = 0.0
    scale[~np.isfinite(scale)] = 0.0
    # beta |e| ê êᵀ = beta / |e| * d dᵀ
    return np.stack([scale * d[:, i] * d[:, j] for i, j in _SYM], axis=1)


def segment_ball(start: np.ndarray, direction: np.ndarray, radius: np.ndarray):
    """Parameter interval of the segments ``start + t * direction``, t in [0, 1], inside a ball.

    Parameters
    ----------
    start : (k, 3) float64
        Segment starts relative to the ball centre.
    direction : (k, 3) float64
        Segment vectors (end - start).
    radius : (k,) float64
        Ball radii.

    Returns
    -------
    t1, t2 : (k,) float64
        ``0 <= t1 <= t2 <= 1``; ``t1 == t2`` where the segment misses the ball.
    """
    a = _dot(direction, direction)
    b = _dot(direction, start)
    c = _dot(start, start) - radius * radius
    disc = b * b - a * c
    hit = (disc > 0) & (a > 0)
    sq = np.sqrt(np.where(hit, disc, 0.0))
    inv = 1.0 / np.where(hit, a, 1.0)
    t1 = np.clip((-b - sq) * inv, 0.0, 1.0)
    t2 = np.clip((-b + sq) * inv, 0.0, 1.0)
    t1 = np.where(hit, t1, 0.0)
    t2 = np.where(hit, t2, 0.0)
    return t1, t2


def face_frames(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal frame and 2-D corner coordinates of every triangle.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.

    Returns
    -------
    frame : (m, 9) float64
        ``u_f, v_f, n_f`` (unit, right-handed): u_f along the edge from corner 0 to corner 1.
        Zero rows on degenerate faces.
    corners : (m, 3) float64
        ``(x1, x2, y2)``: corner 0 is the frame origin, corner 1 is ``(x1, 0)``, corner 2 is
        ``(x2, y2)`` (``y2 > 0`` for a counter-clockwise triangle).
    """
    tri = mesh.triangles
    v = mesh.vertices
    e0 = np.take(v, tri[:, 1], axis=0) - np.take(v, tri[:, 0], axis=0)
    e2 = np.take(v, tri[:, 2], axis=0) - np.take(v, tri[:, 0], axis=0)
    x1 = np.linalg.norm(e0, axis=1)
    bad = mesh.degenerate_faces | ~(x1 > 0)
    n_f = np.where(bad[:, None], 0.0, np.nan_to_num(mesh.face_normals))
    u_f = e0 / np.where(bad, 1.0, x1)[:, None]
    u_f[bad] = 0.0
    v_f = np.cross(n_f, u_f)
    frame = np.concatenate([u_f, v_f, n_f], axis=1)
    corners = np.stack([x1, _dot(e2, u_f), _dot(e2, v_f)], axis=1)
    return frame, corners


def _sector_angles(ax, ay, bx, by, where: np.ndarray, out: np.ndarray) -> None:
    """Add the signed angle from direction a to direction b to ``out``, at the entries ``where`` only.

    ``arctan2`` costs some 30 ns an entry; most pieces of the clipped fan have no sector (an edge
    end inside the disc), so only the others are evaluated.
    """
    idx = np.flatnonzero(where)
    if idx.size:
        ax, ay, bx, by = (np.take(x, idx) for x in (ax, ay, bx, by))
        out[idx] += np.arctan2(ax * by - ay * bx, ax * bx + ay * by)


def triangle_ball_area(offset: np.ndarray, radius: np.ndarray, frame: np.ndarray,
                       corners: np.ndarray) -> np.ndarray:
    """Exact area of triangles within balls: triangle ∩ (ball ∩ plane of the triangle).

    Works in the plane of each triangle: the ball meets it in a disc around the foot of the
    centre; the area is summed over the three edges as (sector, triangle, sector) pieces of the
    fan from that foot: circular sectors where the edge is outside the disc, a straight triangle
    where it is inside.

    Parameters
    ----------
    offset : (k, 3) float64
        Ball centre minus corner 0 of the triangle.
    radius : (k,) float64
        Ball radii.
    frame, corners : (k, 9), (k, 3) float64
        Rows of :func:`face_frames` for the triangles.

    Returns
    -------
    (k,) float64
        Areas; 0 where the plane misses the ball.
    """
    ox, oy, oz = offset[:, 0], offset[:, 1], offset[:, 2]
    cx, cy, dist = (ox * frame[:, 3 * j] + oy * frame[:, 3 * j + 1] + oz * frame[:, 3 * j + 2] for j in range(3))
    rho2 = radius * radius - dist * dist
    # triangle corners relative to the foot of the centre, counter-clockwise
    px = (-cx, corners[:, 0] - cx, corners[:, 1] - cx)
    py = (-cy, -cy, corners[:, 2] - cy)
    straight = np.zeros_like(cx)
    angle = np.zeros_like(cx)  # all sectors have the radius sqrt(rho2): sum their angles
    for i in range(3):
        ax, ay = px[i], py[i]
        bx, by = px[(i + 1) % 3], py[(i + 1) % 3]
        dx, dy = bx - ax, by - ay
        a = dx * dx + dy * dy
        b = dx * ax + dy * ay
        c = ax * ax + ay * ay - rho2
        disc = b * b - a * c
        hit = (disc > 0) & (a > 0)
        sq = np.sqrt(np.where(hit, disc, 0.0))
        inv = 1.0 / np.where(hit, a, 1.0)
        t1 = np.where(hit, np.clip((-b - sq) * inv, 0.0, 1.0), 0.0)
        t2 = np.where(hit, np.clip((-b + sq) * inv, 0.0, 1.0), 0.0)
        p1x, p1y = ax + t1 * dx, ay + t1 * dy
        p2x, p2y = ax + t2 * dx, ay + t2 * dy
        straight += 0.5 * (p1x * p2y - p1y * p2x)
        # a sector before the chord where the edge starts outside the disc, one after it where it
        # ends outside (a missed edge is one sector from a to b: t1 = t2 = 0)
        _sector_angles(ax, ay, p1x, p1y, t1 > 0, angle)
        _sector_angles(p2x, p2y, bx, by, t2 < 1, angle)
    return np.where(rho2 > 0, straight + 0.5 * rho2 * angle, 0.0)


def _with_centres(nb: Neighbourhood, n: int) -> sp.csr_matrix:
    """(c, n) int32 CSR indicator of each centre's support, the centre itself included."""
    c = nb.size
    indptr = nb.indptr + np.arange(c + 1)
    indices = np.empty(indptr[-1], np.int64)
    first = indptr[:-1]
    indices[first] = nb.vertices
    rest = np.ones(indices.size, bool)
    rest[first] = False
    indices[rest] = nb.indices
    return sp.csr_matrix((np.ones(indices.size, np.int32), indices, indptr), shape=(c, n))


def _row_ids(m: sp.csr_matrix) -> np.ndarray:
    return segment_ids(m.indptr)


class _MeshData:
    """Per-mesh arrays shared by all blocks."""

    def __init__(self, mesh: Mesh):
        self.tensors = edge_tensors(mesh)
        self.frame, self.corners = face_frames(mesh)
        self.vertex_edges = mesh.vertex_edges.astype(np.int32)
        self.vertex_faces = mesh.vertex_faces.astype(np.int32)
        degenerate_at = self.vertex_faces @ mesh.degenerate_faces.astype(np.int32) > 0
        self.flags = np.stack([mesh.border_vertices, mesh.nonmanifold_vertices, degenerate_at],
                              axis=1).astype(np.int32)


def _clipped_edges(mesh: Mesh, nb: Neighbourhood, rows: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Fraction of each edge inside the ball of its row's centre; (k,) for (k,) pairs."""
    v = mesh.vertices
    out = np.empty(rows.size)
    for s in range(0, rows.size, PAIR_CHUNK):
        r, e = rows[s:s + PAIR_CHUNK], edges[s:s + PAIR_CHUNK]
        start = np.take(v, mesh.edges[e, 0], axis=0) - np.take(v, nb.vertices[r], axis=0)
        t1, t2 = segment_ball(start, mesh.edge_vectors[e], nb.radius[r])
        out[s:s + PAIR_CHUNK] = t2 - t1
    return out


def _clipped_faces(mesh: Mesh, nb: Neighbourhood, rows: np.ndarray, faces: np.ndarray, data: "_MeshData"):
    """Area of each face inside the ball of its row's centre; (k,) for (k,) pairs."""
    v = mesh.vertices
    first = mesh.triangles[:, 0]
    out = np.empty(rows.size)
    for s in range(0, rows.size, PAIR_CHUNK):
        r, f = rows[s:s + PAIR_CHUNK], faces[s:s + PAIR_CHUNK]
        offset = np.take(v, nb.vertices[r], axis=0) - np.take(v, first[f], axis=0)
        out[s:s + PAIR_CHUNK] = triangle_ball_area(offset, nb.radius[r], data.frame[f], data.corners[f])
    out[~np.isfinite(out)] = 0.0
    return out


def _block_tensor(mesh: Mesh, nb: Neighbourhood, data: _MeshData):
    """Tensor (c, 6), ball area (c,) and flag hits (c, 3) of one block of centres."""
    support = _with_centres(nb, mesh.n_vertices)
    hits = support @ data.flags  # (c, 3): border, nonmanifold, degenerate-face vertices in the support

    # edges with 2 endpoints in the support are wholly inside the (convex) ball; 1 -> clip
    inc = support @ data.vertex_edges
    inc.sum_duplicates()
    part = np.flatnonzero(inc.data == 1)
    frac = np.ones(inc.data.size)
    frac[part] = _clipped_edges(mesh, nb, _row_ids(inc)[part], inc.indices[part])
    tensor = sp.csr_matrix((frac, inc.indices, inc.indptr), shape=inc.shape) @ data.tensors

    faces_in = support @ data.vertex_faces
    faces_in.sum_duplicates()
    areas = mesh.face_areas[faces_in.indices]
    part = np.flatnonzero(faces_in.data < 3)
    areas[part] = _clipped_faces(mesh, nb, _row_ids(faces_in)[part], faces_in.indices[part], data)
    area = np.bincount(_row_ids(faces_in), weights=areas, minlength=nb.size)
    return tensor, area, hits


def _principal_from_tensor3(tensor: np.ndarray, normals: np.ndarray):
    """Curvatures and directions of (c, 6) normal-cycle tensors at vertices with (c, 3) normals."""
    c = tensor.shape[0]
    full = np.empty((c, 3, 3))
    for col, (i, j) in enumerate(_SYM):
        full[:, i, j] = tensor[:, col]
        full[:, j, i] = tensor[:, col]
    values, vectors = np.linalg.eigh(full)
    along = np.abs(np.einsum("cij,ci->cj", vectors, normals))
    drop = np.argmax(along, axis=1)
    keep = np.sort(np.stack([(drop + 1) % 3, (drop + 2) % 3], axis=1), axis=1)
    idx = np.arange(c)
    ka, kb = values[idx, keep[:, 0]], values[idx, keep[:, 1]]
    # the eigenvector of one eigenvalue is the principal direction of the other
    db = vectors[idx, :, keep[:, 0]]
    db -= _dot(db, normals)[:, None] * normals
    with np.errstate(invalid="ignore", divide="ignore"):
        db /= np.linalg.norm(db, axis=1, keepdims=True)
    da = np.cross(normals, db)
    return ka, kb, da, db


def iter_csm(mesh: Mesh, normals: np.ndarray, k: int, *, block_size: int | None = None):
    """Normal-cycle tensor over the ball of radius ``k`` longest 1-ring edges.

    Parameters
    ----------
    mesh : Mesh
        Closed, consistently oriented triangle mesh (vertices whose support reaches a border,
        a non-manifold vertex or a degenerate face are marked invalid).
    normals : (n, 3) float64
        Unit vertex normals; they only pick which eigenvector of T is the normal.
    k : int
        Range factor: the ball radius in longest-1-ring-edge units.
    block_size : int, optional
        Centre vertices per block.

    Yields
    ------
    float
        Fraction done.

    Returns
    -------
    Principal
    """
    mesh.triangles  # noqa: B018  (raises MeshError on polygons)
    data = _MeshData(mesh)
    normal_ok = np.isfinite(normals).all(axis=1)

    def block_result(nb: Neighbourhood):
        ids = nb.vertices
        tensor, area, hits = _block_tensor(mesh, nb, data)
        singular = ~(area > 0) | ~np.isfinite(tensor).all(axis=1)
        usable = ~singular & normal_ok[ids]
        ka = np.full(ids.size, np.nan)
        kb = np.full(ids.size, np.nan)
        da = np.full((ids.size, 3), np.nan)
        db = np.full((ids.size, 3), np.nan)
        if usable.any():
            scaled = tensor[usable] / area[usable, None]
            ka[usable], kb[usable], da[usable], db[usable] = _principal_from_tensor3(scaled, normals[ids[usable]])
        reason = np.full(ids.size, Reason.OK, np.uint8)
        reason[singular | ~np.isfinite(da).all(axis=1)] = Reason.SINGULAR
        reason[hits[:, 0] > 0] = Reason.BORDER
        reason[(hits[:, 2] > 0) | ~normal_ok[ids]] = Reason.DEGENERATE
        reason[hits[:, 1] > 0] = Reason.NONMANIFOLD
        return ka, kb, da, db, reason

    return (yield from iter_blockwise(mesh, k, block_result, block_size=block_size))


register(EstimatorSpec(
    name="csm", title="Cohen-Steiner & Morvan normal cycle", ranges=(1, 2, 3, 4), function=iter_csm,
    triangles_only=True, uses_normals=False, closed_ring=True,
    reference="Cohen-Steiner & Morvan 2003, Restricted Delaunay triangulations and normal cycle",
    summary="signed dihedral angle x clipped edge length x ê êᵀ summed in a ball, over the area in it",
))
