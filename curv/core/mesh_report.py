"""What a mesh contains, counted for a one-screen summary: :class:`MeshReport` and :func:`mesh_report`
(what :meth:`curv.Mesh.report` returns).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from .connectivity import edge_counts
from .wording import count_text

if TYPE_CHECKING:
    from .mesh import Mesh

__all__ = ["MeshReport", "mesh_report"]


@dataclass(frozen=True)
class MeshReport:
    """Counts of what a mesh contains, for a one-screen summary.

    Every field is a plain int, or a dict ``{polygon size: face count}`` for ``polygon_kinds``.
    """

    vertices: int
    faces: int
    edges: int
    polygon_kinds: dict
    components: int
    border_edges: int
    border_loops: int
    nonmanifold_edges: int
    nonmanifold_vertices: int
    degenerate_faces: int
    isolated_vertices: int
    inconsistent_edges: int = 0
    duplicate_vertices: int = 0
    sharp_edges: int = 0
    """Interior edges with a dihedral angle above :data:`curv.core.features.SHARP_DEGREES`."""
    suggested_features: float | None = None
    """A ``features`` angle that separates the creases from the smooth edges, when many are sharp."""

    def lines(self) -> list[str]:
        """Human-readable lines, one fact each."""
        names = {k: _POLY_NAMES.get(k, f"{k}-gons") for k in self.polygon_kinds}
        kinds = ", ".join(count_text(n, names[k][:-1], names[k]) for k, n in sorted(self.polygon_kinds.items()))
        out = [
            f"{count_text(self.vertices, 'vertex', 'vertices')}, {count_text(self.faces, 'face', 'faces')} "
            f"({kinds or 'none'}), {count_text(self.edges, 'edge', 'edges')}",
            f"{count_text(self.components, 'connected component', 'connected components')}",
            f"{count_text(self.border_edges, 'border edge', 'border edges')} in "
            f"{count_text(self.border_loops, 'loop', 'loops')}" if self.border_edges else "closed (no border)",
        ]
        for count, one, many in [
            (self.nonmanifold_edges, "non-manifold edge", "non-manifold edges"),
            (self.nonmanifold_vertices, "non-manifold vertex", "non-manifold vertices"),
            (self.degenerate_faces, "degenerate face", "degenerate faces"),
            (self.isolated_vertices, "isolated vertex", "isolated vertices"),
            (self.inconsistent_edges, "edge between faces of opposite orientation",
             "edges between faces of opposite orientation"),
            (self.duplicate_vertices, "vertex at the same position as another",
             "vertices at the same position as another"),
        ]:
            if count:
                out.append(count_text(count, one, many))
        if self.sharp_edges:
            from .features import SHARP_DEGREES

            line = (f"{count_text(self.sharp_edges, 'sharp edge', 'sharp edges')} "
                    f"(dihedral angle above {SHARP_DEGREES:g} degrees)")
            if self.suggested_features is not None:
                line += f": creases? try features={self.suggested_features:g}"
            out.append(line)
        return out


_POLY_NAMES = {3: "triangles", 4: "quads", 5: "pentagons", 6: "hexagons"}


def mesh_report(mesh: Mesh) -> MeshReport:
    """Summarise ``mesh``: sizes, polygon kinds, components, borders and defects (:meth:`Mesh.report`)."""
    sizes, face_counts = np.unique(mesh.face_sizes, return_counts=True)
    iso = mesh.isolated_vertices
    ncomp, labels = mesh.components
    ncomp_faces = int(np.count_nonzero(np.bincount(labels[~iso], minlength=ncomp)))
    from .features import SHARP_DEGREES

    indptr, corners = mesh.vertex_corners
    corner_face = None if mesh.is_triangular else mesh.corner_face
    counts = edge_counts(indptr, corners, mesh.face_indices, *mesh.corner_steps, corner_face,
                         mesh.face_vector_areas, mesh.face_areas, mesh.degenerate_faces, SHARP_DEGREES)
    loops = 0
    if counts["border"]:
        be = mesh.edges[mesh.border_edges]
        verts = np.unique(be)
        remap = np.searchsorted(verts, be)
        g = sp.csr_matrix((np.ones(len(be)), (remap[:, 0], remap[:, 1])), shape=(verts.size,) * 2)
        loops = int(sp.csgraph.connected_components(g, directed=False)[0])
    # the crease rule (its threshold suggestion) needs every dihedral angle, so the edge table:
    # only when there is a sharp edge at all
    sharp = _sharp_edge_facts(mesh) if counts["sharp"] else {"sharp_edges": 0, "suggested_features": None}
    return MeshReport(
        vertices=mesh.n_vertices,
        faces=mesh.n_faces,
        edges=counts["edges"],
        polygon_kinds={int(s): int(c) for s, c in zip(sizes, face_counts)},
        components=ncomp_faces,
        border_edges=counts["border"],
        border_loops=loops,
        nonmanifold_edges=counts["nonmanifold"],
        nonmanifold_vertices=int(mesh.nonmanifold_vertices.sum()),
        degenerate_faces=int(mesh.degenerate_faces.sum()),
        isolated_vertices=int(iso.sum()),
        inconsistent_edges=counts["inconsistent"],
        duplicate_vertices=int(mesh.duplicate_vertices.sum()),
        **sharp,
    )


def _sharp_edge_facts(mesh: Mesh) -> dict:
    """The report's sharp-edge count and, when there are many, the features angle to suggest."""
    from .features import has_many_sharp_edges, sharp_edge_count, suggest_threshold

    count = sharp_edge_count(mesh)
    return {"sharp_edges": count, "suggested_features": suggest_threshold(mesh) if has_many_sharp_edges(mesh) else None}
