"""Meyer, Desbrun, Schröder & Barr (2003): discrete differential-geometry operators (R1 only).

Per vertex p, over its closed 1-ring of triangles:

- mean-curvature normal ``K(p) = 1/(2 A_mixed) sum_j (cot a_j + cot b_j) (p - q_j)`` and
  ``H = sign(K . N) |K| / 2`` (outward sphere: ``+1/r``);
- Gaussian curvature from the angle defect ``K_G = (2 pi - sum theta) / A_mixed``;
- ``k1,2 = H +- sqrt(max(H^2 - K_G, 0))``.

``A_mixed`` is the Voronoi area of the corner in a non-obtuse triangle, half the triangle's area at
an obtuse corner and a quarter of it at the other two corners of an obtuse triangle.

Directions: Meyer et al. fit a 2x2 tensor to the normal curvatures of the 1-ring edges by least
squares with its trace constrained to 2H. We do the same, unweighted: with the tensor written as
``H I + [[x, y], [y, -x]]`` in the tangent frame, every edge (tangent angle phi) gives one
equation ``x cos 2phi + y sin 2phi = kn - H`` with the edge normal curvature
``kn = 2 (p - q).N / |p - q|^2``. The maximum direction is the eigenvector of that tensor at
angle ``atan2(y, x) / 2``; the curvature values stay those of the formula above.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..frames import tangent_frames
from ..mesh import Mesh
from ..validity import Reason
from ._lsq import MIN_TANGENT_LENGTH
from .registry import EstimatorSpec, empty_principal, register

__all__ = ["iter_meyer", "corner_geometry", "ring_flags", "scatter_matrix"]


def scatter_matrix(index: np.ndarray, n: int) -> sp.csc_matrix:
    """(n, k) matrix summing k per-item values into n bins: ``(S @ x)[b] = sum of x[j] with index[j] == b``.

    One entry per column, so it needs no sorting; ``S @ x`` (1-D or C-contiguous 2-D ``x``) is a
    single C pass, faster than ``np.bincount`` with weights.

    Parameters
    ----------
    index : (k,) int
        Bin of every item.
    n : int
        Number of bins.

    Returns
    -------
    (n, k) scipy.sparse.csc_matrix
    """
    k = index.size
    return sp.csc_matrix((np.ones(k), index, np.arange(k + 1)), shape=(n, k))


def corner_geometry(mesh: Mesh):
    """Per-corner edges, cotangents, angles and mixed Voronoi areas of a triangle mesh.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.

    Returns
    -------
    edge : list of three (m, 3) float64
        ``edge[i]`` runs from corner i to corner i+1 of every face.
    cot : (m, 3) float64
        Cotangent of the angle at each corner (0 on degenerate faces).
    angle : (m, 3) float64
        Corner angles in radians (0 on degenerate faces).
    area : (m, 3) float64
        The corner's share of the mixed Voronoi area ``A_mixed`` (0 on degenerate faces).
    """
    tri = mesh.triangles
    corner = np.take(mesh.vertices, tri, axis=0)
    edge = [corner[:, (i + 1) % 3] - corner[:, i] for i in range(3)]
    len2 = np.stack([np.einsum("ij,ij->i", e, e) for e in edge], axis=1)
    # the angle at corner i is between edge i and the reversed edge i+2
    dots = -np.stack([np.einsum("ij,ij->i", edge[i], edge[(i + 2) % 3]) for i in range(3)], axis=1)
    face_area = mesh.face_areas
    bad = mesh.degenerate_faces
    twice = np.where(bad, 1.0, 2.0 * face_area)[:, None]
    cot = dots / twice
    angle = np.arctan2(twice, dots)
    obtuse = dots < 0
    # edge i faces corner i+2, edge i+2 faces corner i+1
    area = 0.125 * (cot[:, [2, 0, 1]] * len2 + cot[:, [1, 2, 0]] * len2[:, [2, 0, 1]])
    any_obtuse = obtuse.any(axis=1)
    area[any_obtuse] = np.where(obtuse[any_obtuse], 0.5, 0.25) * face_area[any_obtuse, None]
    for arr in (cot, angle, area):
        arr[bad] = 0.0
    return edge, cot, angle, area


def ring_flags(mesh: Mesh, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices whose 1-ring is unfit for a closed-ring estimator.

    Parameters
    ----------
    mesh : Mesh
    normals : (n, 3) float64

    Returns
    -------
    border : (n,) bool
        On a border (or non-manifold edge), or adjacent to such a vertex.
    degenerate : (n,) bool
        Touching a degenerate face, or without a finite normal.
    nonmanifold : (n,) bool
        Non-manifold vertex.
    """
    adj = mesh.adjacency
    on_border = mesh.border_vertices
    border = on_border | (adj @ on_border.astype(np.int32) > 0)
    degenerate = (mesh.vertex_faces @ mesh.degenerate_faces.astype(np.int32) > 0)
    degenerate |= ~np.isfinite(normals).all(axis=1)
    return border, degenerate, mesh.nonmanifold_vertices.copy()


def iter_meyer(mesh: Mesh, normals: np.ndarray, k: int, *, block_size: int | None = None):
    """Meyer et al. operators on the 1-ring (``k`` must be 1; ``block_size`` is unused).

    Parameters
    ----------
    mesh : Mesh
        Closed triangle mesh (vertices with an open or non-manifold 1-ring are marked invalid).
    normals : (n, 3) float64
        Unit vertex normals: the sign of H and the tangent frame of the direction fit.
    k : int
        Range; only 1.

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
    edge, cot, angle, area = corner_geometry(mesh)
    U, V = tangent_frames(normals)
    frames = np.concatenate([U, V, normals], axis=1)
    yield 0.2

    # One pass over the corners. In a closed oriented 1-ring every edge p-q leaves p in exactly
    # one face, so edge i of corner i enumerates the 1-ring pairs once each.
    hvec = np.zeros((n, 3))
    acc = np.zeros((_COLUMNS, n))
    for i in range(3):
        nxt, prv = (i + 1) % 3, (i + 2) % 3
        scatter = scatter_matrix(tri[:, i], n)
        # cot(a_j) (p - q_j) summed: edge i (to q = corner i+1) faces corner i+2, edge i+2 faces i+1
        hvec += scatter @ (cot[:, nxt, None] * edge[prv] - cot[:, prv, None] * edge[i])
        f = np.take(frames, tri[:, i], axis=0).reshape(-1, 3, 3)
        u, v, w = np.einsum("ij,ikj->ki", edge[i], f)
        l2 = u * u + v * v
        with np.errstate(invalid="ignore", divide="ignore"):
            ok = l2 > (MIN_TANGENT_LENGTH**2) * (l2 + w * w)
            inv = np.where(ok, 1.0 / l2, 0.0)
            kn = np.where(ok, -2.0 * w / (l2 + w * w), 0.0)
        c2 = (u * u - v * v) * inv
        s2 = 2.0 * u * v * inv
        for row, values in enumerate((area[:, i], angle[:, i], c2 * c2, c2 * s2, s2 * s2,
                                      kn * c2, kn * s2, c2, s2)):
            acc[row] += scatter @ values
        yield 0.2 + 0.2 * (i + 1)

    a_mixed = acc[0]
    singular = ~(a_mixed > 0)
    safe_area = np.where(singular, 1.0, a_mixed)
    hvec /= (2.0 * safe_area)[:, None]
    sign = np.sign(np.einsum("ij,ij->i", hvec, np.nan_to_num(normals)))
    h = 0.5 * sign * np.linalg.norm(hvec, axis=1)
    kg = (2.0 * np.pi - acc[1]) / safe_area
    root = np.sqrt(np.maximum(h * h - kg, 0.0))

    # trace-constrained fit x cos2phi + y sin2phi = kn - H: a 2x2 system in closed form; only the
    # angle of (x, y) is needed, and det > 0 where the system is regular
    a00, a01, a11 = acc[2], acc[3], acc[4]
    b0 = acc[5] - h * acc[7]
    b1 = acc[6] - h * acc[8]
    det = a00 * a11 - a01 * a01
    fit_singular = ~(det > FIT_RCOND * np.maximum(a00, a11) ** 2)
    theta = 0.5 * np.arctan2(a00 * b1 - a01 * b0, a11 * b0 - a01 * b1)
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    out.k1[:] = h + root
    out.k2[:] = h - root
    out.d1[:] = c * U + s * V
    out.d2[:] = -s * U + c * V

    border, degenerate, nonmanifold = ring_flags(mesh, normals)
    reason = out.reason
    reason[singular | fit_singular] = Reason.SINGULAR
    reason[border] = Reason.BORDER
    reason[degenerate] = Reason.DEGENERATE
    reason[nonmanifold] = Reason.NONMANIFOLD
    yield 1.0
    return out


_COLUMNS = 9
"""Per-vertex sums besides the mean-curvature vector: mixed area, angle sum, direction-fit sums (7)."""

FIT_RCOND = 1e-10
"""The direction fit is singular when its 2x2 determinant is below this times its scale squared."""


register(EstimatorSpec(
    name="meyer", title="Meyer et al. discrete operators", ranges=(1,), function=iter_meyer,
    triangles_only=True, uses_normals=False, closed_ring=True,
    reference="Meyer, Desbrun, Schröder, Barr 2003, Discrete differential-geometry operators for "
              "triangulated 2-manifolds",
    summary="cotan mean-curvature normal and angle defect over the mixed Voronoi area",
))
