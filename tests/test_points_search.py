"""Point search: the grid kNN against a kd-tree, and the neighbour graph's ball search against brute force."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import curv
from curv.knn import GRAPH_NEIGHBOURS, nearest_neighbours, symmetric_graph
from curv.neighbourhood import supports
from curv.ranges import Range, ball_radii, point_spacing
from curv.surfaces import QuadraticPatch, Sphere, sample_points


def _sphere_points(n, seed=0):
    p = np.random.default_rng(seed).normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True)


@pytest.mark.parametrize("k", [1, 6, 10, 25])
def test_grid_knn_matches_kdtree(k):
    rng = np.random.default_rng(k)
    # a surface sample with a dense clump and a few far points: the grid must grow its search there
    p = np.vstack([_sphere_points(3000, k), 0.01 * _sphere_points(200, k + 1), rng.uniform(-5, 5, (5, 3))])
    idx, dist = nearest_neighbours(p, k)
    want_d, want_i = cKDTree(p).query(p, k + 1)
    np.testing.assert_allclose(dist, want_d[:, 1:], rtol=0, atol=1e-15)
    # indices agree wherever distances are not tied
    assert (idx == want_i[:, 1:]).mean() > 0.999
    assert np.allclose(np.linalg.norm(p[idx] - p[:, None, :], axis=2), dist)


def test_knn_with_fewer_points_than_k():
    p = np.random.default_rng(0).uniform(size=(4, 3))
    idx, dist = nearest_neighbours(p, 6)
    assert (idx[:, 3:] == -1).all() and np.isinf(dist[:, 3:]).all()
    assert (np.sort(idx[:, :3], axis=1) == np.array([[j for j in range(4) if j != i] for i in range(4)])).all()


def test_symmetric_graph_is_the_union_of_the_knn_lists():
    p = _sphere_points(500)
    idx, _ = nearest_neighbours(p, 5)
    indptr, nbr = symmetric_graph(idx)
    rows = np.repeat(np.arange(500), np.diff(indptr))
    got = set(zip(rows.tolist(), nbr.tolist()))
    want = {(i, int(j)) for i in range(500) for j in idx[i]} | {(int(j), i) for i in range(500) for j in idx[i]}
    assert got == want


def _clouds():
    yield "uniform sphere", curv.PointCloud(_sphere_points(4000, 3))
    yield "blue patch", sample_points(QuadraticPatch(), 3000, sampling="blue", rng=1).cloud
    yield "rows 5:1", sample_points(QuadraticPatch(), 3000, sampling="rows", ratio=5, rng=2).cloud
    yield "sphere scaled 1e-3", curv.PointCloud(1e-3 * _sphere_points(3000, 4))


@pytest.mark.parametrize("name,cloud", list(_clouds()), ids=[c[0] for c in _clouds()])
@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_graph_ball_search_finds_the_brute_force_ball(name, cloud, k):
    radii = ball_radii(cloud, Range(k=k), uses_normals=False)
    indptr, indices = supports(cloud, radii)
    tree = cKDTree(cloud.points)
    want = tree.query_ball_point(cloud.points, radii)
    missing = 0
    for i, ball in enumerate(want):
        got = set(indices[indptr[i]:indptr[i + 1]].tolist())
        ball = set(ball) - {i}
        assert got <= ball
        missing += len(ball - got)
    assert missing == 0, f"{missing} points of the balls not reached through the graph"


def test_knn_range_is_the_k_nearest():
    cloud = curv.PointCloud(_sphere_points(2000, 5))
    for k in (8, 20, 40):
        radii = ball_radii(cloud, Range(knn=k), uses_normals=False)
        indptr, _ = supports(cloud, radii)
        assert (np.diff(indptr) == k).all()


def test_spacing_is_the_sixth_neighbour_and_matches_the_mesh_edge_on_a_lattice():
    # a regular triangular lattice: six neighbours at distance 1, so spacing == longest 1-ring edge
    i, j = np.meshgrid(np.arange(30), np.arange(30))
    xy = np.column_stack([(i + 0.5 * j).ravel(), (np.sqrt(3) / 2 * j).ravel()])
    pts = np.column_stack([xy, np.zeros(len(xy))])
    cloud = curv.PointCloud(pts)
    inner = (i.ravel() > 1) & (i.ravel() < 28) & (j.ravel() > 1) & (j.ravel() < 28)
    np.testing.assert_allclose(point_spacing(cloud)[inner], 1.0)
    assert GRAPH_NEIGHBOURS >= 6
