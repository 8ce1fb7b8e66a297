"""The connectivity kernels (curv.core.connectivity) against plain numpy/scipy definitions of each table.

The meshes are chosen to reach every branch: random polygon soups (repeated indices, edges with one,
two or many faces, isolated vertices), a fan large enough for the merge-sort path, a bow tie.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import curv
from curv.core import connectivity
from tests.meshes import icosphere, torus_grid


def _soup(seed: int) -> curv.Mesh:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 30))
    faces = [rng.integers(0, n, size=int(rng.integers(3, 6))) for _ in range(int(rng.integers(1, 50)))]
    return curv.Mesh(rng.normal(size=(n, 3)), faces)


def _fan(k: int) -> curv.Mesh:
    """Double cone: apex 0 (the lowest index, so all its edges are numbered at it) and apex k + 1."""
    angle = np.linspace(0, 2 * np.pi, k, endpoint=False)
    v = np.concatenate([[[0, 0, 1.0]], np.stack([np.cos(angle), np.sin(angle), np.zeros(k)], 1), [[0, 0, -1.0]]])
    ring = 1 + np.arange(k)
    nxt = 1 + (np.arange(k) + 1) % k
    faces = np.concatenate([np.stack([np.zeros(k, int), ring, nxt], 1), np.stack([np.full(k, k + 1), nxt, ring], 1)])
    return curv.Mesh(v, faces)


def _bowtie() -> curv.Mesh:
    """Two spheres touching at one shared vertex; the second sphere's own copy of it and an extra
    vertex stay unused."""
    a = icosphere(1)
    b_vertices = a.vertices + [2.0, 0, 0]
    shared = int(np.argmax(a.vertices[:, 0]))
    tip = int(np.argmin(a.vertices[:, 0]))
    remap = np.arange(a.n_vertices) + a.n_vertices
    remap[tip] = shared
    v = np.concatenate([a.vertices, b_vertices, [[9.0, 9, 9]]])
    return curv.Mesh(v, np.concatenate([a.triangles, remap[a.triangles]]))


MESHES = [_soup(s) for s in range(40)] + [_fan(5), _fan(100), _bowtie(), icosphere(2), torus_grid(12, 7, quads=True)[0]]
IDS = [f"soup{s}" for s in range(40)] + ["fan5", "fan100", "bowtie", "sphere", "quads"]


def _halfedges(mesh):
    return mesh.face_indices, mesh.face_indices[mesh.corner_next]


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_edge_table_matches_the_unique_halfedge_pairs(mesh):
    a, b = _halfedges(mesh)
    ok = a != b
    pairs = np.stack([np.minimum(a, b), np.maximum(a, b)], 1)
    expected, inverse = np.unique(pairs[ok], axis=0, return_inverse=True)
    assert np.array_equal(mesh.edges, expected)
    he = np.full(a.size, -1)
    he[ok] = inverse.ravel()
    assert np.array_equal(mesh.halfedge_edge, he)
    assert np.array_equal(mesh.edge_face_count, np.bincount(he[ok], minlength=len(expected)))
    # edge_faces: the faces of the first two halfedges, forward (low -> high) ones first
    for e in range(len(expected)):
        hs = np.flatnonzero(he == e)
        hs = np.concatenate([hs[a[hs] < b[hs]], hs[a[hs] > b[hs]]])[:2]
        want = np.full(2, -1)
        want[:hs.size] = mesh.corner_face[hs]
        assert np.array_equal(mesh.edge_faces[e], want)
    forward = np.bincount(he[ok], weights=(a < b)[ok], minlength=len(expected))
    assert np.array_equal(mesh.inconsistent_edges, (mesh.edge_face_count == 2) & (forward != 1))


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_incidence_matrices_match_their_sparse_definitions(mesh):
    e, n, m = mesh.edges, mesh.n_vertices, mesh.n_faces
    rows, cols = np.concatenate([e[:, 0], e[:, 1]]), np.concatenate([e[:, 1], e[:, 0]])
    adjacency = sp.csr_matrix((np.ones(rows.size, np.int8), (rows, cols)), shape=(n, n))
    assert mesh.adjacency.dtype == np.int8 and mesh.adjacency.has_sorted_indices
    assert (mesh.adjacency != mesh.adjacency.T).nnz == 0
    assert (mesh.adjacency != adjacency).nnz == 0
    assert all(np.all(np.diff(mesh.adjacency.indices[s:t]) > 0)
               for s, t in zip(mesh.adjacency.indptr[:-1], mesh.adjacency.indptr[1:]))
    vertex_edges = sp.csr_matrix((np.ones(2 * len(e), np.int8), (e.ravel(), np.repeat(np.arange(len(e)), 2))),
                                 shape=(n, len(e)))
    assert mesh.vertex_edges.dtype == np.int8 and (mesh.vertex_edges != vertex_edges).nnz == 0
    vertex_faces = sp.csr_matrix((np.ones(mesh.face_indices.size, np.int32),
                                  (mesh.face_indices, mesh.corner_face)), shape=(n, m))
    assert mesh.vertex_faces.dtype == np.int32 and (mesh.vertex_faces != vertex_faces).nnz == 0
    assert np.array_equal(mesh.valence, np.diff(adjacency.indptr))


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_longest_edge_and_isolated_vertices(mesh):
    expected = np.zeros(mesh.n_vertices)
    np.maximum.at(expected, mesh.edges[:, 0], mesh.edge_lengths)
    np.maximum.at(expected, mesh.edges[:, 1], mesh.edge_lengths)
    assert np.array_equal(mesh.longest_edge, expected)
    used = np.zeros(mesh.n_vertices, bool)
    used[mesh.face_indices] = True
    assert np.array_equal(mesh.isolated_vertices, ~used)


def _fans_by_graph(mesh) -> np.ndarray:
    """Fans per vertex as components of the corner graph (corners linked across two-face edges)."""
    idx, nxt, he = mesh.face_indices, mesh.corner_next, mesh.halfedge_edge
    h = idx.size
    rows, cols = [], []
    for e in np.flatnonzero(mesh.edge_face_count == 2):
        h1, h2 = np.flatnonzero(he == e)
        for end in (idx[h1], idx[nxt[h1]]):
            at1 = h1 if idx[h1] == end else nxt[h1]
            at2 = h2 if idx[h2] == end else nxt[h2]
            rows.append(at1)
            cols.append(at2)
    graph = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(h, h))
    _, labels = sp.csgraph.connected_components(graph, directed=False)
    fan_vertex = np.zeros(labels.max() + 1, int)
    fan_vertex[labels] = idx
    return np.bincount(fan_vertex, minlength=mesh.n_vertices)


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_nonmanifold_vertices_are_several_fans_or_on_a_nonmanifold_edge(mesh):
    expected = _fans_by_graph(mesh) > 1
    expected[mesh.edges[mesh.edge_face_count > 2].ravel()] = True
    assert np.array_equal(mesh.nonmanifold_vertices, expected)


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_border_and_inconsistent_vertices_are_the_ends_of_their_edges(mesh):
    border = np.zeros(mesh.n_vertices, bool)
    border[mesh.edges[mesh.edge_face_count != 2].ravel()] = True
    assert np.array_equal(mesh.border_vertices, border)
    inconsistent = np.zeros(mesh.n_vertices, bool)
    inconsistent[mesh.edges[mesh.inconsistent_edges].ravel()] = True
    assert np.array_equal(mesh.inconsistent_vertices, inconsistent)


def test_bowtie_tip_is_the_one_nonmanifold_vertex():
    mesh = _bowtie()
    tip = int(np.argmax(icosphere(1).vertices[:, 0]))
    assert np.flatnonzero(mesh.nonmanifold_vertices).tolist() == [tip]
    tip_copy = icosphere(1).n_vertices + int(np.argmin(icosphere(1).vertices[:, 0]))
    assert np.flatnonzero(mesh.isolated_vertices).tolist() == [tip_copy, mesh.n_vertices - 1]


@pytest.mark.parametrize("mesh", [m for m in MESHES if m.is_triangular], ids=[i for m, i in zip(MESHES, IDS)
                                                                            if m.is_triangular])
def test_triangle_geometry_matches_the_cross_product(mesh):
    p = mesh.vertices[mesh.triangles]
    vector_area = 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.allclose(mesh.face_vector_areas, vector_area, rtol=0, atol=1e-15)
    assert np.allclose(mesh.face_areas, np.linalg.norm(vector_area, axis=1), rtol=0, atol=1e-15)
    t = mesh.triangles
    repeated = (t[:, 0] == t[:, 1]) | (t[:, 1] == t[:, 2]) | (t[:, 0] == t[:, 2])
    sides2 = np.stack([((p[:, i] - p[:, (i + 1) % 3]) ** 2).sum(1) for i in range(3)], 1).max(1)
    assert np.array_equal(mesh.degenerate_faces, repeated | (mesh.face_areas <= 1e-12 * sides2))


def test_vertex_corners_are_a_stable_counting_sort():
    keys = np.random.default_rng(3).integers(0, 50, 1000)
    indptr, items = connectivity.group_corners(keys, 60)
    assert np.array_equal(items, np.argsort(keys, kind="stable"))
    assert np.array_equal(np.diff(indptr), np.bincount(keys, minlength=60))


def test_connectivity_does_not_depend_on_the_thread_count(monkeypatch):
    mesh = _fan(100)
    reference = [mesh.edges, mesh.edge_faces, mesh.halfedge_edge, mesh.nonmanifold_vertices]
    monkeypatch.setenv("CURV_THREADS", "1")
    again = curv.Mesh(mesh.vertices, mesh.triangles)
    for a, b in zip(reference, [again.edges, again.edge_faces, again.halfedge_edge, again.nonmanifold_vertices]):
        assert np.array_equal(a, b)
