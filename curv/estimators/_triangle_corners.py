"""Geometry of the triangle at every corner of a :class:`curv.corners.CornerChunk` (meyer, ru).

Each corner is seen from its own vertex ``a``; ``b`` and ``c`` are the next and previous vertices
of its triangle. Vectors are kept as three (k,) component arrays: the chunk's arrays stay small
and contiguous, and 1-D gathers are several times faster than gathering rows of (n, 3) arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..corners import CornerChunk
from ..validity import Reason

__all__ = ["TriangleCorners", "dot", "cross", "closed_ring_reasons"]

Vec = tuple[np.ndarray, np.ndarray, np.ndarray]


def dot(a: Vec, b: Vec) -> np.ndarray:
    """Row-wise dot product of two vectors given as three (k,) component arrays."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vec, b: Vec) -> Vec:
    """Cross product of two vectors given as three (k,) component arrays."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@dataclass
class TriangleCorners:
    """Edges, cotangents and mixed Voronoi area of the corners of one chunk.

    Attributes
    ----------
    ab, ac : three (k,) float64
        Edge vectors from the corner's vertex to the next and to the previous vertex.
    normal : three (k,) float64
        ``ab x ac``: the face normal times twice the area.
    ab_len2, ac_len2 : (k,) float64
        Squared edge lengths.
    twice_area : (k,) float64
        Twice the triangle's area, ``|ab x ac|``.
    degenerate : (k,) bool
        The corner's face is degenerate (:attr:`curv.Mesh.degenerate_faces`).
    cos_a : (k,) float64
        ``ab . ac`` (the corner angle's cosine times both edge lengths).
    cot_b, cot_c : (k,) float64
        Cotangents at the other two corners (0 on degenerate faces).
    mixed_area : (k,) float64
        The corner's share of Meyer's mixed area ``A_mixed`` (0 on degenerate faces): its Voronoi
        area in a non-obtuse triangle, half the triangle at an obtuse corner, a quarter at the other
        corners of an obtuse triangle.
    """

    ab: Vec
    ac: Vec
    normal: Vec
    ab_len2: np.ndarray
    ac_len2: np.ndarray
    twice_area: np.ndarray
    degenerate: np.ndarray
    cos_a: np.ndarray
    cot_b: np.ndarray
    cot_c: np.ndarray
    mixed_area: np.ndarray

    @classmethod
    def of(cls, chunk: CornerChunk, xyz: Vec, degenerate_faces: np.ndarray,
           corner_face: np.ndarray) -> "TriangleCorners":
        """Compute them for ``chunk`` from the vertex coordinates ``xyz`` (three (n,) arrays)."""
        here = [chunk.expand(coord) for coord in xyz]
        ab = tuple(np.take(coord, chunk.nxt) - p for coord, p in zip(xyz, here))
        ac = tuple(np.take(coord, chunk.prv) - p for coord, p in zip(xyz, here))
        normal = cross(ab, ac)
        twice = np.sqrt(dot(normal, normal))
        bad = np.take(degenerate_faces, np.take(corner_face, chunk.corners))
        twice_safe = np.where(bad, 1.0, twice)
        ab_len2, ac_len2, cos_a = dot(ab, ab), dot(ac, ac), dot(ab, ac)
        # (a - b).(c - b) and (a - c).(b - c), from the dot products already at hand
        cos_b, cos_c = ab_len2 - cos_a, ac_len2 - cos_a
        cot_b, cot_c = cos_b / twice_safe, cos_c / twice_safe
        # edge ab faces corner c, edge ac faces corner b
        area = 0.125 * (cot_c * ab_len2 + cot_b * ac_len2)
        area = np.where(cos_a < 0, 0.25 * twice, np.where((cos_b < 0) | (cos_c < 0), 0.125 * twice, area))
        for arr in (cot_b, cot_c, area):
            arr[bad] = 0.0
        return cls(ab, ac, normal, ab_len2, ac_len2, twice, bad, cos_a, cot_b, cot_c, area)

    def angle(self) -> np.ndarray:
        """(k,) float64 corner angle at ``a`` in radians (0 on degenerate faces)."""
        out = np.arctan2(self.twice_area, self.cos_a)
        out[self.degenerate] = 0.0
        return out


def closed_ring_reasons(chunk: CornerChunk, tc: TriangleCorners, singular: np.ndarray, normals: np.ndarray,
                        border_vertices: np.ndarray, nonmanifold: np.ndarray) -> np.ndarray:
    """Reason codes of a chunk's vertices for an estimator that needs a closed, clean 1-ring.

    Later rules override earlier ones: SINGULAR where ``singular``; BORDER on or next to a border;
    DEGENERATE touching a degenerate face or without a finite normal; NONMANIFOLD where
    ``nonmanifold`` (the chunk's rows).

    Parameters
    ----------
    chunk, tc : CornerChunk, TriangleCorners
    singular : (r,) bool
    normals : (r, 3) float64
        The chunk's vertex normals.
    border_vertices : (n,) bool
        :attr:`curv.Mesh.border_vertices`.
    nonmanifold : (r,) bool

    Returns
    -------
    (r,) uint8
    """
    reason = np.full(chunk.stop - chunk.start, Reason.OK, np.uint8)
    reason[singular] = Reason.SINGULAR
    reason[chunk.ring_any(border_vertices)] = Reason.BORDER
    reason[chunk.any(tc.degenerate) | ~np.isfinite(normals).all(axis=1)] = Reason.DEGENERATE
    reason[nonmanifold] = Reason.NONMANIFOLD
    return reason
