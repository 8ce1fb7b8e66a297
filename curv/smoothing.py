"""Cotan-Laplacian smoothing of vertex positions and of per-vertex values (paper §5.3, Fig. 10)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .errors import MeshError
from .mesh import Mesh

__all__ = ["cotan_weights", "smooth_positions", "smooth_values"]


def cotan_weights(mesh: Mesh) -> sp.csr_matrix:
    """(n, n) symmetric sparse matrix of cotan weights ``(cot a + cot b) / 2`` per edge.

    Negative weights (obtuse triangles) are clamped to zero so that an explicit smoothing step
    stays a convex combination.

    Raises
    ------
    MeshError
        On a non-triangle mesh.
    """
    t = mesh.triangles
    v = mesh.vertices
    rows, cols, vals = [], [], []
    for c in range(3):
        i, j, o = t[:, (c + 1) % 3], t[:, (c + 2) % 3], t[:, c]
        a, b = v[i] - v[o], v[j] - v[o]
        cross = np.linalg.norm(np.cross(a, b), axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            cot = np.einsum("ij,ij->i", a, b) / cross
        cot = np.where(np.isfinite(cot), cot, 0.0)
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * cot, 0.5 * cot]
    w = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(mesh.n_vertices,) * 2)
    w.data = np.maximum(w.data, 0.0)
    return w


def _normalised(w: sp.csr_matrix, keep: np.ndarray | None = None) -> tuple[sp.csr_matrix, np.ndarray]:
    if keep is not None:
        w = w @ sp.diags(keep.astype(float))
    total = np.asarray(w.sum(axis=1)).ravel()
    with np.errstate(divide="ignore"):
        inv = np.where(total > 0, 1.0 / total, 0.0)
    return sp.diags(inv) @ w, total > 0


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
    avg, has = _normalised(cotan_weights(mesh))
    move = (has & ~mesh.border_vertices).astype(float)[:, None] * strength
    x = mesh.vertices.copy()
    for _ in range(iterations):
        x = x + move * (avg @ x - x)
    return mesh.with_vertices(x)


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
    avg, has = _normalised(cotan_weights(mesh), keep=valid)
    x = np.where(valid.reshape((-1,) + (1,) * (values.ndim - 1)), values, 0.0)
    lam = (strength * has).reshape((-1,) + (1,) * (values.ndim - 1))
    for _ in range(iterations):
        x = x + lam * (avg @ x - x)
    x[~valid] = np.nan
    return x
