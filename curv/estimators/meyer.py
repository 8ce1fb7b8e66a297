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

from ..corners import CornerChunk, map_vertex_chunks
from ..frames import tangent_frames
from ..mesh import Mesh
from ..normals import max_corner_weights, normalize_rows, unusable_normal_vertices
from ._lsq import MIN_TANGENT_LENGTH
from ._triangle_corners import TriangleCorners, closed_ring_reasons
from .registry import EstimatorSpec, empty_principal, register

__all__ = ["iter_meyer"]


def iter_meyer(mesh: Mesh, normals: np.ndarray, k: int, *, block_size: int | None = None):
    """Meyer et al. operators on the 1-ring (``k`` must be 1; ``block_size`` is unused).

    The corners around each vertex are processed in cache-sized chunks of vertices on a thread
    pool (:mod:`curv.corners`): every corner contributes its face's cotangent terms, angle and
    mixed-area share to its own vertex, so a chunk needs no data from any other chunk.

    Parameters
    ----------
    mesh : Mesh
        Closed triangle mesh (vertices with an open or non-manifold 1-ring are marked invalid).
    normals : (n, 3) float64 or None
        Unit vertex normals: the sign of H and the tangent frame of the direction fit. None: compute
        the Max-weighted normals from the same corners (returned in ``Principal.normals``, NaN
        where :func:`curv.normals.unusable_normal_vertices`).
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
    if not mesh.is_triangular:
        mesh.triangles  # raises the MeshError that names the polygon sizes
    xyz = tuple(np.ascontiguousarray(mesh.vertices[:, c]) for c in range(3))
    degenerate_faces = mesh.degenerate_faces
    corner_face = mesh.corner_face
    border_vertices, nonmanifold = mesh.border_vertices, mesh.nonmanifold_vertices
    own_normals = normals is None
    if own_normals:
        normals = np.empty((n, 3))
        unusable = unusable_normal_vertices(mesh)
    yield 0.1

    def work(chunk: CornerChunk) -> None:
        rows = slice(chunk.start, chunk.stop)
        tc = TriangleCorners.of(chunk, xyz, degenerate_faces, corner_face)
        ab = tc.ab
        # mean-curvature normal: (a - b) cot c + (a - c) cot b, summed over the corners
        hterm = [-(tc.cot_c * e1 + tc.cot_b * e2) for e1, e2 in zip(ab, tc.ac)]
        area, angle = tc.mixed_area, tc.angle()

        if own_normals:
            summed = np.stack([chunk.sum(w) for w in max_corner_weights(tc.normal, tc.ab_len2, tc.ac_len2)],
                              axis=1)
            nrm = normalize_rows(summed)
            nrm[unusable[rows]] = np.nan
            normals[rows] = nrm
        # direction fit on the edge a -> b (in a closed ring every leaving edge appears once)
        nrm = normals[rows]
        U, V = tangent_frames(nrm)
        u, v, w = (sum(e * np.take(F[:, c], chunk.local) for c, e in enumerate(ab))
                   for F in (U, V, nrm))
        l2 = u * u + v * v
        with np.errstate(invalid="ignore", divide="ignore"):
            ok = l2 > (MIN_TANGENT_LENGTH**2) * (l2 + w * w)
            inv = np.where(ok, 1.0 / l2, 0.0)
            kn = np.where(ok, -2.0 * w / (l2 + w * w), 0.0)
        c2 = (u * u - v * v) * inv
        s2 = 2.0 * u * v * inv
        a_mixed, angle_sum, a00, a01, a11, r0, r1, t0, t1, hx, hy, hz = (
            chunk.sum(x) for x in (area, angle, c2 * c2, c2 * s2, s2 * s2, kn * c2, kn * s2, c2, s2, *hterm))

        empty = ~(a_mixed > 0)
        safe_area = np.where(empty, 1.0, a_mixed)
        hx, hy, hz = (x / (2.0 * safe_area) for x in (hx, hy, hz))
        with np.errstate(invalid="ignore"):
            sign = np.sign(hx * nrm[:, 0] + hy * nrm[:, 1] + hz * nrm[:, 2])
        h = 0.5 * sign * np.sqrt(hx * hx + hy * hy + hz * hz)
        kg = (2.0 * np.pi - angle_sum) / safe_area
        root = np.sqrt(np.maximum(h * h - kg, 0.0))
        # trace-constrained fit x cos2phi + y sin2phi = kn - H: a 2x2 system in closed form; only
        # the angle of (x, y) is needed, and det > 0 where the system is regular
        b0 = r0 - h * t0
        b1 = r1 - h * t1
        det = a00 * a11 - a01 * a01
        fit_singular = ~(det > FIT_RCOND * np.maximum(a00, a11) ** 2)
        theta = 0.5 * np.arctan2(a00 * b1 - a01 * b0, a11 * b0 - a01 * b1)
        c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
        out.k1[rows] = h + root
        out.k2[rows] = h - root
        out.d1[rows] = c * U + s * V
        out.d2[rows] = -s * U + c * V
        out.reason[rows] = closed_ring_reasons(chunk, tc, empty | fit_singular, nrm, border_vertices,
                                               nonmanifold[rows])

    map_vertex_chunks(mesh, work)
    yield 0.9
    if own_normals:
        out.normals = normals
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
    computes_normals=True,
    summary="cotan mean-curvature normal and angle defect over the mixed Voronoi area",
))
