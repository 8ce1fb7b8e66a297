"""The mesh model: vertices, polygon faces and the connectivity every estimator needs.

A :class:`Mesh` is immutable once built; every derived array (edges, adjacency, borders, normals of
faces, ...) is computed on first use and cached. Faces may be triangles or general polygons; they are
stored flat (``face_indices`` with ``face_offsets``) so mixed meshes cost nothing extra.
"""

from __future__ import annotations

from functools import cached_property
import numpy as np
import scipy.sparse as sp

from . import connectivity as _kernels
from .errors import MeshError
from .face_input import flat_faces
from .jit import launch
from .mesh_report import MeshReport, mesh_report
from .pointcloud import PointSet, as_positions

__all__ = ["Mesh", "MeshReport", "scatter_sample", "scattered_corners"]

SCATTERED_SPAN = 65536
"""A face whose vertex indices span more than this many vertices (median over a sample of faces)
marks a numbering too scattered for the caches (:meth:`Mesh.scattered_order`): the coordinates of
that many vertices (1.5 MB) no longer stay in a core's cache between neighbouring vertices."""


def _part(of: str, index: int, doc: str) -> property:
    """A read-only attribute: item ``index`` of the tuple the (cached) attribute ``of`` holds, for the
    arrays that one computation gives together (the corner links, the edge table, the corner pass)."""
    return property(lambda mesh: getattr(mesh, of)[index], doc=doc)


def scatter_sample(n_faces: int, sample: int = 4096) -> np.ndarray:
    """(s,) int64: the faces :meth:`Mesh.scattered_order` reads, evenly spaced over ``n_faces``."""
    return np.linspace(0, n_faces - 1, min(sample, n_faces)).astype(np.int64)


def scattered_corners(n_vertices: int, corners: np.ndarray) -> bool:
    """:meth:`Mesh.scattered_order`'s rule on the first three corners (s, 3) of its sampled faces
    (:func:`scatter_sample`), for a caller that reads a mesh's faces from a file a few at a time."""
    if n_vertices <= SCATTERED_SPAN or corners.shape[0] == 0:
        return False
    return bool(np.median(corners.max(axis=1) - corners.min(axis=1)) > SCATTERED_SPAN)


class Mesh(PointSet):
    """A polygon mesh with validated data and cached connectivity.

    Parameters
    ----------
    vertices : array_like, shape (n, 3)
        Vertex positions; must be finite.
    faces : array_like, shape (m, k), or sequence of sequences of int
        Polygons as vertex indices, counter-clockwise seen from outside (the normal side).
        A 2-D array may pad shorter polygons with trailing ``-1``.

    Raises
    ------
    MeshError
        For malformed data, naming what is wrong and where. Degenerate faces, isolated and
        non-manifold vertices are *not* errors: they are reported by :meth:`report` and
        flagged in the masks below.
    """

    def __init__(self, vertices, faces):
        v = as_positions(vertices, "vertex", "vertices", "mesh")
        indices, offsets = flat_faces(faces, v.shape[0])
        indices.setflags(write=False)
        offsets.setflags(write=False)
        self._vertices = v
        self._indices = indices
        self._offsets = offsets
        self.info: dict = {}
        """Free-form provenance (source file, repairs done on load); not part of the geometry."""

    # ------------------------------------------------------------------ basic data
    @property
    def face_indices(self) -> np.ndarray:
        """(sum of face sizes,) int64: the vertex indices of all faces, one after the other."""
        return self._indices

    @property
    def face_offsets(self) -> np.ndarray:
        """(m + 1,) int64: face ``i`` is ``face_indices[face_offsets[i]:face_offsets[i + 1]]``."""
        return self._offsets

    @property
    def n_faces(self) -> int:
        return self._offsets.size - 1

    @cached_property
    def face_sizes(self) -> np.ndarray:
        """(m,) int64 number of vertices of each face."""
        return np.diff(self._offsets)

    @cached_property
    def is_triangular(self) -> bool:
        """True when every face is a triangle."""
        return bool(np.all(self.face_sizes == 3))

    @cached_property
    def faces(self) -> np.ndarray:
        """(m, kmax) int64 faces, padded with -1 where a polygon has fewer than kmax vertices."""
        kmax = int(self.face_sizes.max())
        if self.is_triangular:  # the flat corners already are the rows
            return self._indices.reshape(-1, 3).copy()
        out = np.full((self.n_faces, kmax), -1, dtype=np.int64)
        col = np.arange(self._indices.size) - np.repeat(self._offsets[:-1], self.face_sizes)
        out[self.corner_face, col] = self._indices
        return out

    @property
    def triangles(self) -> np.ndarray:
        """(m, 3) int64 triangles; raises :class:`MeshError` on a mesh with other polygons."""
        if not self.is_triangular:
            kinds = sorted(set(self.face_sizes.tolist()) - {3})
            raise MeshError(f"needs a triangle mesh, but the mesh has faces with {kinds} vertices")
        return self.faces

    # ------------------------------------------------------------------ vertex order
    def scattered_order(self, *, sample: int = 4096) -> bool:
        """Whether the vertex numbering is too scattered for the kernels' caches.

        Every kernel walks the vertices in index order and reads each one's neighbours: where the
        vertices of a face have nearby indices (a scan, a grid, a subdivision), the neighbours of
        consecutive vertices share cache lines; in a shuffled numbering every read is a miss (a fit
        ran about 7x slower on a shuffled 1M sphere). Scattered: the median index span of
        ``sample`` evenly spaced faces (largest index minus smallest, over their first three
        corners) exceeds :data:`SCATTERED_SPAN` vertices. It reads ``sample`` faces, not the mesh.
        """
        m = self.n_faces
        if self.n_vertices <= SCATTERED_SPAN or m == 0:
            return False
        first = self._offsets[scatter_sample(m, sample)]
        return scattered_corners(self.n_vertices, self._indices[first[:, None] + np.arange(3)])

    def renumbered(self, order: np.ndarray) -> "Mesh":
        """The same mesh with its vertices renumbered: vertex i of the result is vertex ``order[i]``.

        Parameters
        ----------
        order : (n,) int64
            A permutation of the vertices.

        The faces keep their order and their corners' order, so every face-level array (degenerate
        faces, areas) is the same; per-vertex results go back with ``out[order] = result``. (Sorting
        the faces by their new vertices as well cost as much as it saved the kernels.)
        """
        rank = np.empty(self.n_vertices, np.int64)
        rank[order] = np.arange(self.n_vertices, dtype=np.int64)
        twin = Mesh.__new__(Mesh)
        twin._vertices = self._vertices[order]
        twin._indices = rank[self._indices]
        twin._offsets = self._offsets
        twin.info = dict(self.info)
        for arr in (twin._vertices, twin._indices):
            arr.setflags(write=False)
        return twin

    # ------------------------------------------------------------------ corners and edges
    @cached_property
    def corner_face(self) -> np.ndarray:
        """(h,) int64 face of each corner (one corner per entry of ``face_indices``)."""
        return np.repeat(np.arange(self.n_faces, dtype=np.int64), self.face_sizes)

    @cached_property
    def _corner_links(self) -> tuple[np.ndarray, np.ndarray]:
        h = self._indices.size
        # int32 where it fits: two (h,) arrays kept for the mesh's life (960 MB as int64 at 10M vertices)
        kind = np.int32 if h < 2**31 else np.int64
        nxt, prev = np.empty(h, kind), np.empty(h, kind)
        launch(_kernels.corner_links, self._offsets, nxt, prev)
        return nxt, prev

    corner_next = _part("_corner_links", 0, "(h,) int32 (int64 beyond 2**31 corners) index (into ``face_indices``) "
                                            "of the next corner in the same face.")
    corner_prev = _part("_corner_links", 1, "(h,) int32 (int64 beyond 2**31 corners) index of the previous corner in "
                                            "the same face.")

    @property
    def corner_steps(self) -> tuple[np.ndarray | None, np.ndarray | None]:
        """``(corner_next, corner_prev)`` as the kernels take them: ``(None, None)`` on a triangle mesh,
        whose corners step by arithmetic (:func:`curv.core.connectivity.next_corner`; numba compiles
        that case apart), so that a fresh estimate neither builds nor reads the two (h,) arrays."""
        if self.is_triangular:
            return None, None
        return self.corner_next, self.corner_prev

    @cached_property
    def vertex_corners(self) -> tuple[np.ndarray, np.ndarray]:
        """The corners grouped by vertex: ``(indptr (n+1,) int64, corners (h,) int64)``.

        The corners at vertex v are ``corners[indptr[v]:indptr[v+1]]``, in face order. Built with a
        counting sort (linear time).
        """
        return _kernels.group_corners(self._indices, self.n_vertices)

    @cached_property
    def halfedges(self) -> np.ndarray:
        """(h, 2) int64 directed edges ``(corner vertex, next corner vertex)`` of every face."""
        return np.stack([self._indices, self._indices[self.corner_next]], axis=1)

    @cached_property
    def _edge_data(self):
        """The edge table (:func:`curv.core.connectivity.edge_table`): edges, halfedge_edge, face count,
        edge faces, edge halfedges, forward count."""
        indptr, corners = self.vertex_corners
        return _kernels.edge_table(indptr, corners, self._indices, self.corner_next, self.corner_prev,
                                   self.corner_face)

    edges = _part("_edge_data", 0, "(e, 2) int64 unique undirected edges, ``edges[:, 0] < edges[:, 1]``.")
    halfedge_edge = _part("_edge_data", 1, "(h,) int64 undirected edge of each halfedge, -1 for the null edge of a "
                                           "repeated index.")
    edge_face_count = _part("_edge_data", 2, "(e,) int64 number of faces using each edge (1 on a border, >2 where "
                                             "non-manifold).")
    edge_faces = _part("_edge_data", 3, """(e, 2) int64 the first two faces of each edge; -1 where there is none.

    For a manifold interior edge, ``edge_faces[:, 0]`` is the face in which the edge runs
    from ``edges[:, 0]`` to ``edges[:, 1]`` when orientation is consistent.
    """)

    @cached_property
    def edge_vectors(self) -> np.ndarray:
        """(e, 3) float64 ``vertices[edges[:, 1]] - vertices[edges[:, 0]]``."""
        return np.take(self._vertices, self.edges[:, 1], axis=0) - np.take(self._vertices, self.edges[:, 0], axis=0)

    @cached_property
    def edge_lengths(self) -> np.ndarray:
        """(e,) float64 edge lengths."""
        return np.linalg.norm(self.edge_vectors, axis=1)

    @cached_property
    def mean_edge_length(self) -> float:
        return float(self.edge_lengths.mean()) if self.edge_lengths.size else 0.0

    # ------------------------------------------------------------------ vertex connectivity
    @cached_property
    def _incidence(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(indptr (n+1,), neighbours (2e,), edge_ids (2e,))`` int64: the edges of each vertex in
        increasing order, and their other endpoints (also increasing)."""
        return _kernels.vertex_incidence(self.edges, self.n_vertices)

    @cached_property
    def corner_pass(self) -> _kernels.CornerPass:
        """The vertex flags, edge neighbours, longest 1-ring edge and Max normals, from one walk over
        the corners around each vertex (:func:`curv.core.connectivity.corner_pass`; no edge table, so a
        fresh estimate never builds it). The arrays are read-only; the properties below expose them."""
        indptr, corners = self.vertex_corners
        out = _kernels.corner_pass(indptr, corners, self._indices, *self.corner_steps, self._vertices)
        for arr in out:
            arr.setflags(write=False)
        return out

    @property
    def neighbour_lists(self) -> tuple[np.ndarray, np.ndarray]:
        """``(indptr (n+1,), neighbours (a,))`` int64, read-only: each vertex's edge neighbours, sorted
        (the rows of :attr:`adjacency`)."""
        return self.corner_pass.neighbour_ptr, self.corner_pass.neighbours

    @cached_property
    def adjacency(self) -> sp.csr_matrix:
        """(n, n) symmetric CSR matrix of int8 ones: ``A[i, j] = 1`` when ``i`` and ``j`` share an edge.

        Indices are sorted within each row.
        """
        indptr, neighbours = self.neighbour_lists
        n = self.n_vertices
        return _csr(np.ones(neighbours.size, np.int8), neighbours, indptr, (n, n))

    @cached_property
    def valence(self) -> np.ndarray:
        """(n,) int64 number of edge neighbours of each vertex."""
        return np.diff(self.neighbour_lists[0])

    @cached_property
    def vertex_faces(self) -> sp.csr_matrix:
        """(n, m) CSR incidence: entry (v, f) counts the corners of face f at vertex v."""
        indptr, corners = self.vertex_corners
        face_ptr, faces, counts = _kernels.vertex_face_incidence(indptr, corners, self.corner_face)
        return _csr(counts, faces, face_ptr, (self.n_vertices, self.n_faces))

    @cached_property
    def vertex_edges(self) -> sp.csr_matrix:
        """(n, e) CSR incidence: entry (v, e) is 1 when v is an endpoint of edge e."""
        indptr, _, edge_ids = self._incidence
        return _csr(np.ones(edge_ids.size, np.int8), edge_ids, indptr, (self.n_vertices, self.edges.shape[0]))

    @cached_property
    def longest_edge(self) -> np.ndarray:
        """(n,) float64 longest edge incident to each vertex: the maximum distance to p in its 1-ring.

        This is the unit of the estimation range (paper §4.1). 0 for a vertex with no edge.
        """
        return self.corner_pass.longest_edge

    # ------------------------------------------------------------------ faces geometry
    @cached_property
    def _triangle_geometry(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Triangle meshes: ``(vector areas (m, 3), areas (m,), degenerate (m,))`` in one pass."""
        m = self.n_faces
        vector_area, area, degenerate = np.empty((m, 3)), np.empty(m), np.empty(m, bool)
        launch(_kernels.triangle_geometry, self._indices.reshape(-1, 3), self._vertices, (vector_area, area),
               degenerate)
        return vector_area, area, degenerate

    @cached_property
    def _polygon_geometry(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Polygon meshes: ``(vector areas (m, 3), areas (m,), degenerate (m,))`` in one pass."""
        m = self.n_faces
        vector_area, area, degenerate = np.empty((m, 3)), np.empty(m), np.empty(m, bool)
        launch(_kernels.polygon_geometry, (self._offsets, self._indices), self._vertices, (vector_area, area),
               degenerate)
        return vector_area, area, degenerate

    @cached_property
    def face_vector_areas(self) -> np.ndarray:
        """(m, 3) float64 Newell vector area of each face: unit normal times area.

        Exact for planar polygons and the natural average normal for non-planar ones. For a
        triangle it is half the cross product of two edges (the same vector, with less rounding).
        """
        return (self._triangle_geometry if self.is_triangular else self._polygon_geometry)[0]

    @cached_property
    def face_areas(self) -> np.ndarray:
        """(m,) float64 face areas (norm of the Newell vector area)."""
        return (self._triangle_geometry if self.is_triangular else self._polygon_geometry)[1]

    @cached_property
    def face_normals(self) -> np.ndarray:
        """(m, 3) float64 unit face normals; NaN rows for degenerate faces."""
        with np.errstate(invalid="ignore", divide="ignore"):
            out = self.face_vector_areas / self.face_areas[:, None]
        out[self.degenerate_faces] = np.nan
        return out

    @cached_property
    def dihedral_angles(self) -> np.ndarray:
        """(e,) float64 degrees between the normals of each edge's two faces, read-only.

        0 on a flat sheet, 90 on a box's edge, up to 180 on a fold flat onto itself; NaN on border
        and non-manifold edges and next to a degenerate face. Which of them are creases is
        :mod:`curv.core.features`' rule.
        """
        out = np.empty(self.edge_faces.shape[0])
        launch(_kernels.dihedral_angles, self.edge_faces, self.edge_face_count, self.face_normals, out)
        out.setflags(write=False)
        return out

    @cached_property
    def degenerate_faces(self) -> np.ndarray:
        """(m,) bool: faces with a repeated vertex index or (numerically) zero area.

        Zero area means area below ``1e-12`` times the squared longest edge of the face.
        """
        if self.is_triangular:
            if "_triangle_geometry" in self.__dict__:
                return self._triangle_geometry[2]
            # the flags alone (meyer and ru read nothing else): the same test, without the areas
            degenerate = np.empty(self.n_faces, bool)
            launch(_kernels.triangle_geometry, self._indices.reshape(-1, 3), self._vertices, None, degenerate)
            return degenerate
        return self._polygon_geometry[2]

    # ------------------------------------------------------------------ topology flags
    @cached_property
    def border_edges(self) -> np.ndarray:
        """(e,) bool: edges used by exactly one face."""
        return self.edge_face_count == 1

    @cached_property
    def nonmanifold_edges(self) -> np.ndarray:
        """(e,) bool: edges used by three or more faces."""
        return self.edge_face_count > 2

    @cached_property
    def inconsistent_edges(self) -> np.ndarray:
        """(e,) bool: manifold edges whose two faces traverse them in the same direction.

        Such an edge joins faces of opposite orientation (a flipped face); the vertex normals there
        are unreliable. :func:`curv.geometry.repair.orient_faces` fixes them.
        """
        return (self.edge_face_count == 2) & (self._edge_data[5] != 1)

    @cached_property
    def duplicate_vertices(self) -> np.ndarray:
        """(n,) bool: vertices at exactly the position of a vertex with a lower index."""
        out = np.empty(self.n_vertices, bool)
        _kernels.duplicate_positions(self._vertices, self._vertices.view(np.uint64), out)
        return out

    @cached_property
    def _fan_flags(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(nonmanifold, border, inconsistent)`` (n,) bool, read-only: the corner pass's flags when it
        has run, else the same flags from the fans alone (:func:`curv.core.connectivity.fan_flags`),
        without the neighbours and normals an estimator like meyer never reads."""
        if "corner_pass" in self.__dict__:
            cp = self.corner_pass
            return cp.nonmanifold, cp.border, cp.inconsistent
        indptr, corners = self.vertex_corners
        out = _kernels.fan_flags(indptr, corners, self._indices, *self.corner_steps, self._vertices)
        for arr in out:
            arr.setflags(write=False)
        return out

    border_vertices = _part("_fan_flags", 1, "(n,) bool: vertices on a border edge or a non-manifold edge.")

    @cached_property
    def isolated_vertices(self) -> np.ndarray:
        """(n,) bool: vertices that no face uses."""
        indptr = self.vertex_corners[0]
        return indptr[1:] == indptr[:-1]

    # two corners at v are linked when their faces share an edge at v with exactly two faces;
    # the linked groups are the fans (curv.core.connectivity.corner_pass)
    nonmanifold_vertices = _part("_fan_flags", 0, """(n,) bool: vertices whose faces do not form one fan (e.g. the tip of a bow tie).

    Counted as: the faces around v, linked when they share an edge at v, form more than one
    group. Vertices on non-manifold edges are included too.
    """)

    inconsistent_vertices = _part("_fan_flags", 2, "(n,) bool: endpoints of :attr:`inconsistent_edges` (faces of "
                                                    "opposite orientation meet there).")

    @cached_property
    def components(self) -> tuple[int, np.ndarray]:
        """``(count, labels)``: connected components of the vertex graph; labels is (n,) int."""
        labels = np.empty(self.n_vertices, np.int64)
        count = _kernels.component_labels(*self.neighbour_lists, labels)
        return int(count), labels

    def report(self) -> MeshReport:
        """Summarise the mesh: sizes, polygon kinds, components, borders and defects
        (:func:`curv.core.mesh_report.mesh_report`)."""
        return mesh_report(self)

    # ------------------------------------------------------------------ derived meshes
    @classmethod
    def _trusted(cls, vertices: np.ndarray, indices: np.ndarray, offsets: np.ndarray) -> "Mesh":
        m = cls.__new__(cls)
        for arr in (vertices, indices, offsets):
            arr.setflags(write=False)
        m._vertices, m._indices, m._offsets = vertices, indices, offsets
        m.info = {}
        return m

    def with_vertices(self, vertices) -> "Mesh":
        """A mesh with the same faces and new (validated) vertex positions of the same count."""
        v = as_positions(vertices, "vertex", "vertices", "mesh")
        if v.shape[0] != self.n_vertices:
            raise MeshError(f"expected {self.n_vertices} vertices, got {v.shape[0]}")
        return Mesh._trusted(v, self._indices, self._offsets)

    def flipped(self) -> "Mesh":
        """The same mesh with every face's orientation reversed."""
        sizes = self.face_sizes
        local = np.arange(self._indices.size) - np.repeat(self._offsets[:-1], sizes)
        rev = np.repeat(self._offsets[1:], sizes) - 1 - local
        return Mesh._trusted(self._vertices, self._indices[rev].copy(), self._offsets)

    def __repr__(self) -> str:
        kinds = "triangles" if self.is_triangular else "polygons"
        return f"Mesh({self.n_vertices} vertices, {self.n_faces} {kinds})"


def _csr(data: np.ndarray, indices: np.ndarray, indptr: np.ndarray, shape: tuple[int, int]) -> sp.csr_matrix:
    """A CSR matrix from sorted, duplicate-free rows, with the index dtype scipy would choose."""
    small = max(shape) < 2**31 and indices.size < 2**31
    dtype = np.int32 if small else np.int64
    out = sp.csr_matrix((data, indices.astype(dtype), indptr.astype(dtype)), shape=shape, copy=False)
    out.has_sorted_indices = True
    out.has_canonical_format = True
    return out
