"""Cotan-Laplacian smoothing of vertex positions and of per-vertex values (paper §5.3, Fig. 10).

One explicit step moves every vertex towards the cotan-weighted average of its edge neighbours,
``x_p <- x_p + lambda (sum_j w_pj x_j / sum_j w_pj - x_p)`` with ``w_pj = (cot a + cot b) / 2``
over the two angles opposite edge (p, j). The weights live on the rows of :attr:`Mesh.adjacency`
and are computed per vertex from its corners; a step is one pass over those rows.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.errors import MeshError
from ..core.jit import jit, jit_parallel, launch, prange
from ..core.mesh import Mesh

__all__ = ["smooth_positions", "smooth_values", "KERNELS"]


@jit
def _half_cot(x, o, i, j):
    """``cot / 2`` of the angle at o of triangle (o, i, j); 0 where the triangle has no area."""
    ax, ay, az = x[i, 0] - x[o, 0], x[i, 1] - x[o, 1], x[i, 2] - x[o, 2]
    bx, by, bz = x[j, 0] - x[o, 0], x[j, 1] - x[o, 1], x[j, 2] - x[o, 2]
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    sin = math.sqrt(cx * cx + cy * cy + cz * cz)
    if sin == 0.0:
        return 0.0
    cot = (ax * bx + ay * by + az * bz) / sin
    return 0.5 * cot if math.isfinite(cot) else 0.0


@jit
def _add_at(row_lo, row_hi, neighbours, q, value, weights):
    """``weights[k] += value`` at the entry of neighbour q in the (sorted) row ``row_lo:row_hi``."""
    for k in range(row_lo, row_hi):
        if neighbours[k] == q:
            weights[k] += value
            return


@jit_parallel
def _cotan_rows(indptr, neighbours, corner_ptr, corners, indices, corner_next, corner_prev, x, weights):
    # row p: each corner (p, b, q) of a face gives edge (p, b) the angle at q and edge (p, q) the angle at b
    for p in prange(indptr.size - 1):
        lo, hi = indptr[p], indptr[p + 1]
        for k in range(lo, hi):
            weights[k] = 0.0
        for i in range(corner_ptr[p], corner_ptr[p + 1]):
            c = corners[i]
            b, q = indices[corner_next[c]], indices[corner_prev[c]]
            if b != p:
                _add_at(lo, hi, neighbours, b, _half_cot(x, q, p, b), weights)
            if q != p:
                _add_at(lo, hi, neighbours, q, _half_cot(x, b, q, p), weights)
        # obtuse angles give negative weights: clamp, so that a step stays a convex combination
        for k in range(lo, hi):
            weights[k] = max(weights[k], 0.0)


@jit_parallel
def _smooth_step(indptr, neighbours, weights, keep, step, x, out):
    """``out_p = x_p + step_p (average of the kept neighbours - x_p)``; ``x`` is (n, c).

    The average weighs neighbour j by ``w_pj keep_j``; a vertex whose weights sum to 0 stays.
    """
    for p in prange(indptr.size - 1):
        total = 0.0
        for k in range(indptr[p], indptr[p + 1]):
            total += weights[k] * keep[neighbours[k]]
        if not total > 0:  # no neighbour to average: the vertex stays
            for c in range(x.shape[1]):
                out[p, c] = x[p, c]
            continue
        inv = 1.0 / total
        for c in range(x.shape[1]):
            avg = 0.0
            for k in range(indptr[p], indptr[p + 1]):
                avg += inv * (weights[k] * keep[neighbours[k]]) * x[neighbours[k], c]
            out[p, c] = x[p, c] + step[p] * (avg - x[p, c])


KERNELS = (_cotan_rows, _smooth_step)
"""The numba dispatchers of this module (for :func:`curv.core.jit.compile_pending`)."""


def _cotan_data(mesh: Mesh) -> np.ndarray:
    """The cotan weights on the entries of ``mesh.adjacency`` (clamped at 0)."""
    adjacency = mesh.adjacency
    indptr, neighbours = adjacency.indptr.astype(np.int64), adjacency.indices.astype(np.int64)
    corner_ptr, corners = mesh.vertex_corners
    weights = np.empty(neighbours.size)
    launch(_cotan_rows, indptr, neighbours, corner_ptr, corners, mesh.face_indices, mesh.corner_next,
           mesh.corner_prev, mesh.vertices, weights)
    return weights



def _smooth(mesh: Mesh, x: np.ndarray, keep: np.ndarray, step: np.ndarray, iterations: int) -> np.ndarray:
    adjacency = mesh.adjacency
    indptr, neighbours = adjacency.indptr.astype(np.int64), adjacency.indices.astype(np.int64)
    weights = _cotan_data(mesh)
    x = np.ascontiguousarray(x, dtype=np.float64)
    for _ in range(iterations):
        out = np.empty_like(x)
        launch(_smooth_step, indptr, neighbours, weights, keep, step, x, out)
        x = out
    return x


def smooth_positions(mesh: Mesh, *, iterations: int = 1, strength: float = 0.5) -> Mesh:
    """Move vertices towards the cotan-weighted average of their neighbours; borders stay fixed.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    iterations : int
        Number of explicit steps.
    strength : float
        Step size lambda in (0, 1]: ``x <- x + lambda (avg(x) - x)``.

    Returns
    -------
    Mesh
        Same connectivity, smoothed positions.
    """
    if mesh.n_faces and not mesh.is_triangular:
        raise MeshError("mesh smoothing uses cotan weights and needs a triangle mesh")
    keep = np.ones(mesh.n_vertices)
    # the border vertices stay
    step = np.where(mesh.border_vertices, 0.0, strength)
    return mesh.with_vertices(_smooth(mesh, mesh.vertices, keep, step, iterations))


def smooth_values(mesh: Mesh, values: np.ndarray, valid: np.ndarray, *, iterations: int = 1,
                  strength: float = 0.5) -> np.ndarray:
    """Smooth per-vertex values with cotan weights over valid neighbours.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    values : (n,) or (n, k) float64
        Values to smooth; entries at invalid vertices are ignored.
    valid : (n,) bool
        Vertices whose values may be used; invalid ones stay NaN.
    iterations, strength
        As in :func:`smooth_positions`.

    Returns
    -------
    ndarray
        Same shape as ``values``.
    """
    if mesh.n_faces and not mesh.is_triangular:
        raise MeshError("value smoothing uses cotan weights and needs a triangle mesh")
    x = np.where(valid.reshape((-1,) + (1,) * (values.ndim - 1)), values, 0.0).reshape(values.shape[0], -1)
    out = _smooth(mesh, x, valid.astype(np.float64), np.full(mesh.n_vertices, float(strength)), iterations)
    out = out.reshape(values.shape)
    out[~valid] = np.nan
    return out
