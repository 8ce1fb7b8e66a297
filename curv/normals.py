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


def _corner_vectors(mesh: Mesh) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Vectors from each corner to the next and to the previous corner of its face.

    Returns two lists of three (h,) arrays (x, y, z components): 1-D gathers of single coordinates
    are several times faster than gathering rows of the (n, 3) vertex array.
    """
    idx = mesh.face_indices
    nxt, prv = mesh.corner_next, mesh.corner_prev
    a, b = [], []
    for k in range(3):
        here = np.take(np.ascontiguousarray(mesh.vertices[:, k]), idx)
        # the neighbours' coordinates come from the corner array itself: local indices, cache-friendly
        a.append(np.take(here, nxt) - here)
        b.append(np.take(here, prv) - here)
    return a, b


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
    (ax, ay, az), (bx, by, bz) = _corner_vectors(mesh)
    cross = [ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx]
    if weighting is NormalWeighting.MAX:
        with np.errstate(invalid="ignore", divide="ignore"):
            inv = 1.0 / ((ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz))
        inv[~np.isfinite(inv)] = 0.0  # a zero-length edge: the corner has no direction to give
        w = [c * inv for c in cross]
    elif weighting is NormalWeighting.AREA:
        w = list(mesh.face_vector_areas[mesh.corner_face].T)
    else:
        sin = np.sqrt(cross[0] ** 2 + cross[1] ** 2 + cross[2] ** 2)
        angle = np.arctan2(sin, ax * bx + ay * by + az * bz)
        fn = np.nan_to_num(mesh.face_normals)[mesh.corner_face]
        w = [fn[:, k] * angle for k in range(3)]
    idx = mesh.face_indices
    n = mesh.n_vertices
    acc = np.stack([np.bincount(idx, weights=w[k], minlength=n) for k in range(3)], axis=1)
    return normalize_rows(acc)
