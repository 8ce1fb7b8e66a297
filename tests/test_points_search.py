"""Point search: the grid kNN against a kd-tree, and the neighbour graph's ball search against brute force."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import curv
from curv.core.knn import GRAPH_NEIGHBOURS, nearest_neighbours, symmetric_graph
from curv.geometry.neighbourhood import supports
from curv.core.ranges import Range, ball_radii, point_spacing
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


def _sorted_gaps(cloud, radii, normals):
    """The widest angular gap of every ball by brute force: atan2 of the projected offsets, sorted."""
    gaps = np.full(cloud.n_points, 2 * np.pi)
    for i, ball in enumerate(cKDTree(cloud.points).query_ball_point(cloud.points, radii)):
        n = normals[i]
        if not np.isfinite(n).all():
            continue
        e1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        d = cloud.points[[j for j in ball if j != i]] - cloud.points[i]
        u, v = d @ e1, d @ e2
        keep = u * u + v * v > 0
        if keep.sum() < 2:
            continue
        a = np.sort(np.arctan2(v[keep], u[keep]))
        gaps[i] = max(a[0] + 2 * np.pi - a[-1], np.diff(a).max())
    return gaps


def _gap_clouds():
    yield "blue patch", sample_points(QuadraticPatch(), 2000, sampling="blue", rng=1).cloud
    yield "rows 5:1", sample_points(QuadraticPatch(), 2000, sampling="rows", ratio=5, rng=2).cloud
    # an axis-aligned flat grid: projections with exact (and signed) zeros, ties on the bins' edges
    i, j = np.meshgrid(np.arange(25), np.arange(25))
    yield "flat grid", curv.PointCloud(np.column_stack([i.ravel(), j.ravel(), np.zeros(i.size)]).astype(float))


@pytest.mark.parametrize("name,cloud", list(_gap_clouds()), ids=[c[0] for c in _gap_clouds()])
@pytest.mark.parametrize("k", [2, 3])
def test_binned_gap_is_the_sorted_gap(name, cloud, k):
    from curv.point_normals import local_frames

    radii = ball_radii(cloud, Range(k=k), uses_normals=False)
    normals, gap, count = _run_gen(local_frames(cloud, radii))
    want = _sorted_gaps(cloud, radii, normals)
    # exact down to rounding wherever the widest gap spans two bins (7.2 degrees) or more
    np.testing.assert_allclose(gap, want, rtol=0, atol=1e-9)
    assert (gap > np.radians(135)).any() and (gap < np.radians(90)).any()
    np.testing.assert_array_equal(count, [len(b) - 1 for b in cKDTree(cloud.points).query_ball_point(cloud.points, radii)])


def _run_gen(gen):
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


def test_one_pass_gives_the_jet_normals_and_spreads_of_the_separate_kernels():
    """The fused pass (frames, jet normals, line checks from one ball search per point) agrees with
    the estimator's own jet normal kernel and with a separate spread pass, to rounding."""
    from curv.estimators.jet import jet_normals
    from curv.point_normals import local_frames, point_normals, support_spread

    cloud = sample_points(QuadraticPatch(), 3000, sampling="blue", rng=4).cloud
    est = point_normals(cloud)
    pca, _, _ = _run_gen(local_frames(cloud, ball_radii(cloud, Range(k=3), uses_normals=False)))
    oriented = np.where(np.einsum("ij,ij->i", pca, est.normals)[:, None] < 0, -pca, pca)
    r2 = ball_radii(cloud, Range(k=2), uses_normals=False)
    fitted, _ = _run_gen(jet_normals(cloud, oriented, r2))
    ok = np.isfinite(est.normals).all(axis=1)
    assert ok.mean() > 0.9
    np.testing.assert_allclose(est.normals[ok], fitted[ok], atol=1e-9)
    # the line check of an estimate at R2 comes from the pass, else from its own walk, or a region's
    cached = _run_gen(support_spread(cloud, r2))
    fresh = _run_gen(support_spread(curv.PointCloud(cloud.points), r2))
    np.testing.assert_allclose(cached, fresh, rtol=0, atol=1e-12)
    centres = np.arange(0, cloud.n_points, 7)
    region = _run_gen(support_spread(curv.PointCloud(cloud.points), r2, centres))
    np.testing.assert_allclose(region[centres], fresh[centres], rtol=0, atol=1e-12)


def test_a_support_along_a_bending_row_has_no_spread_and_a_patch_keeps_its_own():
    """The line check reads a scan row over a curved surface (a plane curve) as one-dimensional: its
    sagitta is a quadratic function of the position along the row, and is not taken for width."""
    from curv.point_normals import MIN_SPREAD, support_spread

    u = np.linspace(-1.0, 1.0, 41)
    row = np.column_stack([u, np.zeros_like(u), 0.5 * u**2])   # a parabola, curvature 1 at its vertex
    cloud = curv.PointCloud(row)
    centre = np.array([20])
    radii = np.full(row.shape[0], 1.0)
    spread = _run_gen(support_spread(cloud, radii, centre))[20]
    offsets = row - row[20]
    eig = np.linalg.eigvalsh(offsets.T @ offsets)
    assert np.sqrt(eig[1] / eig[2]) > MIN_SPREAD  # the plain eigenvalue ratio reads the sagitta as width
    assert spread < 1e-6
    # across a patch of the same surface the second direction is independent of the first
    g = np.linspace(-1.0, 1.0, 21)
    x, y = (a.ravel() for a in np.meshgrid(g, 0.5 * g))
    patch = np.column_stack([x, y, 0.5 * x**2 + 0.5 * y**2])
    centre = np.array([len(patch) // 2])
    spread = _run_gen(support_spread(curv.PointCloud(patch), np.full(len(patch), 2.0), centre))[centre[0]]
    assert spread == pytest.approx(0.5, rel=0.05)  # half as wide as long
    # neighbours the estimator cannot use (no normal) are not counted: the patch's centre row alone is a row
    usable = np.abs(patch[:, 1]) < 1e-12
    thin = _run_gen(support_spread(curv.PointCloud(patch), np.full(len(patch), 2.0), centre, usable=usable))
    assert thin[centre[0]] < 1e-6


@pytest.mark.parametrize("name,cloud", list(_clouds())[:3], ids=[c[0] for c in _clouds()][:3])
def test_grid_ordered_twin_has_the_same_neighbours(name, cloud):
    """The twin in grid order holds the cloud's points in that order, and its nearest neighbours are the
    cloud's, ties included (the same cells, scanned in the same order)."""
    from curv.point_normals import grid_ordered

    shuffled = curv.PointCloud(cloud.points[np.random.default_rng(5).permutation(cloud.n_points)])
    twin, order = grid_ordered(shuffled)
    assert np.array_equal(np.sort(order), np.arange(shuffled.n_points))
    assert np.array_equal(twin.points, shuffled.points[order])
    assert grid_ordered(twin) is None and grid_ordered(shuffled)[0] is twin
    assert np.array_equal(twin.grid[0][3], np.arange(twin.n_points))
    idx, dist = shuffled.nearest
    twin_idx, twin_dist = twin.nearest
    assert np.array_equal(twin_dist, dist[order])
    assert np.array_equal(np.where(twin_idx >= 0, order[np.maximum(twin_idx, 0)], -1), idx[order])


def test_a_cloud_reads_its_spacing_from_its_twin():
    """After an estimate (on the twin in grid order) the cloud's spacing is the twin's, row for row:
    the same distances as its own search, without a second search."""
    from curv.point_normals import grid_ordered

    points = _sphere_points(3000, 7)
    own = point_spacing(curv.PointCloud(points))
    cloud = curv.PointCloud(points)
    twin, order = grid_ordered(cloud)
    got = point_spacing(cloud)
    assert np.array_equal(got, own)
    assert "nearest" in twin.__dict__ and "nearest" not in cloud.__dict__


def test_a_cloud_reads_its_coincident_and_isolated_points_from_its_twin():
    """A cloud with a grid-ordered twin finds its coincident points (the first of each group stands
    for it, by this cloud's own indices) and isolated points from the twin's search, as its own
    search finds them, and makes no search of its own."""
    from curv.point_normals import grid_ordered

    points = _sphere_points(3000, 11)
    points[[40, 900, 2500]] = points[[2999, 5, 1200]]  # repeats before and after their original
    points = np.vstack([points, [[9.0, 9.0, 9.0]]])    # far from the rest, but not alone in a cloud
    own = curv.PointCloud(points)
    cloud = curv.PointCloud(points)
    grid_ordered(cloud)
    assert np.array_equal(cloud.coincident_points, own.coincident_points)
    assert own.coincident_points.sum() == 3 and not own.coincident_points[[5, 1200]].any()
    assert np.array_equal(cloud.isolated_vertices, own.isolated_vertices)
    assert "nearest" not in cloud.__dict__


def test_stable_rank_is_the_stable_argsort():
    """Kruskal's edge order: the radix sort gives numpy's stable argsort, ties in their order."""
    from curv.point_normals.orientation import _stable_rank

    rng = np.random.default_rng(3)
    for w in (rng.random(3000), np.round(rng.random(5000), 2) + 1e-9, np.full(7, 1e-9), np.zeros(0),
              1.0 - np.abs(rng.uniform(-1, 1, 20000)) + 1e-9, np.array([2.0 ** -40, 0.0, 1.5, 2.0 ** -40, 0.0])):
        assert np.array_equal(_stable_rank(w), np.argsort(w, kind="stable"))
