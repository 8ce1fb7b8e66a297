"""The propagation's spanning forest (issue 33, item 5): the tree's edges written per row in
parallel and Kruskal on the edges' ends gathered in rank order equal plain one-by-one references,
on random, clustered and multi-part clouds, with undecided (NaN) normals and tied weights."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.point_normals import grid_ordered
from curv.point_normals.orientation import _spanning_forest, _stable_rank, _tree_edges


def _cloud(kind: str, rng: np.random.Generator) -> np.ndarray:
    if kind == "sphere":
        p = rng.normal(size=(3000, 3))
        return p / np.linalg.norm(p, axis=1, keepdims=True)
    if kind == "clusters":
        centres = rng.uniform(-1.0, 1.0, size=(6, 3))
        return np.concatenate([c + 0.05 * rng.normal(size=(400, 3)) for c in centres])
    # parts far apart, one of a few points only
    return np.concatenate([rng.normal(size=(1500, 3)), 50.0 + rng.normal(size=(1200, 3)),
                           [-80.0, 0.0, 0.0] + 0.01 * rng.normal(size=(4, 3))])


def _reference(n, indptr, neighbours, normal, finite):
    """The edges one row at a time, Kruskal one edge at a time, the forest's CSR and parts."""
    rows, cols, weight = [], [], []
    for p in range(n):
        for q in neighbours[indptr[p]:indptr[p + 1]]:
            if finite[p] and q > p and finite[q]:
                rows.append(p)
                cols.append(q)
                c = normal[p, 0] * normal[q, 0] + normal[p, 1] * normal[q, 1] + normal[p, 2] * normal[q, 2]
                weight.append(1.0 - abs(c) + 1e-9)
    rows, cols, weight = np.array(rows), np.array(cols), np.array(weight)
    parent = list(range(n))

    def root(i):
        while parent[i] != i:
            i = parent[i]
        return i

    taken = np.zeros(rows.size, bool)
    for e in np.argsort(weight, kind="stable"):
        a, b = root(rows[e]), root(cols[e])
        if a != b:
            parent[max(a, b)] = min(a, b)
            taken[e] = True
    lists = [[] for _ in range(n)]
    for e in np.flatnonzero(taken):
        lists[rows[e]].append(cols[e])
        lists[cols[e]].append(rows[e])
    ptr = np.concatenate([[0], np.cumsum([len(x) for x in lists])])
    adj = np.array([q for x in lists for q in x], dtype=np.int64)
    part = np.array([root(p) for p in range(n)])
    return (rows, cols, weight), (ptr, adj, part)


@pytest.mark.parametrize("kind", ["sphere", "clusters", "parts"])
@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("ordered", [True, False])
def test_edges_and_forest_equal_the_one_by_one_reference(kind, seed, ordered):
    rng = np.random.default_rng(seed)
    cloud = curv.PointCloud(_cloud(kind, rng))
    # in grid order (as the estimate runs) and in random order (deeper union-find trees)
    twin = grid_ordered(cloud)[0] if ordered else cloud
    n = twin.n_points
    graph = twin.adjacency
    indptr, neighbours = graph.indptr, graph.indices
    # normals on a coarse lattice: many equal weights, so the ties' order is checked too
    normal = np.round(rng.normal(size=(n, 3)), 0)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    normal[rng.random(n) < 0.05] = np.nan
    finite = np.isfinite(normal).all(axis=1)
    safe = np.where(finite[:, None], normal, 0.0)
    rows, cols, weight = _tree_edges(indptr, neighbours, safe, finite)
    (r_rows, r_cols, r_weight), (r_ptr, r_adj, r_part) = _reference(n, indptr, neighbours, safe, finite)
    assert np.array_equal(rows, r_rows) and np.array_equal(cols, r_cols)
    assert np.array_equal(weight, r_weight)
    assert np.unique(weight).size < weight.size // 2
    ptr, adj, part = _spanning_forest(n, _stable_rank(weight), rows, cols)
    assert np.array_equal(ptr, r_ptr)
    assert np.array_equal(adj, r_adj)
    assert np.array_equal(part, r_part)
    assert np.unique(part).size > (1 if kind == "sphere" else 3)
