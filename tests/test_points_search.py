"""Point search: the grid kNN against a kd-tree, and the neighbour graph's ball search against brute force."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

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


@pytest.mark.parametrize("name,cloud", list(_gap_clouds()), ids=[c[0] for c in _gap_clouds()])
def test_screened_gap_reads_the_same_above_its_screen(name, cloud):
    """Below the screen the pass keeps only an upper bound of the gap (the occupied bins), itself
    below the screen: every test against a threshold at or above the screen reads the same."""
    from curv.core.jit import run_to_end
    from curv.point_normals.normals import EXACT_GAP
    from curv.point_normals.one_pass import _one_pass

    radii = ball_radii(cloud, Range(k=3), uses_normals=False)
    exact = run_to_end(_one_pass(cloud, radii)).gap_a
    screened = run_to_end(_one_pass(cloud, radii, screens=(EXACT_GAP, 0.0))).gap_a
    above = exact >= EXACT_GAP
    np.testing.assert_array_equal(screened[above], exact[above])
    assert (screened[~above] < EXACT_GAP).all() and (screened[~above] >= exact[~above] - 1e-12).all()
    # the bound is a bound, not the gap: most points below the screen read more than their gap
    assert (~above).sum() > 100 and (screened[~above] > exact[~above] + 1e-6).mean() > 0.5


_FAR_POINT = """
import faulthandler, sys
import numpy as np
import curv
from curv.core.knn import nearest_neighbours

rng = np.random.default_rng(0)
pts = rng.normal(size=(200, 3))
curv.estimate(curv.PointCloud(pts.copy()), "qs", 2)  # compiles (a fresh cache): not timed
faulthandler.dump_traceback_later(float(sys.argv[1]), exit=True)
pts[-1] = (2.0 ** 31, 0.0, 0.0)
idx, dist = nearest_neighbours(pts, 10)
result = curv.estimate(curv.PointCloud(pts), "qs", 2)
print(int(idx[-1, 0] >= 0), int(result.valid[:-1].sum()))
"""


def test_one_far_point_costs_its_points_not_the_empty_cells(tmp_path):
    """A point 2^31 away from 199 others spans ~10^7 empty cells of the grid: a kNN that grows its
    block a ring at a time, or a ball search that visits every column of the block, took 100-390 s
    here. The search walks the occupied cells instead when they are fewer than the block's columns."""
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, "-c", _FAR_POINT, "60"], capture_output=True, text=True, timeout=900,
                          env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    found, valid = map(int, proc.stdout.split())
    assert found == 1 and valid > 150


def _lattice_plane(step=2.0 ** -6, side=48, origin=(0.0, 0.0, 0.0)):
    """Points on a tilted lattice whose x and y are exact multiples of a power of two: many sit on
    the ball grid's cell bounds."""
    u, v = np.meshgrid(np.arange(side) * step, np.arange(side) * step)
    pts = np.column_stack([u.ravel(), v.ravel(), 0.5 * u.ravel()])
    return curv.PointCloud(pts + np.asarray(origin))


def _pruned_clouds():
    yield "uniform sphere", curv.PointCloud(_sphere_points(3000, 5))
    yield "rows 5:1", sample_points(QuadraticPatch(), 3000, sampling="rows", ratio=5, rng=2).cloud
    yield "lattice on cell bounds", _lattice_plane()
    yield "georeferenced lattice", _lattice_plane(step=0.25, side=40, origin=(512000.0, 4096000.0, 120.0))
    yield "sphere far from the origin", curv.PointCloud(1e-3 * _sphere_points(2000, 6) + 1e4)


@pytest.mark.parametrize("name,cloud", list(_pruned_clouds()), ids=[c[0] for c in _pruned_clouds()])
def test_a_cells_block_skipping_far_cells_gives_every_ball_in_the_search_order(name, cloud):
    """The pass reads each ball from its cell's block, one run per occupied cell, skipping the
    cells whose box lies farther than the radius (:func:`curv.core.grid_blocks.block_cells`): the
    same points in the same order as the plain search, also where points lie on the cells' bounds
    or far from the origin."""
    from curv.core.grid_blocks import block_around, block_cells, block_runs, cell_coordinates
    from curv.core.knn import block_gather, cell_of, grid_gather, ring_of

    radii = 3.0 * point_spacing(cloud)
    cells, coords = cloud.ball_grid(radii)
    n = cloud.n_points
    queue, dist2, want, want_d = (np.empty(n + 1, np.int64), np.empty(n + 1), np.empty(n + 1, np.int64),
                                  np.empty(n + 1))
    runs, bounds, columns = np.empty((4, 2), np.int64), np.empty((4, 6)), np.empty((4, 2), np.int64)
    skipped = skipped_z = 0
    for i in range(n):
        r2 = float(radii[cells[3][i]] ** 2)
        c = cell_of(i, cells[1])
        block = block_around(*cell_coordinates(cells[0][c], cells[2]), ring_of(r2, cells[2], coords[0]), cells[2])
        m, runs, bounds = block_cells(block, cells, coords[0], runs, bounds)
        # the block's points in the columns' order, one run per occupied cell
        m_col, columns = block_runs(block, cells, columns)
        assert np.array_equal(np.concatenate([np.arange(a, b) for a, b in runs[:m]]),
                              np.concatenate([np.arange(a, b) for a, b in columns[:m_col]]))
        assert all(cell_of(a, cells[1]) == cell_of(b - 1, cells[1]) for a, b in runs[:m])
        count = block_gather(i, r2, (runs, m, bounds), coords, queue, dist2)
        expect = grid_gather(i, r2, cells, coords, want, want_d)
        assert count == expect and np.array_equal(queue[:count], want[:count]), f"point {i}"
        np.testing.assert_array_equal(dist2[:count], want_d[:count])
        p = np.array([coords[1][i], coords[2][i], coords[3][i]])
        near = np.maximum(np.maximum(bounds[:m, [0, 2, 4]] - p, p - bounds[:m, [1, 3, 5]]), 0.0) ** 2
        skipped += int((near.sum(axis=1) > r2).sum())
        skipped_z += int(((near[:, :2].sum(axis=1) <= r2) & (near.sum(axis=1) > r2)).sum())
    assert skipped > 0 and skipped_z > 0  # the test reaches the skip, and the one in z


def test_a_line_check_the_pass_left_out_reads_as_if_the_pass_had_measured_it():
    """The normals' pass measures the line check at R2 only; an estimate that asks for the one
    without the neighbours' normals (mru, an: R1) has it measured over the pass's own grid, so its
    supports' points come in the pass's order: the spreads are those of a pass measuring both."""
    from curv.core.jit import run_to_end
    from curv.point_normals import border_radii, point_normals, support_spread
    from curv.point_normals.normals import EXACT_GAP, ONE_SIDED_GAP, _default_spreads, _radii
    from curv.point_normals.one_pass import _one_pass

    for cloud_of in (lambda: sample_points(QuadraticPatch(), 4000, sampling="rows", ratio=4, rng=3).cloud,
                     lambda: curv.PointCloud(_sphere_points(5000, 7))):
        ref = cloud_of()
        both = run_to_end(_one_pass(ref, border_radii(ref), _radii(ref, 2), jet=True, spreads=_default_spreads(ref),
                                    screens=(EXACT_GAP, ONE_SIDED_GAP)))
        cloud = cloud_of()
        point_normals(cloud)
        r2, r1 = _default_spreads(cloud)
        np.testing.assert_array_equal(_run_gen(support_spread(cloud, r2)), both.spreads[0])
        np.testing.assert_array_equal(_run_gen(support_spread(cloud, r1)), both.spreads[1])
