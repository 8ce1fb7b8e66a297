"""Rusinkiewicz (2004): per-face second fundamental tensors averaged at the vertices (R2 only).

1. Per face, in an orthonormal frame (u_f, v_f) of its plane, the tensor ``W_f`` that maps each of
   the three edge vectors to the difference of the vertex normals along it (our convention
   ``dN = W t``): six equations in (e, f, g), solved by their 3x3 normal equations in closed form.
2. Per corner, the face frame is rotated about ``n_f x N_p`` so that its normal matches the vertex
   normal N_p, and ``W_f`` is re-expressed in the vertex frame (U_p, V_p).
3. Per vertex, the corner tensors are averaged with the corner's mixed Voronoi area as weight.

Next to a crease (``features=``) a face that touches a feature vertex is left out of the average:
the normal of a crease vertex blends both sides, and the normal of one side alone (its sector's)
is tilted by O(h) at a curved rim, which a normal difference over an edge of length h turns into
an O(1) error. The faces on the vertex's own side away from the crease give the tensor alone.

The eigen-decomposition of the averaged tensor gives the principal curvatures and directions. It
uses the vertex normals of the whole 1-ring, hence range R2.
"""

from __future__ import annotations

import math

import numpy as np

from ..core import connectivity
from ..core.jit import iter_chunks, jit, jit_parallel, launch, prange
from ..core.mesh import Mesh
from ..core.small_linalg import solve_sym3
from ..core.validity import precedence
from ._frames import tangent_frame
from ._principal import store_principal
from ._triangle_corners import corner_ends, corner_triangle, ring_flag, ring_run
from .registry import EstimatorSpec, register

__all__ = ["iter_ru"]

MIN_ROTATION_COS = -1.0 + 1e-9
"""A face whose normal is (almost) opposite the vertex normal has no defined rotation onto it."""


@jit_parallel
def _ru(centres, lo, hi, ring, normals, crease, out):
    """Rusinkiewicz's tensors at ``centres[lo:hi]`` into ``out`` (k1, k2, d1, d2, reason); ``crease``
    (n,) bool the feature vertices, or None without ``features``."""
    k1, k2, d1, d2, reason = out
    x = ring.x
    for j in prange(lo, hi):
        p = centres[j]
        c_lo, c_hi = ring.indptr[p], ring.indptr[p + 1]
        nax, nay, naz = normals[p, 0], normals[p, 1], normals[p, 2]  # N_p
        ux, uy, uz, vx, vy, vz = tangent_frame(nax, nay, naz)  # (U_p, V_p)
        total = e = f = g = 0.0
        any_bad = any_opposite = touches_degenerate = False
        for i in range(c_lo, c_hi):
            c = ring.corners[i]
            b, q = corner_ends(ring, c)
            if _on_crease(crease, b, q):
                continue  # no normal of this face's crease vertex belongs to p's side
            degenerate = ring.degenerate[c // 3]  # a triangle mesh: face f has the corners 3f .. 3f + 2
            touches_degenerate |= degenerate
            nbx, nby, nbz = normals[b, 0], normals[b, 1], normals[b, 2]
            ncx, ncy, ncz = normals[q, 0], normals[q, 1], normals[q, 2]
            (abx, aby, abz, acx, acy, acz, nx, ny, nz, ab2, _, twice_area, _, _, _,
             area) = corner_triangle(x, p, b, q, degenerate)
            if (degenerate or twice_area == 0.0 or ab2 == 0.0
                    or not (math.isfinite(nax) and math.isfinite(nbx) and math.isfinite(ncx))):
                # no face frame, or a normal missing: the corner gives nothing (and spoils p)
                any_bad = True
                continue
            # face frame: n_f, u_f along ab, v_f = n_f x u_f
            nfx, nfy, nfz = nx / twice_area, ny / twice_area, nz / twice_area
            ab_len = math.sqrt(ab2)
            ufx, ufy, ufz = abx / ab_len, aby / ab_len, abz / ab_len
            vfx = nfy * ufz - nfz * ufy
            vfy = nfz * ufx - nfx * ufz
            vfz = nfx * ufy - nfy * ufx

            # 1. the face tensor W (dN = W t) from its three edges and the normal differences along
            # them, in (u_f, v_f): rows [eu ev 0] -> nu and [0 eu ev] -> nv, by normal equations
            a00 = a01 = a11 = b0 = b1 = b2 = 0.0
            for k in range(3):
                if k == 0:  # a -> b
                    ex, ey, ez = abx, aby, abz
                    dx, dy, dz = nbx - nax, nby - nay, nbz - naz
                elif k == 1:  # b -> c
                    ex, ey, ez = acx - abx, acy - aby, acz - abz
                    dx, dy, dz = ncx - nbx, ncy - nby, ncz - nbz
                else:  # c -> a
                    ex, ey, ez = -acx, -acy, -acz
                    dx, dy, dz = nax - ncx, nay - ncy, naz - ncz
                eu = ex * ufx + ey * ufy + ez * ufz
                ev = ex * vfx + ey * vfy + ez * vfz
                nu = dx * ufx + dy * ufy + dz * ufz
                nv = dx * vfx + dy * vfy + dz * vfz
                a00 += eu * eu
                a01 += eu * ev
                a11 += eu * eu + ev * ev
                b0 += eu * nu
                b1 += ev * nu + eu * nv
                b2 += ev * nv
            # the 3x3 normal matrix is [[a00, a01, 0], [a01, a11, a01], [0, a01, a11 - a00]]
            fe, ff, fg, face_singular = solve_sym3(a00, a01, 0.0, a11, a01, a11 - a00, b0, b1, b2)
            if face_singular:
                any_bad = True
                continue

            # 2. rotate the face frame onto N_p: R takes n_f to N_p (Rodrigues with the
            # unnormalised axis a = n_f x N_p): R y = cos y + a x y + a (a.y) / (1 + cos). We need
            # U.(R u_f) = (R^T U).u_f, and R^T is the same formula with -a.
            cos = nfx * nax + nfy * nay + nfz * naz
            opposite = not cos > MIN_ROTATION_COS
            axx = -(nfy * naz - nfz * nay)
            axy = -(nfz * nax - nfx * naz)
            axz = -(nfx * nay - nfy * nax)
            inv = 0.0 if opposite else 1.0 / (1.0 + cos)
            # R^T U and R^T V, in the face frame: (uu, uv) and (vu, vv)
            rotation = ((axx, axy, axz), cos, inv)
            uf, vf = (ufx, ufy, ufz), (vfx, vfy, vfz)
            uu, uv = _rotated_coords((ux, uy, uz), rotation, uf, vf)
            vu, vv = _rotated_coords((vx, vy, vz), rotation, uf, vf)
            # (a, b)^T W (c, d) with W = [[e, f], [f, g]]
            e_p = fe * uu * uu + 2.0 * ff * uu * uv + fg * uv * uv
            f_p = fe * uu * vu + ff * (uu * vv + uv * vu) + fg * uv * vv
            g_p = fe * vu * vu + 2.0 * ff * vu * vv + fg * vv * vv

            # 3. average over the corners, weighted by the mixed Voronoi area
            if opposite:
                any_opposite = True
                continue
            total += area
            if area > 0:
                e += area * e_p
                f += area * f_p
                g += area * g_p
        empty = not total > 0
        safe = 1.0 if empty else total
        store_principal(p, (e / safe, f / safe, g / safe), (ux, uy, uz, vx, vy, vz), k1, k2, d1, d2)
        singular = empty or any_opposite or not math.isfinite(k1[p]) or any_bad
        finite = math.isfinite(nax) and math.isfinite(nay) and math.isfinite(naz)
        # the neighbours' normals enter the estimate: a non-manifold neighbour spoils it too
        reason[p] = precedence(ring_flag(ring, p, ring.nonmanifold), touches_degenerate or not finite,
                               ring_flag(ring, p, ring.border), singular)


@jit
def _on_crease(crease, b, q):
    """Whether vertex b or q is a crease vertex (``crease`` None: no creases)."""
    if crease is None:
        return False
    return crease[b] or crease[q]


@jit
def _rotated_coords(b, rotation, uf, vf):
    """``(R^T b . u_f, R^T b . v_f)`` for the rotation of :func:`_ru`, ``rotation = (axis a, cosine,
    1 / (1 + cos))``; b, a, u_f, v_f 3-tuples."""
    bx, by, bz = b
    (ax, ay, az), cos, inv = rotation
    ufx, ufy, ufz = uf
    vfx, vfy, vfz = vf
    tx = ay * bz - az * by
    ty = az * bx - ax * bz
    tz = ax * by - ay * bx
    along = (ax * bx + ay * by + az * bz) * inv
    rx = cos * bx + tx + ax * along
    ry = cos * by + ty + ay * along
    rz = cos * bz + tz + az * along
    return rx * ufx + ry * ufy + rz * ufz, rx * vfx + ry * vfy + rz * vfz


def iter_ru(mesh: Mesh, normals: np.ndarray, radii: None = None, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None):
    """Rusinkiewicz's estimator on the 1-ring with its normals (range R2; ``radii`` is None).

    One kernel call per chunk of vertices: every corner solves its face's tensor in a frame of its
    own (three times per face in all, cheaper than storing and gathering a per-face tensor) and
    rotates it into its vertex's frame, so vertices need nothing from each other and the result
    does not depend on the chunks or the threads.

    Parameters
    ----------
    mesh : Mesh
        Closed triangle mesh (vertices with an open or non-manifold 1-ring are marked invalid).
    normals : (n, 3) float64
        Unit vertex normals, used for the normal differences and as the vertex frames.
    centres : (c,) int64, optional
        The vertices to estimate (default all).
    features : curv.core.features.FeatureSet, optional
        The faces that touch a feature vertex are left out of the average (the module's notes).

    ``radii``, ``chunk``, the yields and the result: as :func:`~curv.estimators.meyer.iter_meyer`.
    """
    centres, out, ring = ring_run(mesh, centres)
    crease = features.vertices if features is not None and features.any else None
    # normals in any memory layout: a copy would cost the whole mesh for a small region
    normals = np.asarray(normals, dtype=np.float64)
    rows = (out.k1, out.k2, out.d1, out.d2, out.reason)

    def run(lo: int, hi: int) -> None:
        launch(_ru, centres, lo, hi, ring, normals, crease, rows)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return out


register(EstimatorSpec(
    name="ru", title="Rusinkiewicz", ranges=(2,), function=iter_ru,
    triangles_only=True, uses_normals=True, closed_ring=True, has_support=False,
    kernels=(_ru, *connectivity.KERNELS),
    reference="Rusinkiewicz 2004, Estimating curvatures and their derivatives on triangle meshes",
    summary="per-face tensors from normal differences, rotated to the vertex frames, area-weighted",
))
