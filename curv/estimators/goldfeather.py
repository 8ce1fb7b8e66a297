"""Goldfeather & Interrante (2004) fits, extended to any range (paper §4.1).

For every neighbour q of vertex p in range, with ``(u, v, w)`` the offset ``q - p`` in p's frame
(U, V, N) and W = [[e, f], [f, g]] the shape operator in (U, V):

- ``nc``: normal curvature approximation, one equation per neighbour:
  ``t^T W t = kn`` with t = (u, v)/|(u, v)| and ``kn = 2 (p - q).N / |p - q|^2``.
- ``qs``: quadratic height fit ``w = A/2 u^2 + B u v + C/2 v^2``, W = -[[A, B], [B, C]].
- ``an``: adjacent-normal cubic fit: the quadratic plus four cubic terms
  ``D u^3 + E u^2 v + F u v^2 + G v^3``; the neighbour's normal N_q = (a, b, c) in p's frame gives
  the slopes ``w_u = -a/c`` and ``w_v = -b/c`` (7 unknowns, 3 equations per neighbour).

All three work on any polygon mesh and on borders (the fit is one-sided there; the API marks the
border vertices themselves). Each is one kernel: the ball search and the normal equations run
neighbour by neighbour (:mod:`curv.estimators._local_fit`).
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import jit, jit_parallel, prange
from ..mesh import Mesh
from ..neighbourhood import ball_support
from ._local_fit import (MIN_PAIRS, MIN_TANGENT_LENGTH, finish_fit, mark_degenerate, offset_in_frame, run_fit, slice_bounds,
                         solve_scaled, solve_sym3, tangent_frame)
from .registry import EstimatorSpec, register

MIN_NORMAL_Z = 0.1
"""A neighbour normal tilted more than ~84 degrees from the centre normal gives no slope equation."""


@jit
def _nc_at(p, queue, count, r, x, y, z, nx, ny, nz, k1, k2, d1, d2, reason):
    """Normal-curvature least squares at vertex p over its support ``queue[1:count]``."""
    n0, n1, n2 = nx[p], ny[p], nz[p]
    if not (math.isfinite(n0) and math.isfinite(n1) and math.isfinite(n2)):
        mark_degenerate(p, k1, k2, d1, d2, reason)
        return
    frame = tangent_frame(n0, n1, n2)
    tiny2 = (MIN_TANGENT_LENGTH * r) ** 2
    a00 = a01 = a02 = a11 = a12 = a22 = b0 = b1 = b2 = 0.0
    used = 0
    for i in range(1, count):
        q = queue[i]
        u, v, w = offset_in_frame(p, q, x, y, z, frame, n0, n1, n2)
        l2 = u * u + v * v
        if not (l2 > tiny2):
            continue
        used += 1
        kn = -2.0 * w / (l2 + w * w)
        # row (tu^2, 2 tu tv, tv^2) of the unit tangent t = (u, v)/|(u, v)|
        c0, c1, c2 = u * u / l2, 2.0 * u * v / l2, v * v / l2
        a00 += c0 * c0
        a01 += c0 * c1
        a02 += c0 * c2
        a11 += c1 * c1
        a12 += c1 * c2
        a22 += c2 * c2
        b0 += c0 * kn
        b1 += c1 * kn
        b2 += c2 * kn
    e, f, g, singular = solve_sym3(a00, a01, a02, a11, a12, a22, b0, b1, b2)
    finish_fit(p, e, f, g, singular, used, frame, k1, k2, d1, d2, reason)


@jit
def _qs_at(p, queue, count, r, x, y, z, nx, ny, nz, k1, k2, d1, d2, reason):
    """Quadratic height fit at vertex p over its support ``queue[1:count]``."""
    n0, n1, n2 = nx[p], ny[p], nz[p]
    if not (math.isfinite(n0) and math.isfinite(n1) and math.isfinite(n2)):
        mark_degenerate(p, k1, k2, d1, d2, reason)
        return
    frame = tangent_frame(n0, n1, n2)
    tiny2 = (MIN_TANGENT_LENGTH * r) ** 2
    a00 = a01 = a02 = a11 = a12 = a22 = b0 = b1 = b2 = 0.0
    used = 0
    for i in range(1, count):
        q = queue[i]
        u, v, w = offset_in_frame(p, q, x, y, z, frame, n0, n1, n2)
        if not (u * u + v * v > tiny2):
            continue
        used += 1
        # w = A/2 u^2 + B uv + C/2 v^2
        c0, c1, c2 = 0.5 * u * u, u * v, 0.5 * v * v
        a00 += c0 * c0
        a01 += c0 * c1
        a02 += c0 * c2
        a11 += c1 * c1
        a12 += c1 * c2
        a22 += c2 * c2
        b0 += c0 * w
        b1 += c1 * w
        b2 += c2 * w
    A, B, C, singular = solve_sym3(a00, a01, a02, a11, a12, a22, b0, b1, b2)
    # W = -Hessian of the height along N
    finish_fit(p, -A, -B, -C, singular, used, frame, k1, k2, d1, d2, reason)


@jit
def _accumulate(ata, atb, row, rhs):
    """Add the equation ``row . x = rhs`` to the normal equations."""
    m = row.size
    for i in range(m):
        ri = row[i]
        if ri != 0.0:
            atb[i] += ri * rhs
            for j in range(m):
                ata[i, j] += ri * row[j]


@jit
def _an_at(p, queue, count, r, x, y, z, nx, ny, nz, k1, k2, d1, d2, reason, ata, atb, row, sol):
    """Adjacent-normal cubic fit at vertex p (``ata`` (7,7), ``atb``, ``row``, ``sol`` (7,): scratch)."""
    n0, n1, n2 = nx[p], ny[p], nz[p]
    if not (math.isfinite(n0) and math.isfinite(n1) and math.isfinite(n2)):
        mark_degenerate(p, k1, k2, d1, d2, reason)
        return
    frame = tangent_frame(n0, n1, n2)
    ux, uy, uz, vx, vy, vz = frame
    # Heights are lengths, slopes are not: fit in coordinates divided by the ball radius so the
    # balance of the two kinds of equation (and so the result) does not depend on the mesh's scale.
    inv_r = 1.0 / r
    tiny2 = MIN_TANGENT_LENGTH ** 2
    ata[:, :] = 0.0
    atb[:] = 0.0
    used = 0
    for i in range(1, count):
        q = queue[i]
        dx, dy, dz = (x[q] - x[p]) * inv_r, (y[q] - y[p]) * inv_r, (z[q] - z[p]) * inv_r
        u = dx * ux + dy * uy + dz * uz
        v = dx * vx + dy * vy + dz * vz
        w = dx * n0 + dy * n1 + dz * n2
        if not (u * u + v * v > tiny2):
            continue
        used += 1
        uu, uv, vv = u * u, u * v, v * v
        # height: w = A/2 u^2 + B uv + C/2 v^2 + D u^3 + E u^2 v + F u v^2 + G v^3
        row[0], row[1], row[2] = 0.5 * uu, uv, 0.5 * vv
        row[3], row[4], row[5], row[6] = uu * u, uu * v, u * vv, vv * v
        _accumulate(ata, atb, row, w)
        a = nx[q] * ux + ny[q] * uy + nz[q] * uz
        b = nx[q] * vx + ny[q] * vy + nz[q] * vz
        c = nx[q] * n0 + ny[q] * n1 + nz[q] * n2
        if not (c > MIN_NORMAL_Z) or not (math.isfinite(a) and math.isfinite(b)):
            continue
        # slopes of the neighbour's normal: w_u = -a/c, w_v = -b/c
        row[0], row[1], row[2], row[3], row[4], row[5], row[6] = u, v, 0.0, 3.0 * uu, 2.0 * uv, vv, 0.0
        _accumulate(ata, atb, row, -a / c)
        row[0], row[1], row[2], row[3], row[4], row[5], row[6] = 0.0, u, v, 0.0, uu, 2.0 * uv, 3.0 * vv
        _accumulate(ata, atb, row, -b / c)
    singular = solve_scaled(ata, atb, sol)
    # second derivatives back in unscaled coordinates
    finish_fit(p, -sol[0] * inv_r, -sol[1] * inv_r, -sol[2] * inv_r, singular, used, frame,
               k1, k2, d1, d2, reason)


@jit_parallel
def _nc_kernel(centres, lo, hi, radius, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, k1, k2, d1, d2, reason):
    parts = stamps.shape[0]
    for t in prange(parts):
        queue = queues[t]
        stamp = stamps[t]
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            count, queue = ball_support(p, radius[p] ** 2, adj_ptr, adj, x, y, z, stamp, queue)
            _nc_at(p, queue, count, radius[p], x, y, z, nx, ny, nz, k1, k2, d1, d2, reason)


@jit_parallel
def _qs_kernel(centres, lo, hi, radius, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, k1, k2, d1, d2, reason):
    parts = stamps.shape[0]
    for t in prange(parts):
        queue = queues[t]
        stamp = stamps[t]
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            count, queue = ball_support(p, radius[p] ** 2, adj_ptr, adj, x, y, z, stamp, queue)
            _qs_at(p, queue, count, radius[p], x, y, z, nx, ny, nz, k1, k2, d1, d2, reason)


@jit_parallel
def _an_kernel(centres, lo, hi, radius, adj_ptr, adj, x, y, z, nx, ny, nz, stamps, queues, k1, k2, d1, d2, reason):
    parts = stamps.shape[0]
    for t in prange(parts):
        queue = queues[t]
        stamp = stamps[t]
        ata, atb = np.empty((7, 7)), np.empty(7)
        row, sol = np.empty(7), np.empty(7)
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            count, queue = ball_support(p, radius[p] ** 2, adj_ptr, adj, x, y, z, stamp, queue)
            _an_at(p, queue, count, radius[p], x, y, z, nx, ny, nz, k1, k2, d1, d2, reason,
                   ata, atb, row, sol)


def iter_nc(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None):
    """Normal-curvature least squares over each vertex's support (3 unknowns, 1 equation per neighbour)."""
    return (yield from run_fit(mesh, normals, radii, _nc_kernel, chunk=chunk, centres=centres,
                                 features=features))


def iter_qs(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None):
    """Quadratic height fit over each vertex's support (3 unknowns, 1 equation per neighbour)."""
    return (yield from run_fit(mesh, normals, radii, _qs_kernel, chunk=chunk, centres=centres,
                                 features=features))


def iter_an(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None):
    """Adjacent-normal cubic fit over each vertex's support (7 unknowns, 3 equations per neighbour)."""
    return (yield from run_fit(mesh, normals, radii, _an_kernel, chunk=chunk, centres=centres,
                                 features=features))


_GI = "Goldfeather & Interrante 2004, A novel cubic-order algorithm for approximating principal direction vectors"

register(EstimatorSpec(
    name="nc", title="Normal curvature approximation", ranges=(1, 2, 3, 4), function=iter_nc,
    triangles_only=False, uses_normals=False, closed_ring=False, takes_points=True, reference=_GI, min_neighbours=MIN_PAIRS,
    summary="least squares of edge normal curvatures 2 (p-q).N/|p-q|^2", kernels=(_nc_kernel,),
))
register(EstimatorSpec(
    name="qs", title="Quadratic surface approximation", ranges=(1, 2, 3, 4), function=iter_qs,
    triangles_only=False, uses_normals=False, closed_ring=False, takes_points=True, reference=_GI, min_neighbours=MIN_PAIRS,
    summary="least-squares height fit A/2 u^2 + B uv + C/2 v^2 in the tangent frame", kernels=(_qs_kernel,),
))
register(EstimatorSpec(
    name="an", title="Adjacent-normal cubic approximation", ranges=(2, 3, 4), function=iter_an,
    triangles_only=False, uses_normals=True, closed_ring=False, takes_points=True, reference=_GI, min_neighbours=MIN_PAIRS,
    summary="cubic height fit using positions and the neighbours' normals (7 unknowns)", kernels=(_an_kernel,),
))
