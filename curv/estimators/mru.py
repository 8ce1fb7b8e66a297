"""Modified Rusinkiewicz (paper §4.2): per-vertex least squares of normal differences.

For every neighbour q in range, the shape operator maps the tangent offset (u, v) of ``q - p`` to
the tangent part (a, b) of ``N_q - N_p`` (eq. 4.1/4.2, with our sign convention dN = W t): two
equations ``[u v 0] (e f g)^T = a`` and ``[0 u v] (e f g)^T = b`` per neighbour. N_p is orthogonal
to its own frame's U and V, so only N_q enters (a, b). No per-face step, so it works on any polygon
mesh. One kernel: the ball search and the normal equations run neighbour by neighbour.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit, jit_parallel, prange
from ..core.mesh import Mesh
from ..geometry.neighbourhood import ball_support
from ._local_fit import (MIN_PAIRS, MIN_TANGENT_LENGTH, finish_fit, mark_degenerate, offset_in_frame, run_fit,
                         slice_bounds, solve_sym3, store_se3, tangent_frame)
from .registry import EstimatorSpec, register


@jit
def _mru_at(p, queue, count, r, x, y, z, nx, ny, nz, k1, k2, d1, d2, reason, k1_se, k2_se):
    """Normal-difference least squares at vertex p over its support ``queue[1:count]``."""
    n0, n1, n2 = nx[p], ny[p], nz[p]
    if not (math.isfinite(n0) and math.isfinite(n1) and math.isfinite(n2)):
        mark_degenerate(p, k1, k2, d1, d2, reason)
        return
    frame = tangent_frame(n0, n1, n2)
    ux, uy, uz, vx, vy, vz = frame
    tiny2 = (MIN_TANGENT_LENGTH * r) ** 2
    # normal equations of the two equation kinds: rows (u, v, 0) and (0, u, v)
    suu = suv = svv = sau = sav = sbu = sbv = saa_bb = 0.0
    used = 0
    for i in range(1, count):
        q = queue[i]
        u, v, _ = offset_in_frame(p, q, x, y, z, frame, n0, n1, n2)
        a = nx[q] * ux + ny[q] * uy + nz[q] * uz
        b = nx[q] * vx + ny[q] * vy + nz[q] * vz
        if not (u * u + v * v > tiny2) or not (math.isfinite(a) and math.isfinite(b)):
            continue
        used += 1
        suu += u * u
        suv += u * v
        svv += v * v
        sau += a * u
        sav += a * v
        sbu += b * u
        sbv += b * v
        saa_bb += a * a + b * b
    # AᵀA = [[uu, uv, 0], [uv, uu + vv, uv], [0, uv, vv]], Aᵀb = (au, av + bu, bv)
    e, f, g, singular = solve_sym3(suu, suv, 0.0, suu + svv, suv, svv, sau, sav + sbu, sbv)
    finish_fit(p, e, f, g, singular, used, frame, k1, k2, d1, d2, reason)
    # two equations per neighbour, errors taken as independent (docs/UNCERTAINTY.md)
    store_se3(p, suu, suv, 0.0, suu + svv, suv, svv, saa_bb, e * sau + f * (sav + sbu) + g * sbv, 2 * used, 0,
              0.0, 0.0, 0.0, e, f, g, k1_se, k2_se)


@jit_parallel
def _mru_kernel(centres, lo, hi, radius, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, k1, k2, d1, d2, reason,
                k1_se, k2_se):
    parts = stamps.shape[0]
    for t in prange(parts):
        queue = queues[t]
        stamp = stamps[t]
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            count, queue = ball_support(p, radius[p] ** 2, adj_ptr, adj, x, y, z, stamp, queue)
            _mru_at(p, queue, count, radius[p], x, y, z, nx, ny, nz, k1, k2, d1, d2, reason, k1_se, k2_se)


def iter_mru(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None):
    """Normal-difference least squares over each vertex's support (within (k-1) longest 1-ring edges at Rk)."""
    return (yield from run_fit(mesh, normals, radii, _mru_kernel, chunk=chunk, centres=centres,
                                 features=features))


register(EstimatorSpec(
    name="mru", title="Modified Rusinkiewicz", ranges=(2, 3, 4), function=iter_mru,
    triangles_only=False, uses_normals=True, closed_ring=False, takes_points=True, min_neighbours=MIN_PAIRS,
    reference="Multivariate analysis of curvature estimators, §4.2 (after Rusinkiewicz 2004)",
    summary="per-vertex least squares of neighbour normal differences (eq. 4.1/4.2)", kernels=(_mru_kernel,),
))
