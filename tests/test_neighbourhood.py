from collections import deque

import numpy as np
import pytest

import curv
from curv.geometry.neighbourhood import iter_neighbourhoods
from tests.meshes import hex_plane, icosphere
from tests.supports import neighbourhood_matrix


def reference_support(mesh, p, factor):
    """Plain BFS that never leaves the ball: slow, obviously right."""
    adj = mesh.adjacency.tolil().rows
    r = factor * mesh.longest_edge[p] * (1 + 1e-9)
    x = mesh.vertices
    seen, queue = {p}, deque([p])
    while queue:
        q = queue.popleft()
        for w in adj[q]:
            if w not in seen and np.linalg.norm(x[w] - x[p]) <= r:
                seen.add(w)
                queue.append(w)
    return seen - {p}


@pytest.mark.parametrize("factor, expected", [(1, 6), (2, 18), (3, 36)])
def test_regular_grid_counts_match_the_lattice(factor, expected):
    m = hex_plane(8)
    centre = int(np.argmin(np.linalg.norm(m.vertices, axis=1)))
    sup = neighbourhood_matrix(m, factor)[centre].indices
    # lattice shells: 6 at L, 6 at sqrt(3) L, 6 at 2L, 12 at sqrt(7) L, 6 at 3L
    assert sup.size == expected


def test_matches_reference_bfs_on_irregular_mesh():
    rng = np.random.default_rng(3)
    m = icosphere(2)
    m = m.with_vertices(m.vertices * (1 + 0.15 * rng.standard_normal((m.n_vertices, 1))))
    mat = neighbourhood_matrix(m, 2.5)
    for p in rng.choice(m.n_vertices, 25, replace=False):
        assert set(mat[p].indices) == reference_support(m, p, 2.5)


def test_support_does_not_jump_across_a_gap():
    # a strip folded into a U: the two arms are 0.3 apart in space but far apart through the mesh
    xs = np.linspace(0, 4, 9)
    top = np.stack([xs, np.zeros_like(xs), np.full_like(xs, 0.3)], 1)
    bottom = np.stack([xs, np.zeros_like(xs), np.zeros_like(xs)], 1)
    top_w = top + [0, 1, 0]
    bottom_w = bottom + [0, 1, 0]
    v = np.vstack([bottom, bottom_w, top, top_w])
    n = len(xs)
    quads = [[i, i + 1, n + i + 1, n + i] for i in range(n - 1)]
    quads += [[2 * n + i, 3 * n + i, 3 * n + i + 1, 2 * n + i + 1] for i in range(n - 1)]
    m = curv.Mesh(v, quads)
    sup = neighbourhood_matrix(m, 4)
    for p in range(n):  # bottom arm
        assert np.all(sup[p].indices < 2 * n)


def test_block_size_does_not_change_the_result():
    m = icosphere(2)
    full = neighbourhood_matrix(m, 3)
    rows = np.zeros(m.n_vertices, int)
    for nb in iter_neighbourhoods(m, 3, block_size=37):
        for i, p in enumerate(nb.vertices):
            got = np.sort(nb.indices[nb.indptr[i]:nb.indptr[i + 1]])
            assert np.array_equal(got, np.sort(full[p].indices))
            rows[p] += 1
    assert np.all(rows == 1)


def test_radius_is_range_times_longest_edge():
    m = icosphere(1)
    nb = next(iter_neighbourhoods(m, 3))
    np.testing.assert_allclose(nb.radius, 3 * m.longest_edge[nb.vertices], rtol=1e-8)
    d = np.linalg.norm(m.vertices[nb.indices] - m.vertices[nb.centres], axis=1)
    assert np.all(d <= nb.radius[nb.rows] * (1 + 1e-8))


def test_bad_factor_rejected():
    with pytest.raises(ValueError):
        next(iter_neighbourhoods(icosphere(0), 0))
