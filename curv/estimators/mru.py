"""Modified Rusinkiewicz (paper §4.2): per-vertex least squares of normal differences.

For every neighbour q in range, the shape operator maps the tangent offset of ``q - p`` to the
tangent part of ``N_q - N_p`` (eq. 4.1/4.2, with our sign convention dN = W t): two equations in the
three unknowns (e, f, g) per neighbour. No per-face step, so it works on any polygon mesh.
"""

from __future__ import annotations

import numpy as np

from ..mesh import Mesh
from ._lsq import LocalPairs, normal_equations, run_fit, solve_normal_equations
from .registry import EstimatorSpec, register


def _fit_mru(pairs: LocalPairs, normals: tuple):
    u, v = pairs.u, pairs.v
    # tangent part of N_q - N_p: N_p is orthogonal to its own frame's U and V, so only N_q remains
    a, b, _ = pairs.project(normals)
    ok = pairs.usable & np.isfinite(a) & np.isfinite(b)
    m = ok.astype(float)
    u, v = u * m, v * m
    a, b = np.where(ok, a, 0.0), np.where(ok, b, 0.0)
    # [u v 0] (e f g)^T = a ;  [0 u v] (e f g)^T = b
    ata, atb = normal_equations(pairs, [([u, v, None], a), ([None, u, v], b)])
    x, singular = solve_normal_equations(ata, atb)
    used = pairs.row_sum(m)
    return x[:, 0], x[:, 1], x[:, 2], used, singular


def iter_mru(mesh: Mesh, normals: np.ndarray, k: int, *, block_size: int | None = None):
    """Normal-difference least squares over neighbours within (k-1) longest 1-ring edges."""
    return (yield from run_fit(mesh, normals, k - 1, _fit_mru, min_pairs=3, block_size=block_size))


register(EstimatorSpec(
    name="mru", title="Modified Rusinkiewicz", ranges=(2, 3, 4), function=iter_mru,
    triangles_only=False, uses_normals=True, closed_ring=False,
    reference="Multivariate analysis of curvature estimators, §4.2 (after Rusinkiewicz 2004)",
    summary="per-vertex least squares of neighbour normal differences (eq. 4.1/4.2)",
))
