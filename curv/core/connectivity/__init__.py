"""Connectivity kernels behind :class:`curv.Mesh`: counting sorts over corners, halfedges and edges.

Every table is built in linear time (plus tiny sorts of the few halfedges that share a low vertex),
without hashing or sorting global keys:

- :func:`group_corners` groups the corners by their vertex (a stable counting sort);
- :func:`edge_table` lists the halfedges around each vertex u (from its corners), sorts that small
  list by the other endpoint w and numbers the distinct w > u: edges come out in lexicographic order;
- :func:`vertex_incidence` lists, per vertex, its edges in increasing edge order, which is also
  increasing neighbour order (all edges ``(q, p)`` with ``q < p`` precede the edges ``(p, r)``);
- :func:`corner_pass` walks the corners around each vertex once, without the edge table, for the
  border, non-manifold and inconsistently oriented vertices (counting the fans of faces around each
  vertex), the edge neighbours, the longest 1-ring edge and the Max vertex normals: what a fresh
  estimate needs;
- :func:`triangle_geometry` and :func:`polygon_geometry` give the vector area, area and degeneracy
  of every triangle or polygon.

The :class:`curv.Mesh` properties wrap them; their meaning is documented there. The modules:
:mod:`~.corners` (grouping and stepping), :mod:`~.edges` (the edge table, incidences, dihedral
angles, the report's counts), :mod:`~.fans` (the corner pass), :mod:`~.faces` (face geometry,
repeated positions).
"""

from __future__ import annotations

from . import corners, edges, faces, fans
from .corners import corner_links, find_root, group_corners, next_corner, prev_corner
from .edges import (EDGE_COUNTS, component_labels, dihedral_angles, edge_counts, edge_table, vertex_face_incidence,
                    vertex_incidence)
from .faces import duplicate_positions, polygon_geometry, triangle_geometry
from .fans import CornerPass, corner_pass, fan_flags

__all__ = ["group_corners", "edge_table", "vertex_incidence", "vertex_face_incidence", "corner_pass", "CornerPass",
           "fan_flags", "next_corner", "prev_corner", "find_root", "triangle_geometry", "polygon_geometry",
           "duplicate_positions",
           "dihedral_angles", "corner_links", "component_labels", "edge_counts", "EDGE_COUNTS", "KERNELS"]

KERNELS = (*corners.KERNELS, *edges.KERNELS, *fans.KERNELS, *faces.KERNELS)
"""The numba dispatchers of the package (for :func:`curv.core.jit.compile_pending`)."""
