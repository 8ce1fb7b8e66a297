"""Model error or noise? The residual spread of a quadratic and a quartic local height fit.

A local quadric misses a smooth surface by its cubic and higher terms (and, on a coarse or
irregularly lifted mesh, by the distortion of the support), and misses noise by the noise itself.
A quartic over the same support absorbs most of the first and none of the second: per vertex, the
residual standard deviations (the residual sum of squares over the degrees of freedom left) of the
two fits are about equal where noise dominates and the quartic's is a small part of the quadric's
where the surface's own shape does. :func:`fit_residual_spreads` measures both on a fixed sample of
vertices; :func:`curv.advice.features.raw_measures` turns them into the ``noise_raw4`` and
``residual_ratio`` features.
"""

from __future__ import annotations

import numpy as np

from ..core.jit import jit, jit_parallel, launch, prange
from ..core.mesh import Mesh

__all__ = ["RESIDUAL_RANGE", "RESIDUAL_SAMPLE", "fit_residual_spreads"]

RESIDUAL_RANGE = 3
"""k of the Rk ball both fits collect their support in (the centre's own support rule,
:func:`curv.core.ranges.ball_radii`, without neighbour normals)."""

RESIDUAL_SAMPLE = 1000
"""Centres the spreads are measured at: every vertex up to this many, a fixed random sample (seed 0)
above."""

_N2 = 6
_N4 = 15
_MIN_POINTS = _N4 + 6
"""A centre is measured when its support and itself hold at least this many points (six degrees of
freedom left to the quartic)."""


@jit
def _spreads_at(p, lo, hi, indices, x, y, z, normals, a):
    """(quadric spread, quartic spread) at centre ``p`` (NaN, NaN where it cannot be fitted).

    ``a`` is scratch of shape (m, 15) with m >= the support size + 1."""
    nx, ny, nz = normals[p, 0], normals[p, 1], normals[p, 2]
    m = hi - lo + 1
    if m < _MIN_POINTS or not (np.isfinite(nx) and np.isfinite(ny) and np.isfinite(nz)):
        return np.nan, np.nan
    # a tangent basis (e1, e2) orthogonal to the normal
    if abs(nx) < 0.9:
        tx, ty, tz = 0.0, -nz, ny  # n x (1, 0, 0)
    else:
        tx, ty, tz = nz, 0.0, -nx  # n x (0, 1, 0)
    t = np.sqrt(tx * tx + ty * ty + tz * tz)
    e1x, e1y, e1z = tx / t, ty / t, tz / t
    e2x, e2y, e2z = ny * e1z - nz * e1y, nz * e1x - nx * e1z, nx * e1y - ny * e1x
    u = np.empty(m)
    v = np.empty(m)
    h = np.empty(m)
    u[0] = 0.0
    v[0] = 0.0
    h[0] = 0.0
    scale = 0.0
    for i in range(1, m):
        q = indices[lo + i - 1]
        dx, dy, dz = x[q] - x[p], y[q] - y[p], z[q] - z[p]
        u[i] = e1x * dx + e1y * dy + e1z * dz
        v[i] = e2x * dx + e2y * dy + e2z * dz
        h[i] = nx * dx + ny * dy + nz * dz
        scale = max(scale, abs(u[i]), abs(v[i]))
    if not scale > 0:
        return np.nan, np.nan
    for i in range(m):  # monomials of degree <= 4 in the scaled (u, v), by increasing degree
        uu, vv = u[i] / scale, v[i] / scale
        col = 0
        for d in range(5):
            for j in range(d + 1):
                a[i, col] = uu ** (d - j) * vv ** j
                col += 1
    out2 = np.nan
    out4 = np.nan
    for degree in (2, 4):
        n_unknowns = _N2 if degree == 2 else _N4
        sub = np.ascontiguousarray(a[:m, :n_unknowns])
        coef, _, rank, _ = np.linalg.lstsq(sub, h, -1.0)
        if rank < n_unknowns:
            continue
        r = h - sub @ coef
        spread = np.sqrt(np.sum(r * r) / (m - n_unknowns))
        if degree == 2:
            out2 = spread
        else:
            out4 = spread
    return out2, out4


@jit_parallel
def _spreads(centres, indptr, indices, x, y, z, normals, width, out2, out4):
    for c in prange(centres.size):
        a = np.empty((width, _N4))
        out2[c], out4[c] = _spreads_at(centres[c], indptr[c], indptr[c + 1], indices, x, y, z, normals, a)


def fit_residual_spreads(mesh: Mesh, *, normals: np.ndarray | None = None,
                         sample: int = RESIDUAL_SAMPLE) -> tuple[np.ndarray, np.ndarray]:
    """Residual standard deviations of a quadratic and a quartic height fit at sampled vertices.

    At each centre p the support of the R3 ball (:data:`RESIDUAL_RANGE`) and p itself are put in the
    frame of p's normal, and the heights ``n·(x_j - x_p)`` are fitted by least squares with every
    monomial of the tangent coordinates up to degree 2 (6 unknowns) and up to degree 4 (15); the
    spread of each is ``sqrt(sum of squared residuals / (points - unknowns))``, an unbiased estimate
    of the noise's variance where noise alone is left.

    Parameters
    ----------
    mesh : Mesh
    normals : (n, 3) float64, optional
        Unit vertex normals of the frames; default Max-weighted.
    sample : int
        Centres: all vertices up to this many, else a fixed random sample of this size (seed 0).

    Returns
    -------
    spread2, spread4 : (c,) float64
        At each centre, in mesh units; NaN where the support holds fewer than 21 points, the normal
        is unusable or a fit is rank deficient.
    """
    from ..core.ranges import Range, ball_radii
    from ..geometry.neighbourhood import supports
    from ..geometry.normals import cached_max_normals

    n = mesh.n_vertices
    centres = (np.arange(n, dtype=np.int64) if n <= sample
               else np.sort(np.random.default_rng(0).choice(n, sample, replace=False)).astype(np.int64))
    normals = cached_max_normals(mesh) if normals is None else np.ascontiguousarray(normals, np.float64)
    radii = ball_radii(mesh, Range(k=float(RESIDUAL_RANGE)), uses_normals=False)
    indptr, indices = supports(mesh, radii, centres)
    x, y, z = (np.ascontiguousarray(mesh.vertices[:, i]) for i in range(3))
    width = int(np.diff(indptr).max(initial=0)) + 1
    out2, out4 = np.empty(centres.size), np.empty(centres.size)
    launch(_spreads, centres, indptr, indices, x, y, z, normals, width, out2, out4)
    return out2, out4
