"""Goldfeather & Interrante (2004) fits, extended to any range (paper §4.1).

- ``nc``: normal curvature approximation: ``t^T W t = 2 (p - q).N / |p - q|^2`` per neighbour.
- ``qs``: quadratic height fit ``w = A/2 u^2 + B u v + C/2 v^2``.
- ``an``: adjacent-normal cubic fit: the quadratic plus four cubic terms, with the neighbour's
  normal giving two more equations per neighbour (7 unknowns).

All three work on any polygon mesh and on borders (the fit is one-sided there).
"""

from __future__ import annotations

import numpy as np

from ..mesh import Mesh
from ._lsq import LocalPairs, normal_equations, run_fit, solve_normal_equations
from .registry import EstimatorSpec, register

MIN_NORMAL_Z = 0.1
"""A neighbour normal tilted more than ~84 degrees from the centre normal gives no slope equation."""


def _fit_nc(pairs: LocalPairs, normals: tuple):
    u, v, w, ok = pairs.u, pairs.v, pairs.w, pairs.usable
    l2 = u * u + v * v
    with np.errstate(invalid="ignore", divide="ignore"):
        kn = np.where(ok, -2.0 * w / (l2 + w * w), 0.0)
        inv = np.where(ok, 1.0 / l2, 0.0)
    # unit tangent t = (u, v) / |(u, v)|: t^T W t = e tu^2 + 2 f tu tv + g tv^2
    coeffs = [u * u * inv, 2.0 * u * v * inv, v * v * inv]
    ata, atb = normal_equations(pairs, [(coeffs, kn)])
    x, singular = solve_normal_equations(ata, atb)
    used = pairs.row_sum(ok)
    return x[:, 0], x[:, 1], x[:, 2], used, singular


def _fit_qs(pairs: LocalPairs, normals: tuple):
    u, v, w, ok = pairs.u, pairs.v, pairs.w, pairs.usable
    m = ok.astype(float)
    coeffs = [0.5 * u * u * m, u * v * m, 0.5 * v * v * m]
    ata, atb = normal_equations(pairs, [(coeffs, w * m)])
    x, singular = solve_normal_equations(ata, atb)
    used = pairs.row_sum(m)
    # W = -Hessian of the height along N
    return -x[:, 0], -x[:, 1], -x[:, 2], used, singular


def _fit_an(pairs: LocalPairs, normals: tuple):
    # Heights are lengths, slopes are not: solve in coordinates divided by the support radius so the
    # balance of the two kinds of equation (and so the result) does not depend on the mesh's scale.
    scale = pairs.radius[:, None]
    u, v, w, ok = pairs.u / scale, pairs.v / scale, pairs.w / scale, pairs.usable
    a, b, c = pairs.project(normals)
    m = ok.astype(float)
    slope_ok = ok & (c > MIN_NORMAL_Z) & np.isfinite(c)
    s = slope_ok.astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        fu = np.where(slope_ok, -a / c, 0.0)
        fv = np.where(slope_ok, -b / c, 0.0)
    uu, uv, vv = u * u, u * v, v * v
    us, vs = u * s, v * s
    # unknowns A, B, C, D, E, F, G of w = A/2 u^2 + B uv + C/2 v^2 + D u^3 + E u^2 v + F u v^2 + G v^3
    height = [0.5 * uu * m, uv * m, 0.5 * vv * m, uu * u * m, uu * v * m, u * vv * m, vv * v * m]
    slope_u = [us, vs, None, 3 * uu * s, 2 * uv * s, vv * s, None]
    slope_v = [None, us, vs, None, uu * s, 2 * uv * s, 3 * vv * s]
    ata, atb = normal_equations(pairs, [(height, w * m), (slope_u, fu), (slope_v, fv)])
    x, singular = solve_normal_equations(ata, atb)
    used = pairs.row_sum(m)
    with np.errstate(invalid="ignore", divide="ignore"):
        inv = 1.0 / pairs.radius  # second derivatives in unscaled coordinates
    return -x[:, 0] * inv, -x[:, 1] * inv, -x[:, 2] * inv, used, singular


def iter_nc(mesh: Mesh, normals: np.ndarray, k: int, *, block_size: int | None = None):
    """Normal-curvature least squares over the Rk support (3 unknowns, 1 equation per neighbour)."""
    return (yield from run_fit(mesh, normals, k, _fit_nc, min_pairs=3, block_size=block_size))


def iter_qs(mesh: Mesh, normals: np.ndarray, k: int, *, block_size: int | None = None):
    """Quadratic height fit over the Rk support (3 unknowns, 1 equation per neighbour)."""
    return (yield from run_fit(mesh, normals, k, _fit_qs, min_pairs=3, block_size=block_size))


def iter_an(mesh: Mesh, normals: np.ndarray, k: int, *, block_size: int | None = None):
    """Adjacent-normal cubic fit; support within (k-1) longest edges (7 unknowns, 3 equations per neighbour)."""
    # 35 normal-equation columns per pair (7 unknowns): smaller blocks keep the peak memory flat
    return (yield from run_fit(mesh, normals, k - 1, _fit_an, min_pairs=3, block_size=block_size,
                               pairs_per_block=250_000))


_GI = "Goldfeather & Interrante 2004, A novel cubic-order algorithm for approximating principal direction vectors"

register(EstimatorSpec(
    name="nc", title="Normal curvature approximation", ranges=(1, 2, 3, 4), function=iter_nc,
    triangles_only=False, uses_normals=False, closed_ring=False, reference=_GI,
    summary="least squares of edge normal curvatures 2 (p-q).N/|p-q|^2",
))
register(EstimatorSpec(
    name="qs", title="Quadratic surface approximation", ranges=(1, 2, 3, 4), function=iter_qs,
    triangles_only=False, uses_normals=False, closed_ring=False, reference=_GI,
    summary="least-squares height fit A/2 u^2 + B uv + C/2 v^2 in the tangent frame",
))
register(EstimatorSpec(
    name="an", title="Adjacent-normal cubic approximation", ranges=(2, 3, 4), function=iter_an,
    triangles_only=False, uses_normals=True, closed_ring=False, reference=_GI,
    summary="cubic height fit using positions and the neighbours' normals (7 unknowns)",
))
