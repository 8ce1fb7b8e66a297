"""Rusinkiewicz (2004): per-face second fundamental tensors averaged at the vertices (R2 only).

1. Per face, in an orthonormal frame (u_f, v_f) of its plane, the tensor ``W_f`` that maps each of
   the three edge vectors to the difference of the vertex normals along it (our convention
   ``dN = W t``): six equations in (e, f, g), solved by their 3x3 normal equations in closed form.
2. Per corner, the face frame is rotated about ``n_f x N_p`` so that its normal matches the vertex
   normal N_p, and ``W_f`` is re-expressed in the vertex frame (U_p, V_p).
3. Per vertex, the corner tensors are averaged with the corner's mixed Voronoi area as weight.

The eigen-decomposition of the averaged tensor gives the principal curvatures and directions. It
uses the vertex normals of the whole 1-ring, hence range R2.
"""

from __future__ import annotations

import numpy as np

from ..corners import CornerChunk, map_vertex_chunks
from ..frames import principal_from_tensor, solve_sym3, tangent_frames
from ..mesh import Mesh
from ._triangle_corners import TriangleCorners, closed_ring_reasons, cross, dot
from .registry import EstimatorSpec, empty_principal, register

__all__ = ["iter_ru"]

MIN_ROTATION_COS = -1.0 + 1e-9
"""A face whose normal is (almost) opposite the vertex normal has no defined rotation onto it."""


def iter_ru(mesh: Mesh, normals: np.ndarray, k: int, *, block_size: int | None = None):
    """Rusinkiewicz's estimator (``k`` must be 2; ``block_size`` is unused).

    Works corner by corner in cache-sized chunks of vertices on a thread pool
    (:mod:`curv.corners`): every corner solves its face's tensor in a frame of its own (three
    times per face in all, which is cheaper than gathering a stored per-face tensor back) and
    rotates it into its vertex's frame, so chunks need nothing from each other.

    Parameters
    ----------
    mesh : Mesh
        Closed triangle mesh (vertices with an open or non-manifold 1-ring are marked invalid).
    normals : (n, 3) float64
        Unit vertex normals, used for the normal differences and as the vertex frames.
    k : int
        Range; only 2.

    Yields
    ------
    float
        Fraction done.

    Returns
    -------
    Principal
    """
    n = mesh.n_vertices
    out = empty_principal(n)
    if not mesh.is_triangular:
        mesh.triangles  # raises the MeshError that names the polygon sizes
    xyz = tuple(np.ascontiguousarray(mesh.vertices[:, c]) for c in range(3))
    nxyz = tuple(np.ascontiguousarray(normals[:, c]) for c in range(3))
    degenerate_faces = mesh.degenerate_faces
    corner_face = mesh.corner_face
    border_vertices, nonmanifold = mesh.border_vertices, mesh.nonmanifold_vertices
    yield 0.1

    def work(chunk: CornerChunk) -> None:
        rows = slice(chunk.start, chunk.stop)
        tc = TriangleCorners.of(chunk, xyz, degenerate_faces, corner_face)
        ab, ac = tc.ab, tc.ac
        n_a = tuple(chunk.expand(c) for c in nxyz)
        n_b = tuple(np.take(c, chunk.nxt) for c in nxyz)
        n_c = tuple(np.take(c, chunk.prv) for c in nxyz)
        with np.errstate(invalid="ignore", divide="ignore"):
            n_f = tuple(x / tc.twice_area for x in cross(ab, ac))
            u_f = tuple(x / np.sqrt(dot(ab, ab)) for x in ab)
        v_f = cross(n_f, u_f)

        # 1. the face tensor W (dN = W t) from its three edges, in the face frame (u_f, v_f)
        a00, a01, a11, b0, b1, b2 = (np.zeros(ab[0].size) for _ in range(6))
        edges = (ab, tuple(y - x for x, y in zip(ab, ac)), tuple(-x for x in ac))
        dns = (tuple(y - x for x, y in zip(n_a, n_b)), tuple(y - x for x, y in zip(n_b, n_c)),
               tuple(y - x for x, y in zip(n_c, n_a)))
        for edge, dn in zip(edges, dns):
            eu, ev = dot(edge, u_f), dot(edge, v_f)
            nu, nv = dot(dn, u_f), dot(dn, v_f)
            # rows [eu ev 0] -> nu and [0 eu ev] -> nv
            a00 += eu * eu
            a01 += eu * ev
            a11 += eu * eu + ev * ev
            b0 += eu * nu
            b1 += ev * nu + eu * nv
            b2 += ev * nv
        # the 3x3 normal matrix is [[a00, a01, 0], [a01, a11, a01], [0, a01, a22]] with a22 = a11 - a00
        efg, face_singular = solve_sym3(a00, a01, np.zeros_like(a00), a11, a01, a11 - a00, b0, b1, b2)
        finite = np.isfinite(n_a[0]) & np.isfinite(n_b[0]) & np.isfinite(n_c[0])
        bad = face_singular | tc.degenerate | ~finite

        # 2. rotate the face frame onto the vertex normal: R takes n_f to N_a (Rodrigues with the
        # unnormalised axis a = n_f x N_a): R x = c x + a x x + a (a.x) / (1 + c). We need
        # U.(R u_f) = (R^T U).u_f, and R^T is the same formula with -a.
        cos = dot(n_f, n_a)
        opposite = ~(cos > MIN_ROTATION_COS)
        axis = tuple(-x for x in cross(n_f, n_a))
        with np.errstate(invalid="ignore", divide="ignore"):
            inv = np.where(opposite, 0.0, 1.0 / (1.0 + cos))
        nrm = normals[rows]
        U, V = tangent_frames(nrm)
        coords = []
        for frame in (U, V):
            basis = tuple(np.take(frame[:, c], chunk.local) for c in range(3))
            turn = cross(axis, basis)
            along = dot(axis, basis) * inv
            rt = tuple(cos * b + t + a * along for b, t, a in zip(basis, turn, axis))
            coords.append((dot(rt, u_f), dot(rt, v_f)))
        (uu, uv), (vu, vv) = coords
        fe, ff, fg = (np.where(bad, 0.0, efg[:, c]) for c in range(3))
        # (a, b)^T W (c, d) with W = [[e, f], [f, g]]
        e_p = fe * uu * uu + 2.0 * ff * uu * uv + fg * uv * uv
        f_p = fe * uu * vu + ff * (uu * vv + uv * vu) + fg * uv * vv
        g_p = fe * vu * vu + 2.0 * ff * vu * vv + fg * vv * vv

        # 3. average over the corners, weighted by the mixed Voronoi area
        w = np.where(bad | opposite, 0.0, tc.mixed_area)
        total = chunk.sum(w)
        empty = ~(total > 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            e, f, g = (chunk.sum(np.where(w > 0, w * val, 0.0)) / np.where(empty, 1.0, total)
                       for val in (e_p, f_p, g_p))
        k1, k2, d1, d2 = principal_from_tensor(e, f, g, U, V)
        out.k1[rows], out.k2[rows], out.d1[rows], out.d2[rows] = k1, k2, d1, d2
        singular = empty | chunk.any(opposite & ~bad) | ~np.isfinite(k1) | chunk.any(bad)
        # the neighbours' normals enter the estimate: a non-manifold neighbour spoils it too
        out.reason[rows] = closed_ring_reasons(chunk, tc, singular, nrm, border_vertices,
                                               chunk.ring_any(nonmanifold))

    map_vertex_chunks(mesh, work)
    yield 1.0
    return out


register(EstimatorSpec(
    name="ru", title="Rusinkiewicz", ranges=(2,), function=iter_ru,
    triangles_only=True, uses_normals=True, closed_ring=True,
    reference="Rusinkiewicz 2004, Estimating curvatures and their derivatives on triangle meshes",
    summary="per-face tensors from normal differences, rotated to the vertex frames, area-weighted",
))
