"""Vertex normals from face geometry.

Max (1999) weights each face's normal at a corner by ``sin(angle) / (|e1| |e2|)``, i.e. the corner
cross product divided by both squared edge lengths; it is exact for vertices on a sphere and is the
normal the paper's study uses (§5.1). Area and angle weights are there for comparison.
"""

from __future__ import annotations

import enum

import numpy as np

from .corners import CornerChunk, map_vertex_chunks
from .mesh import Mesh

__all__ = ["NormalWeighting", "vertex_normals", "normalize_rows", "max_corner_weights", "unusable_normal_vertices"]


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


def unusable_normal_vertices(mesh: Mesh) -> np.ndarray:
    """(n,) bool: vertices whose normal means nothing, so no estimate may use it.

    Where the faces around a vertex are not one consistently oriented fan (a non-manifold vertex,
    or an endpoint of an edge whose two faces disagree on orientation), the averaged normal mixes
    unrelated sheets.
    """
    out = mesh.nonmanifold_vertices.copy()
    out[mesh.edges[mesh.inconsistent_edges].reshape(-1)] = True
    return out


def max_corner_weights(cross: tuple, a_len2: np.ndarray, b_len2: np.ndarray) -> list:
    """Max (1999) weighted normal of each corner from its two edge vectors a and b.

    Parameters
    ----------
    cross : three (k,) float64
        Components of ``a x b``, a and b the edges from the corner's vertex to the next and to the
        previous vertex of its face.
    a_len2, b_len2 : (k,) float64
        ``|a|^2`` and ``|b|^2``.

    Returns
    -------
    list of three (k,) float64
        ``(a x b) / (|a|^2 |b|^2)``; zero where an edge has zero length.
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        inv = 1.0 / (a_len2 * b_len2)
    inv[~np.isfinite(inv)] = 0.0  # a zero-length edge: the corner has no direction to give
    return [c * inv for c in cross]


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
    xyz = tuple(np.ascontiguousarray(mesh.vertices[:, k]) for k in range(3))
    if weighting is NormalWeighting.AREA:
        face_weight = mesh.face_vector_areas
    elif weighting is NormalWeighting.ANGLE:
        face_weight = np.nan_to_num(mesh.face_normals)
    acc = np.zeros((mesh.n_vertices, 3))
    corner_face = mesh.corner_face

    def work(chunk: CornerChunk) -> None:
        # edges from the corner's vertex to the next and to the previous corner of its face
        here = [chunk.expand(coord) for coord in xyz]
        ax, ay, az = (np.take(coord, chunk.nxt) - p for coord, p in zip(xyz, here))
        bx, by, bz = (np.take(coord, chunk.prv) - p for coord, p in zip(xyz, here))
        cross = (ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx)
        if weighting is NormalWeighting.MAX:
            w = max_corner_weights(cross, ax * ax + ay * ay + az * az, bx * bx + by * by + bz * bz)
        else:
            fw = np.take(face_weight, np.take(corner_face, chunk.corners), axis=0)
            if weighting is NormalWeighting.AREA:
                w = list(fw.T)
            else:
                sin = np.sqrt(cross[0] ** 2 + cross[1] ** 2 + cross[2] ** 2)
                angle = np.arctan2(sin, ax * bx + ay * by + az * bz)
                w = [fw[:, k] * angle for k in range(3)]
        for k in range(3):
            acc[chunk.start:chunk.stop, k] = chunk.sum(w[k])

    map_vertex_chunks(mesh, work)
    return normalize_rows(acc)
