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

import math

import numpy as np

from ..core import connectivity
from ..core.filled import filled
from ..core.jit import iter_chunks, jit, jit_parallel, launch, prange, threads
from ..core.mesh import Mesh
from ..core.validity import precedence
from ..geometry.normals import KERNELS as NORMAL_KERNELS, max_weight, unit, unusable_normal_vertices
from ._frames import MIN_TANGENT_LENGTH, tangent_frame
from ._triangle_corners import angle_sum, corner_ends, corner_triangle, ring_flag, ring_run, turn_by_corner
from .registry import EstimatorSpec, register

__all__ = ["iter_meyer"]

FIT_RCOND = 1e-10
"""The direction fit is singular when its 2x2 determinant is below this times its scale squared."""

TINY2 = MIN_TANGENT_LENGTH**2
"""An edge whose tangent part is below MIN_TANGENT_LENGTH of its length gives no direction."""


@jit_parallel
def _meyer(centres, lo, hi, parts, width, ring, normals, unusable, out):
    """Meyer et al.'s operators at ``centres[lo:hi]`` into ``out`` (k1, k2, d1, d2, reason), ``parts``
    thread slices with a scratch of ``width`` corners each. ``unusable`` None: ``normals`` (n, 3)
    are given and read; else ``normals`` receives the Max normals of the same corners, NaN where
    ``unusable`` (n,) bool."""
    k1, k2, d1, d2, reason = out
    for t in prange(parts):
        # the leaving edges ab of the current vertex's corners, for the direction fit
        edge_x, edge_y, edge_z = np.empty(width), np.empty(width), np.empty(width)
        start, stop = lo + (hi - lo) * t // parts, lo + (hi - lo) * (t + 1) // parts
        for j in range(start, stop):
            p = centres[j]
            c_lo, c_hi = ring.indptr[p], ring.indptr[p + 1]
            a_mixed = 0.0
            turn_re, turn_im, turns = 1.0, 0.0, 0  # sum of the corner angles theta (turn_by_corner)
            kx = ky = kz = 0.0  # 2 A_mixed K(p): sum of (p - q_j)(cot a_j + cot b_j), one term per corner
            sx = sy = sz = 0.0  # the Max normal, unnormalised
            touches_degenerate = False
            for i in range(c_lo, c_hi):
                c = ring.corners[i]
                bad = ring.degenerate[c // 3]  # a triangle mesh: face f has the corners 3f .. 3f + 2
                touches_degenerate |= bad
                b, q = corner_ends(ring, c)
                (abx, aby, abz, acx, acy, acz, nx, ny, nz, ab2, ac2, twice_area, cos_a, cot_b, cot_c,
                 area) = corner_triangle(ring.x, p, b, q, bad)
                # (a - b) cot c + (a - c) cot b
                kx += -(cot_c * abx + cot_b * acx)
                ky += -(cot_c * aby + cot_b * acy)
                kz += -(cot_c * abz + cot_b * acz)
                a_mixed += area
                turn_re, turn_im, turns = turn_by_corner(turn_re, turn_im, turns, twice_area, cos_a, bad)
                wx, wy, wz = max_weight(nx, ny, nz, ab2, ac2)
                sx += wx
                sy += wy
                sz += wz
                edge_x[i - c_lo], edge_y[i - c_lo], edge_z[i - c_lo] = abx, aby, abz
            if unusable is not None:
                # the Max normal (as vertex_normals), NaN where the fan has no meaningful normal
                nx, ny, nz = unit(sx, sy, sz)
                if unusable[p]:
                    nx, ny, nz = math.nan, math.nan, math.nan
                normals[p, 0], normals[p, 1], normals[p, 2] = nx, ny, nz
            else:
                nx, ny, nz = normals[p, 0], normals[p, 1], normals[p, 2]
            ux, uy, uz, vx, vy, vz = tangent_frame(nx, ny, nz)
            # direction fit on the edges a -> b (in a closed ring every leaving edge appears once):
            # tangent angle phi of the edge, normal curvature kn = 2 (p - q).N / |p - q|^2
            a00 = a01 = a11 = r0 = r1 = t0 = t1 = 0.0
            for i in range(c_hi - c_lo):
                abx, aby, abz = edge_x[i], edge_y[i], edge_z[i]
                u = abx * ux + aby * uy + abz * uz
                v = abx * vx + aby * vy + abz * vz
                w = abx * nx + aby * ny + abz * nz
                l2 = u * u + v * v
                if l2 > TINY2 * (l2 + w * w):
                    inv = 1.0 / l2
                    kn = -2.0 * w / (l2 + w * w)
                else:
                    inv = kn = 0.0
                c2 = (u * u - v * v) * inv  # cos 2 phi
                s2 = 2.0 * u * v * inv  # sin 2 phi
                a00 += c2 * c2
                a01 += c2 * s2
                a11 += s2 * s2
                r0 += kn * c2
                r1 += kn * s2
                t0 += c2
                t1 += s2

            empty = not a_mixed > 0
            safe_area = 1.0 if empty else a_mixed
            kx, ky, kz = kx / (2.0 * safe_area), ky / (2.0 * safe_area), kz / (2.0 * safe_area)
            # H = sign(K . N) |K| / 2; K_G = (2 pi - sum theta) / A_mixed
            h = 0.5 * _sign(kx * nx + ky * ny + kz * nz) * math.sqrt(kx * kx + ky * ky + kz * kz)
            kg = (2.0 * math.pi - angle_sum(turn_re, turn_im, turns)) / safe_area
            disc = h * h - kg
            root = math.sqrt(disc) if disc > 0.0 else (disc if math.isnan(disc) else 0.0)
            # trace-constrained fit x cos2phi + y sin2phi = kn - H: a 2x2 system in closed form; only
            # the angle of (x, y) is needed, and det > 0 where the system is regular
            b0 = r0 - h * t0
            b1 = r1 - h * t1
            det = a00 * a11 - a01 * a01
            scale = max(a00, a11) if not (math.isnan(a00) or math.isnan(a11)) else math.nan
            fit_singular = not det > FIT_RCOND * scale * scale
            theta = 0.5 * math.atan2(a00 * b1 - a01 * b0, a11 * b0 - a01 * b1)
            cs, sn = math.cos(theta), math.sin(theta)
            k1[p] = h + root
            k2[p] = h - root
            d1[p, 0], d1[p, 1], d1[p, 2] = cs * ux + sn * vx, cs * uy + sn * vy, cs * uz + sn * vz
            d2[p, 0], d2[p, 1], d2[p, 2] = -sn * ux + cs * vx, -sn * uy + cs * vy, -sn * uz + cs * vz
            finite = math.isfinite(nx) and math.isfinite(ny) and math.isfinite(nz)
            reason[p] = precedence(ring.nonmanifold[p], touches_degenerate or not finite,
                                   ring_flag(ring, p, ring.border), empty or fit_singular)


def iter_meyer(mesh: Mesh, normals: np.ndarray | None, radii: None = None, *, chunk: int | None = None,
               centres: np.ndarray | None = None, features=None):
    """Meyer et al. operators on the closed 1-ring of every vertex (a fixed range: ``radii`` is None).

    One kernel call per chunk of vertices: every vertex sums, over its corners, the cotangent terms,
    angle and mixed-area share of the corner's triangle and the direction-fit terms of its leaving
    edge. Vertices need nothing from each other, so the result does not depend on the chunks or
    the threads.

    Parameters
    ----------
    mesh : Mesh
        Closed triangle mesh (vertices with an open or non-manifold 1-ring are marked invalid).
    normals : (n, 3) float64 or None
        Unit vertex normals: the sign of H and the tangent frame of the direction fit. None: compute
        the Max-weighted normals from the same corners (returned in ``Principal.normals``, NaN
        where :func:`curv.geometry.normals.unusable_normal_vertices`; identical to
        :func:`curv.geometry.normals.vertex_normals` there).

    ``radii`` (no range support: None), ``chunk``, the fractions done it yields and the
    :class:`~curv.core.result.Principal` it returns are those of every estimator
    (:data:`~curv.estimators.registry.EstimatorFunction`).
    """
    n = mesh.n_vertices
    centres, out, ring = ring_run(mesh, centres)
    indptr = ring.indptr
    own_normals = normals is None
    if own_normals:
        # NaN outside a region, at the cost of the region's rows
        normals = np.empty((n, 3)) if centres.size == n else filled((n, 3), np.nan)
        unusable = unusable_normal_vertices(mesh)
    else:
        normals = np.asarray(normals, dtype=np.float64)  # any layout: no copy of the whole mesh
        unusable = None
    width = int((indptr[centres + 1] - indptr[centres]).max(initial=0)) + 1
    rows = (out.k1, out.k2, out.d1, out.d2, out.reason)

    def run(lo: int, hi: int) -> None:
        launch(_meyer, centres, lo, hi, max(1, min(threads(), hi - lo)), width, ring, normals, unusable, rows)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    if own_normals:
        out.normals = normals
    return out


@jit
def _sign(value):
    """``np.sign``: -1, 0 or 1, NaN for NaN."""
    if value > 0.0:
        return 1.0
    if value < 0.0:
        return -1.0
    return value  # 0 or NaN


register(EstimatorSpec(
    name="meyer", title="Meyer et al. discrete operators", ranges=(1,), function=iter_meyer,
    triangles_only=True, uses_normals=False, closed_ring=True,
    reference="Meyer, Desbrun, Schröder, Barr 2003, Discrete differential-geometry operators for "
              "triangulated 2-manifolds",
    computes_normals=True, has_support=False,
    kernels=(_meyer, *connectivity.KERNELS, *NORMAL_KERNELS),
    summary="cotan mean-curvature normal and angle defect over the mixed Voronoi area",
))
