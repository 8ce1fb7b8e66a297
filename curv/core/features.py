"""Sharp features: the one owner of the rule for which edges are creases.

An interior edge is a *feature edge* when the dihedral angle between its two faces (the angle
between their normals: 0 on a flat sheet, 90 degrees on a box's edge) exceeds a threshold, or
when a caller's per-edge mask says so. Border edges are never feature edges (they are borders).
A vertex on a feature edge is a *feature vertex*; a vertex where three or more feature edges meet
is a *corner*.

What the estimators do with them (``curv.estimate(..., features=30)``):

- the support search (:func:`curv.geometry.neighbourhood.expansion_adjacency`) reaches a feature vertex but
  never expands through it, so a vertex next to a crease is estimated from its own side only;
- neighbour-normal terms leave feature vertices' normals out (their vertex normal blends both
  sides); ``icc``, which interpolates normals over faces, gives each corner of a face at a
  feature vertex the normal of its own *sector* (:func:`sector_corner_normals`), and ``ru`` leaves
  the faces that touch a feature vertex out of its average (a sector normal at a curved rim is
  tilted by O(h), an O(1) error in a normal difference over one edge);
- ``csm`` and ``icc`` collect edges and faces from the centre's side only (never from a feature
  vertex), so the crease's dihedral term is left out;
- feature vertices get ``Reason.FEATURE`` (NaN values): the smooth curvature is undefined there.

The crease's strength is :func:`dihedral_angles` itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .errors import EstimatorError
from .mesh import Mesh

__all__ = ["FeatureSet", "feature_set", "feature_edges", "feature_vertices", "feature_corners", "dihedral_angles",
           "suggest_threshold", "sharp_edge_count", "has_many_sharp_edges", "check_angle", "sector_corner_normals", "SHARP_DEGREES", "MIN_GAP_DEGREES"]

SHARP_DEGREES = 30.0
"""Dihedral angle above which the mesh report counts an edge as sharp."""

MIN_GAP_DEGREES = 10.0
"""A threshold is suggested only where the sorted dihedral angles have a gap at least this wide."""

MIN_CREASE_EDGES = 3
"""Fewer edges than this (or than :data:`SHARP_SHARE` of them) above a gap are outliers, not creases."""

SHARP_SHARE = 0.001
"""Share of sharp edges above which the report and the advisor speak of "many sharp edges"."""


def dihedral_angles(mesh: Mesh) -> np.ndarray:
    """(e,) float64 angle in degrees between the normals of each edge's two faces (read-only).

    :attr:`curv.Mesh.dihedral_angles`: computed once per mesh (seconds at 10M vertices), so every
    threshold after the first costs one comparison.
    """
    return mesh.dihedral_angles


def check_angle(angle) -> float:
    """A feature angle in degrees (0-180) as a float; :class:`EstimatorError` otherwise (one line)."""
    try:
        value = float(angle)
    except (TypeError, ValueError):
        raise EstimatorError(f"features must be an angle in degrees or a per-edge mask; got {angle!r}") from None
    if not (0.0 <= value <= 180.0):
        raise EstimatorError(f"features angle must be between 0 and 180 degrees; got {angle!r}")
    return value


def feature_edges(mesh: Mesh, angle_or_mask) -> np.ndarray:
    """(e,) bool feature edges: dihedral angle above ``angle_or_mask`` degrees, or the given mask.

    Parameters
    ----------
    mesh : Mesh
    angle_or_mask : float or (e,) bool array_like
        A threshold in degrees (0-180), or a per-edge mask aligned with ``mesh.edges``. Border
        edges are cleared either way.

    Raises
    ------
    EstimatorError
        A negative or non-numeric angle, or a mask of the wrong shape.
    """
    if isinstance(angle_or_mask, (bool, np.bool_)) or np.ndim(angle_or_mask) != 0:
        mask = np.asarray(angle_or_mask)
        if mask.dtype != bool or mask.shape != (mesh.edges.shape[0],):
            raise EstimatorError(f"a features mask must be a bool array of shape ({mesh.edges.shape[0]},) "
                                 f"aligned with mesh.edges; got {mask.dtype} {mask.shape}")
        return mask & (mesh.edge_face_count >= 2)
    threshold = check_angle(angle_or_mask)
    with np.errstate(invalid="ignore"):
        return dihedral_angles(mesh) > threshold


def feature_vertices(mesh: Mesh, edges_mask: np.ndarray) -> np.ndarray:
    """(n,) bool: vertices on a feature edge (``edges_mask`` (e,) bool from :func:`feature_edges`)."""
    out = np.zeros(mesh.n_vertices, bool)
    out[mesh.edges[edges_mask].ravel()] = True
    return out


def feature_corners(mesh: Mesh, edges_mask: np.ndarray) -> np.ndarray:
    """(n,) bool: vertices where three or more feature edges meet."""
    return np.bincount(mesh.edges[edges_mask].ravel(), minlength=mesh.n_vertices) >= 3


def sharp_edge_count(mesh: Mesh, angle: float = SHARP_DEGREES) -> int:
    """Number of interior edges with a dihedral angle above ``angle`` degrees (for the mesh report)."""
    return int(feature_edges(mesh, angle).sum())


def has_many_sharp_edges(mesh: Mesh) -> bool:
    """Whether more than :data:`SHARP_SHARE` of the edges are sharp (then the report and the advisor
    suggest a threshold, if :func:`suggest_threshold` finds one)."""
    edges = mesh.edges.shape[0]
    return edges > 0 and sharp_edge_count(mesh) > SHARP_SHARE * edges


def suggest_threshold(mesh: Mesh) -> float | None:
    """A feature angle in degrees that separates the mesh's creases from its smooth edges, or None.

    The middle of the widest gap in the sorted dihedral angles whose upper side is sharp (above
    :data:`SHARP_DEGREES`) and holds enough edges (:data:`MIN_CREASE_EDGES`, :data:`SHARP_SHARE`),
    if that gap is at least :data:`MIN_GAP_DEGREES` wide; None for a mesh without sharp edges or
    whose angles spread without a clear gap (noise).
    """
    angles = dihedral_angles(mesh)
    angles = np.sort(angles[np.isfinite(angles)])
    if angles.size == 0 or angles[-1] <= SHARP_DEGREES:
        return None
    values = np.concatenate([[0.0], angles])
    gaps = np.diff(values)
    gaps[values[1:] <= SHARP_DEGREES] = 0.0  # only gaps below a sharp angle
    # a few outliers at the top of a noisy mesh's angles are not creases
    above = angles.size - np.arange(angles.size)
    gaps[above < max(MIN_CREASE_EDGES, SHARP_SHARE * angles.size)] = 0.0
    i = int(np.argmax(gaps))
    if gaps[i] < MIN_GAP_DEGREES:
        return None
    return float(round(0.5 * (values[i] + values[i + 1]), 1))


@dataclass(frozen=True)
class FeatureSet:
    """The feature edges of a mesh and what follows from them.

    Attributes
    ----------
    label : float or str
        The threshold in degrees, or ``"mask"`` for a caller's mask (for ``Curvature.info``).
    edges : (e,) bool
        Feature edges.
    vertices : (n,) bool
        Vertices on a feature edge (corners included).
    corners : (n,) bool
        Vertices where three or more feature edges meet.
    count : int
        Number of feature edges.
    """

    label: object
    edges: np.ndarray
    vertices: np.ndarray
    corners: np.ndarray
    count: int = 0

    @property
    def any(self) -> bool:
        """Whether there is any feature edge."""
        return self.count > 0


def feature_set(mesh: Mesh, angle_or_mask) -> FeatureSet:
    """The :class:`FeatureSet` of ``mesh`` for a threshold in degrees or a per-edge mask (read-only arrays)."""
    edges = feature_edges(mesh, angle_or_mask)
    label = "mask" if np.ndim(angle_or_mask) != 0 else check_angle(angle_or_mask)
    out = FeatureSet(label=label, edges=edges, vertices=feature_vertices(mesh, edges),
                     corners=feature_corners(mesh, edges), count=int(edges.sum()))
    for arr in (out.edges, out.vertices, out.corners):
        arr.setflags(write=False)
    return out


def sector_corner_normals(mesh: Mesh, normals: np.ndarray, features: FeatureSet | None) -> np.ndarray:
    """(h, 3) float64 normal of every face corner: its vertex's normal, or its sector's at a feature vertex.

    Around a feature vertex the faces split into *sectors*: runs of faces between two feature edges
    (or a feature edge and a border). A corner at a feature vertex gets the Max-weighted normal of
    the faces of its own sector, so a face next to a crease interpolates the normal of its own
    side. Every other corner gets ``normals`` of its vertex, unchanged.

    Parameters
    ----------
    mesh : Mesh
    normals : (n, 3) float64
        Unit vertex normals.
    features : FeatureSet or None
        None: every corner takes its vertex's normal.
    """
    out = normals[mesh.face_indices]
    if features is None or not features.any:
        return out
    corner_vertex = mesh.face_indices
    nxt = mesh.corner_next
    at_feature = features.vertices[corner_vertex]
    chosen = np.flatnonzero(at_feature)
    # Two corners of the same feature vertex are in one sector when their faces share a non-feature
    # interior edge at that vertex: the corner of a halfedge a->b and the corner after its twin b->a.
    edge = mesh.halfedge_edge
    ok = edge >= 0
    joinable = ok.copy()
    joinable[ok] = ~features.edges[edge[ok]] & (mesh.edge_face_count[edge[ok]] == 2)
    halves = np.flatnonzero(joinable & (at_feature | at_feature[nxt]))
    order = halves[np.argsort(edge[halves], kind="stable")]
    sorted_edges = edge[order]
    first = np.flatnonzero((sorted_edges[:-1] == sorted_edges[1:]))
    c0, c1 = order[first], order[first + 1]  # c0: a->b in one face, c1: b->a in the other
    rows = np.concatenate([c0, nxt[c0]])
    cols = np.concatenate([nxt[c1], c1])
    keep = at_feature[rows]
    local = np.full(corner_vertex.size, -1, np.int64)
    local[chosen] = np.arange(chosen.size)
    graph = sp.csr_matrix((np.ones(int(keep.sum())), (local[rows[keep]], local[cols[keep]])),
                          shape=(chosen.size, chosen.size))
    _, sector = sp.csgraph.connected_components(graph, directed=False)
    # Max's weight of each chosen corner: (a x b) / (|a|^2 |b|^2) with a, b its two edges
    x = mesh.vertices
    a = x[corner_vertex[nxt[chosen]]] - x[corner_vertex[chosen]]
    b = x[corner_vertex[mesh.corner_prev[chosen]]] - x[corner_vertex[chosen]]
    denominator = np.einsum("ij,ij->i", a, a) * np.einsum("ij,ij->i", b, b)
    with np.errstate(invalid="ignore", divide="ignore"):
        weight = np.where(denominator[:, None] > 0, np.cross(a, b) / denominator[:, None], 0.0)
    summed = np.zeros((sector.max() + 1 if sector.size else 0, 3))
    np.add.at(summed, sector, weight)
    length = np.linalg.norm(summed, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(length > 0, summed / length, np.nan)
    out[chosen] = unit[sector]
    return out
