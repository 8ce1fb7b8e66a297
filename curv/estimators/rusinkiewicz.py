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

from ..frames import principal_from_tensor, solve_sym3, tangent_frames
from ..mesh import Mesh
from ..validity import Reason
from .meyer import corner_geometry, ring_flags
from .registry import EstimatorSpec, empty_principal, register

__all__ = ["iter_ru", "face_tensors"]

MIN_ROTATION_COS = -1.0 + 1e-9
"""A face whose normal is (almost) opposite the vertex normal has no defined rotation onto it."""


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def face_tensors(mesh: Mesh, normals: np.ndarray):
    """Second fundamental tensor of every face from its edges and the normals at its corners.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    normals : (n, 3) float64
        Unit vertex normals.

    Returns
    -------
    u_f, v_f : (m, 3) float64
        Orthonormal frame of each face plane (``u_f x v_f`` = face normal); NaN on degenerate faces.
    efg : (m, 3) float64
        Tensor entries (e, f, g) in that frame; NaN where the system is singular.
    singular : (m,) bool
    """
    tri = mesh.triangles
    v = mesh.vertices
    nf = mesh.face_normals
    e0 = np.take(v, tri[:, 1], axis=0) - np.take(v, tri[:, 0], axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        u_f = e0 / np.linalg.norm(e0, axis=1, keepdims=True)
    v_f = np.cross(nf, u_f)
    size = tri.shape[0]
    a00 = np.zeros(size); a01 = np.zeros(size); a11 = np.zeros(size)  # noqa: E702
    b0 = np.zeros(size); b1 = np.zeros(size); b2 = np.zeros(size)  # noqa: E702
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        edge = np.take(v, tri[:, k], axis=0) - np.take(v, tri[:, j], axis=0)
        dn = np.take(normals, tri[:, k], axis=0) - np.take(normals, tri[:, j], axis=0)
        eu, ev = _dot(edge, u_f), _dot(edge, v_f)
        nu, nv = _dot(dn, u_f), _dot(dn, v_f)
        # rows [eu ev 0] -> nu and [0 eu ev] -> nv
        a00 += eu * eu
        a01 += eu * ev
        a11 += eu * eu + ev * ev
        b0 += eu * nu
        b1 += ev * nu + eu * nv
        b2 += ev * nv
    # the 3x3 normal matrix is [[a00, a01, 0], [a01, a11, a01], [0, a01, a22]] with a22 = a11 - a00
    efg, singular = solve_sym3(a00, a01, np.zeros(size), a11, a01, a11 - a00, b0, b1, b2)
    return u_f, v_f, efg, singular


def iter_ru(mesh: Mesh, normals: np.ndarray, k: int, *, block_size: int | None = None):
    """Rusinkiewicz's estimator (``k`` must be 2; ``block_size`` is unused: one pass over faces).

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
    tri = mesh.triangles
    u_f, v_f, efg, face_singular = face_tensors(mesh, normals)
    nf = mesh.face_normals
    _, _, _, weight = corner_geometry(mesh)
    yield 0.3

    U, V = tangent_frames(normals)
    acc = np.zeros((n, 4))  # weighted e, f, g and total weight
    flip = np.zeros(n, bool)
    bad_face = face_singular | mesh.degenerate_faces | ~np.isfinite(np.take(normals, tri, axis=0)).all(axis=(1, 2))
    fe, ff, fg = (np.where(bad_face, 0.0, efg[:, c]) for c in range(3))
    for i in range(3):
        p = tri[:, i]
        n_p = np.take(normals, p, axis=0)
        c = _dot(nf, n_p)
        opposite = ~(c > MIN_ROTATION_COS)
        np.logical_or.at(flip, p[opposite & ~bad_face], True)
        # Rotation R taking n_f to N_p (Rodrigues with the unnormalised axis a = n_f x N_p):
        # R x = c x + a x x + a (a.x) / (1 + c). We need U.(R u_f) = (R^T U).u_f, and R^T is the
        # same formula with -a.
        axis = -np.cross(nf, n_p)
        with np.errstate(invalid="ignore", divide="ignore"):
            inv = np.where(opposite, 0.0, 1.0 / (1.0 + c))
        rows = []
        for basis in (np.take(U, p, axis=0), np.take(V, p, axis=0)):
            rt = c[:, None] * basis + np.cross(axis, basis) + axis * (_dot(axis, basis) * inv)[:, None]
            rows.append((_dot(rt, u_f), _dot(rt, v_f)))
        (uu, uv), (vu, vv) = rows
        # (a, b)^T W_f (c, d) with W_f = [[e, f], [f, g]]
        e_p = fe * uu * uu + 2.0 * ff * uu * uv + fg * uv * uv
        f_p = fe * uu * vu + ff * (uu * vv + uv * vu) + fg * uv * vv
        g_p = fe * vu * vu + 2.0 * ff * vu * vv + fg * vv * vv
        w = np.where(bad_face | opposite, 0.0, weight[:, i])
        for col, val in enumerate((e_p, f_p, g_p)):
            acc[:, col] += np.bincount(p, weights=np.where(w > 0, w * val, 0.0), minlength=n)
        acc[:, 3] += np.bincount(p, weights=w, minlength=n)
        yield 0.3 + 0.2 * (i + 1)

    total = acc[:, 3]
    empty = ~(total > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        e, f, g = (acc[:, col] / np.where(empty, 1.0, total) for col in range(3))
    k1, k2, d1, d2 = principal_from_tensor(e, f, g, U, V)
    out.k1[:], out.k2[:], out.d1[:], out.d2[:] = k1, k2, d1, d2

    border, degenerate, nonmanifold = ring_flags(mesh, normals)
    face_bad_at = mesh.vertex_faces @ bad_face.astype(np.int32) > 0
    nonmanifold |= mesh.adjacency @ mesh.nonmanifold_vertices.astype(np.int32) > 0
    reason = out.reason
    reason[empty | flip | ~np.isfinite(k1) | face_bad_at] = Reason.SINGULAR
    reason[border] = Reason.BORDER
    reason[degenerate] = Reason.DEGENERATE
    reason[nonmanifold] = Reason.NONMANIFOLD
    yield 1.0
    return out


register(EstimatorSpec(
    name="ru", title="Rusinkiewicz", ranges=(2,), function=iter_ru,
    triangles_only=True, uses_normals=True, closed_ring=True,
    reference="Rusinkiewicz 2004, Estimating curvatures and their derivatives on triangle meshes",
    summary="per-face tensors from normal differences, rotated to the vertex frames, area-weighted",
))
