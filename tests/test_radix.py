"""The parallel stable radix sort (curv.core.radix) and the parallel passes built on it or beside
it: the grid's order, the kNN lists put back in the caller's order, the symmetric neighbour graph,
a result's rows put back (issue 33, item 5)."""

import numpy as np
import pytest

from curv.core.grid import build_grid
from curv.core.knn import nearest_neighbours
from curv.core.neighbour_graph import symmetric_graph
from curv.core.radix import _SLICE, stable_order, stable_sort


@pytest.mark.parametrize("m,high", [(0, 1), (1, 1), (1000, 1), (1000, 7), (3 * _SLICE + 17, 50),
                                    (5 * _SLICE, 2 ** 40), (2 * _SLICE + 3, 2 ** 62)])
def test_stable_order_is_numpys_stable_argsort(m, high):
    """Many ties (the order among them is the index order), several slices, keys of 1 to 62 bits."""
    keys = np.random.default_rng(m).integers(0, high, size=m)
    want = np.argsort(keys, kind="stable")
    order, ordered = stable_sort(keys)
    assert order.dtype == np.int64 and np.array_equal(order, want)
    assert np.array_equal(ordered, keys[want])
    assert np.array_equal(stable_order(keys, 64, np.int32), want)


def test_stable_order_of_float_bit_patterns_with_ties():
    """Non-negative floats order as their bit patterns: the spanning tree's weights."""
    rng = np.random.default_rng(3)
    w = np.concatenate([rng.uniform(0, 1, 3 * _SLICE), np.full(1000, 0.25), np.full(1000, 1e-9), [0.0, 2.0]])
    rng.shuffle(w)
    assert np.array_equal(stable_order(w.view(np.int64), 64, np.int32), np.argsort(w, kind="stable"))


def _grid_reference(points, grid):
    """What build_grid gave with numpy's argsort and gathers (the same cells and origin)."""
    origin, h = grid[1][0][:3], grid[1][0][3]
    cells3 = np.floor((points - origin) / h).astype(np.int64)
    dims = grid[0][2]
    keys = (cells3[:, 0] * dims[1] + cells3[:, 1]) * dims[2] + cells3[:, 2]
    order = np.argsort(keys, kind="stable")
    return order, np.unique(keys), points[order]


@pytest.mark.parametrize("n", [50, 300_000])
def test_grid_order_is_the_stable_argsort_of_the_cells(n):
    rng = np.random.default_rng(n)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    p[: n // 10] = p[n // 10: 2 * (n // 10)]  # coincident points: ties inside a cell
    grid = build_grid(p, 10)
    order, cell_keys, ordered = _grid_reference(p, grid)
    assert np.array_equal(grid[0][3], order) and np.array_equal(grid[0][0], cell_keys)
    assert all(np.array_equal(grid[1][1 + a], ordered[:, a]) for a in range(3))


def _knn_reference(points, k):
    """The k nearest by brute force, each row in (distance, grid position) order: the search scans
    every block in ascending sorted position and keeps the first of equal distances, so its lists
    are exactly these, ties included."""
    cells, _ = build_grid(points, k)
    order, n = cells[3], points.shape[0]
    position = np.empty(n, np.int64)
    position[order] = np.arange(n)
    indices, distances = np.full((n, k), -1, np.int64), np.full((n, k), np.inf)
    for p in range(n):
        dx, dy, dz = (points[:, a] - points[p, a] for a in range(3))
        d2 = dx * dx + dy * dy + dz * dz  # the search's sum, in its order
        d2[p] = np.inf
        near = np.lexsort((position, d2))[:min(k, n - 1)]
        indices[p, :near.size], distances[p, :near.size] = near, np.sqrt(d2[near])
    return indices, distances


def _knn_clouds():
    rng = np.random.default_rng(5)
    sphere = rng.normal(size=(3000, 3))
    sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    duplicates = sphere.copy()
    duplicates[:600] = duplicates[600:1200]  # coincident points: ties at distance 0
    clusters = (rng.normal(size=(20, 1, 3)) + 0.01 * rng.normal(size=(20, 150, 3))).reshape(-1, 3)
    lattice = np.stack(np.meshgrid(np.arange(15.0), np.arange(15.0), np.arange(12.0)), -1).reshape(-1, 3)
    outliers = np.concatenate([sphere[:2500], rng.uniform(-40, 40, size=(6, 3))])  # the wider rings
    return {"few": rng.uniform(size=(5, 3)), "uniform": rng.uniform(size=(3000, 3)), "sphere": sphere,
            "duplicates": duplicates, "clusters": clusters, "lattice (exact ties)": lattice, "outliers": outliers}


@pytest.mark.parametrize("cloud", list(_knn_clouds()))
@pytest.mark.parametrize("k", [3, 10])
def test_nearest_rows_are_the_brute_force_lists(cloud, k):
    """Bit for bit the brute-force lists in the caller's order, ties broken by the grid position,
    -1 and inf kept where there are fewer than k others."""
    p = _knn_clouds()[cloud]
    idx, dist = nearest_neighbours(p, k)
    want_idx, want_dist = _knn_reference(p, k)
    assert np.array_equal(idx, want_idx) and np.array_equal(dist, want_dist)
    assert (idx >= 0).sum() == p.shape[0] * min(k, p.shape[0] - 1)


def _graph_reference(indices):
    """The union of the lists, both ways, by numpy: rows sorted and unique."""
    n = indices.shape[0]
    rows = np.repeat(np.arange(n), indices.shape[1])
    cols = indices.ravel()
    keep = cols >= 0
    pairs = np.unique(np.concatenate([np.stack([rows[keep], cols[keep]], 1),
                                      np.stack([cols[keep], rows[keep]], 1)]), axis=0)
    return np.concatenate([[0], np.cumsum(np.bincount(pairs[:, 0], minlength=n))]), pairs[:, 1]


@pytest.mark.parametrize("n,k", [(4, 6), (3000, 10), (50_000, 3)])
def test_symmetric_graph_matches_the_union_of_both_directions(n, k):
    """Few points (lists padded with -1), rows sorted without repeats, many one-way edges (k = 3)."""
    rng = np.random.default_rng(k)
    p = rng.uniform(size=(n, 3)) * np.array([1.0, 1.0, 0.01])
    idx, _ = nearest_neighbours(p, k)
    indptr, nbr = symmetric_graph(idx)
    want_ptr, want = _graph_reference(idx)
    assert np.array_equal(indptr, want_ptr) and np.array_equal(nbr, want)


def test_rows_back_puts_every_field_at_its_row():
    from dataclasses import fields

    import curv
    from curv.locality import rank, rows_back

    p = np.random.default_rng(5).normal(size=(3000, 3))
    cloud = curv.PointCloud(p / np.linalg.norm(p, axis=1, keepdims=True))
    res = curv.estimate(cloud, "qs", 2)
    order = np.random.default_rng(6).permutation(3000)
    back = rows_back(res, order)
    for f in ("k1", "k2", "d1", "d2", "normals", "valid", "reason"):
        a, b = getattr(res, f), getattr(back, f)
        assert b.dtype == a.dtype and b.shape == a.shape
        assert np.array_equal(b[order], a, equal_nan=a.dtype.kind == "f")
    assert np.array_equal(rank(order)[order], np.arange(3000))
    assert {f.name for f in fields(res)} >= {"k1", "k2", "valid", "reason"}
