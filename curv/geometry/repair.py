"""Optional repairs of loaded meshes, each reported in one line ("merged 124 duplicate vertices").

None is applied unless asked for: each can change the result of an estimate.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..core.mesh import Mesh

__all__ = ["repair", "merge_duplicate_vertices", "drop_degenerate_faces", "drop_unreferenced_vertices",
           "orient_faces"]


def _rebuild(mesh: Mesh, vertices: np.ndarray, indices: np.ndarray, sizes: np.ndarray) -> Mesh:
    offsets = np.zeros(sizes.size + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    faces = np.split(indices, offsets[1:-1]) if not np.all(sizes == 3) else indices.reshape(-1, 3)
    out = Mesh(vertices, faces)
    out.info = dict(mesh.info)
    return out


def merge_duplicate_vertices(mesh: Mesh) -> tuple[Mesh, int]:
    """Merge vertices with identical coordinates; returns the mesh and how many were merged."""
    uniq, inverse = np.unique(mesh.vertices, axis=0, return_inverse=True)
    merged = mesh.n_vertices - uniq.shape[0]
    if merged == 0:
        return mesh, 0
    return _rebuild(mesh, uniq, inverse.reshape(-1)[mesh.face_indices], mesh.face_sizes), merged


def drop_degenerate_faces(mesh: Mesh) -> tuple[Mesh, int]:
    """Remove faces with a repeated vertex or zero area; returns the mesh and the count removed."""
    bad = mesh.degenerate_faces
    count = int(bad.sum())
    if count == 0:
        return mesh, 0
    if count == mesh.n_faces:
        return mesh, 0  # removing everything would leave no mesh; keep it and let the masks speak
    keep_corner = ~bad[mesh.corner_face]
    return _rebuild(mesh, mesh.vertices, mesh.face_indices[keep_corner], mesh.face_sizes[~bad]), count


def drop_unreferenced_vertices(mesh: Mesh) -> tuple[Mesh, int]:
    """Remove vertices that no face uses (renumbers the rest); returns the mesh and the count removed."""
    iso = mesh.isolated_vertices
    count = int(iso.sum())
    if count == 0:
        return mesh, 0
    new_index = np.cumsum(~iso) - 1
    return _rebuild(mesh, mesh.vertices[~iso], new_index[mesh.face_indices], mesh.face_sizes), count


def _tree_parity(n_nodes: int, pred: np.ndarray, bit: np.ndarray) -> np.ndarray:
    """XOR of ``bit`` along each node's path to its root, by pointer jumping (log depth steps).

    ``pred`` is (n_nodes,) with -1 at roots; ``bit[i]`` belongs to the tree edge (i, pred[i]).
    """
    parent = np.where(pred < 0, np.arange(n_nodes), pred)
    parity = np.where(pred < 0, 0, bit).astype(np.int8)
    while True:
        parity = parity ^ parity[parent]
        grand = parent[parent]
        if np.array_equal(grand, parent):
            return parity
        parent = grand


def orient_faces(mesh: Mesh) -> tuple[Mesh, int]:
    """Make orientation consistent across manifold edges, then turn closed components outward.

    Returns the mesh and the number of faces flipped.
    """
    he_edge = mesh.halfedge_edge
    ok = he_edge >= 0
    forward = (mesh.halfedges[:, 0] < mesh.halfedges[:, 1]) & ok
    n_forward = np.bincount(he_edge[ok], weights=forward[ok], minlength=mesh.edges.shape[0])
    manifold = mesh.edge_face_count == 2
    f0, f1 = mesh.edge_faces[manifold].T
    inconsistent = (n_forward[manifold] != 1).astype(np.int8)
    m = mesh.n_faces
    ncomp, labels = sp.csgraph.connected_components(
        sp.csr_matrix((np.ones(f0.size), (f0, f1)), shape=(m, m)), directed=False)
    roots = np.unique(labels, return_index=True)[1]
    # a virtual node m joined to one face per component makes the forest one BFS tree
    rows = np.concatenate([f0, f1, np.full(roots.size, m), roots])
    cols = np.concatenate([f1, f0, roots, np.full(roots.size, m)])
    bits = np.concatenate([inconsistent, inconsistent, np.zeros(2 * roots.size, np.int8)]) + 2
    graph = sp.csr_matrix((bits.astype(np.int8), (rows, cols)), shape=(m + 1, m + 1))
    graph.sum_duplicates()
    order, pred = sp.csgraph.breadth_first_order(graph, m, directed=False, return_predecessors=True)
    pred = pred.copy()
    pred[pred == -9999] = -1
    edge_bit = np.zeros(m + 1, np.int8)
    child = np.flatnonzero(pred >= 0)
    edge_bit[child] = (np.asarray(graph[child, pred[child]]).ravel() - 2) % 2
    flip = _tree_parity(m + 1, pred, edge_bit)[:m].astype(bool)
    # closed components: outward means positive signed volume
    centroid = np.stack([np.bincount(mesh.corner_face, weights=mesh.vertices[mesh.face_indices, k],
                                     minlength=m) for k in range(3)], axis=1) / mesh.face_sizes[:, None]
    vol = np.einsum("ij,ij->i", mesh.face_vector_areas, centroid) / 3.0
    vol = np.where(flip, -vol, vol)
    border_faces = np.zeros(m, bool)
    border_faces[mesh.edge_faces[mesh.border_edges, 0]] = True
    comp_open = np.bincount(labels, weights=border_faces, minlength=ncomp) > 0
    comp_vol = np.bincount(labels, weights=vol, minlength=ncomp)
    flip ^= ((comp_vol < 0) & ~comp_open)[labels]
    count = int(flip.sum())
    if count == 0:
        return mesh, 0
    sizes = mesh.face_sizes
    local = np.arange(mesh.face_indices.size) - np.repeat(mesh.face_offsets[:-1], sizes)
    rev = np.repeat(mesh.face_offsets[1:], sizes) - 1 - local
    idx = np.where(flip[mesh.corner_face], mesh.face_indices[rev], mesh.face_indices)
    return _rebuild(mesh, mesh.vertices, idx, sizes), count


def repair(mesh: Mesh, *, merge_vertices: bool = False, remove_degenerate: bool = False, orient: bool = False,
           remove_unreferenced: bool = False) -> tuple[Mesh, list[str]]:
    """Apply the requested repairs in a fixed order; return the mesh and one line per change made."""
    lines = []
    steps = [
        (merge_vertices, merge_duplicate_vertices, "merged {} duplicate vertices"),
        (remove_degenerate, drop_degenerate_faces, "removed {} degenerate faces"),
        (remove_unreferenced, drop_unreferenced_vertices, "removed {} unreferenced vertices"),
        (orient, orient_faces, "flipped {} faces to a consistent orientation"),
    ]
    for wanted, step, text in steps:
        if wanted:
            mesh, count = step(mesh)
            if count:
                lines.append(text.format(count))
    return mesh, lines
