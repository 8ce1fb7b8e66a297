"""Vertex normals from face geometry.

Max (1999) weights each face's normal at a corner by ``sin(angle) / (|e1| |e2|)``, i.e. the corner
cross product divided by both squared edge lengths; it is exact for vertices on a sphere and is the
normal the paper's study uses (§5.1). Area and angle weights are there for comparison.
"""

from __future__ import annotations

import enum

import numpy as np

from .mesh import Mesh

__all__ = ["NormalWeighting", "vertex_normals", "normalize_rows"]


class NormalWeighting(str, enum.Enum):
    """How the faces around a vertex are weighted."""

    MAX = "max"
    AREA = "area"
    ANGLE = "angle"


def normalize_rows(v: np.ndarray) -> np.ndarray:
    """Return ``v`` (k, 3) with unit rows; rows of (near) zero length become NaN."""
    norm = np.linalg.norm(v, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = v / norm[:, None]
    out[~(norm > 1e-300)] = np.nan
    return out


def _corner_vectors(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """(h, 3) vectors from each corner to the next and to the previous corner of its face."""
    v = mesh.vertices
    idx = mesh.face_indices
    p = v[idx]
    return v[idx[mesh.corner_next]] - p, v[idx[mesh.corner_prev]] - p


def vertex_normals(mesh: Mesh, *, weighting: NormalWeighting | str = NormalWeighting.MAX) -> np.ndarray:
    """Unit vertex normals.

    Parameters
    ----------
    mesh : Mesh
        Triangle or polygon mesh; orientation of the faces gives the side of the normal.
    weighting : {"max", "area", "angle"}
        Face weights: Max (1999), face area, or corner angle.

    Returns
    -------
    (n, 3) float64
        Unit normals; NaN rows for isolated vertices and vertices whose faces cancel or are all
        degenerate.
    """
    weighting = NormalWeighting(weighting)
    a, b = _corner_vectors(mesh)
    cross = np.cross(a, b)
    if weighting is NormalWeighting.MAX:
        la = np.einsum("ij,ij->i", a, a)
        lb = np.einsum("ij,ij->i", b, b)
        with np.errstate(invalid="ignore", divide="ignore"):
            w = cross / (la * lb)[:, None]
        w[~np.isfinite(w).all(axis=1)] = 0.0
    elif weighting is NormalWeighting.AREA:
        w = mesh.face_vector_areas[mesh.corner_face]
    else:
        sin = np.linalg.norm(cross, axis=1)
        cos = np.einsum("ij,ij->i", a, b)
        angle = np.arctan2(sin, cos)
        fn = np.nan_to_num(mesh.face_normals)[mesh.corner_face]
        w = fn * angle[:, None]
    idx = mesh.face_indices
    n = mesh.n_vertices
    acc = np.stack([np.bincount(idx, weights=w[:, k], minlength=n) for k in range(3)], axis=1)
    return normalize_rows(acc)
