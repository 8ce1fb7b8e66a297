"""Tiles with halos (curv.tiles): every tiled estimate equals the whole one, on every input kind.

Meshes keep their numbering in a tile, so their results are the whole call's bit for bit (the
standard errors of an and mru, whose default noise model samples 2000 vertices of what is
estimated, are compared with noise_model="normals"). Point clouds hold the same points, the same
neighbours (ties included) and the same supports, but a support's points may be summed in another
order (their ball grid's cell follows the median radius of the tile, not of the whole cloud):
equal to rounding there, the reason codes exactly (curv/tiles/frame.py).
"""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.core.errors import EstimatorError
from curv.core.validity import Reason
from curv.surfaces import Torus, make_surface, sample_points
from curv.tiles import estimate_tiled, support_reach
from curv.tiles.engine import Job, iter_run_tile
from curv.tiles.memory import InMemoryInput, plan_for
from curv.tiles.plan import Region

from clouds import ground_ball_and_roof
from meshes import torus_grid, tube

FIELDS = ("k1", "k2", "d1", "d2", "normals", "k1_se", "k2_se")


def assert_same(tiled, whole, *, rounding: bool = False, signless_directions: bool = False):
    """Equal rows: bit for bit, or to rounding (a few units in the last place) where told."""
    assert np.array_equal(tiled.reason, whole.reason), np.flatnonzero(tiled.reason != whole.reason)[:10]
    assert np.array_equal(tiled.valid, whole.valid)
    for name in FIELDS:
        a, b = np.asarray(getattr(tiled, name)), np.asarray(getattr(whole, name))
        if signless_directions and name in ("d1", "d2"):
            a = a * np.where(np.einsum("ij,ij->i", a, b) < 0, -1.0, 1.0)[:, None]
        if rounding:
            # an ill-conditioned fit (an's seven unknowns) turns a last-place change into 1e-8 of its errors
            np.testing.assert_allclose(a, b, rtol=1e-6 if name.endswith("_se") else 1e-9, atol=1e-12, err_msg=name)
        else:
            assert np.array_equal(a, b, equal_nan=True), (name, np.nanmax(np.abs(a - b)))


@pytest.fixture(scope="module")
def torus_mesh():
    return torus_grid(80, 36)[0]


@pytest.mark.parametrize("method", ["meyer", "csm", "nc", "qs", "an", "ru", "mru", "jet", "icc"])
def test_every_estimator_on_a_closed_mesh_equals_the_whole_call(torus_mesh, method):
    # the fits with their standard errors (pooled over edge neighbours: the halo's extra ring)
    options = {"standard_errors": True} if method in ("nc", "qs", "an", "mru", "jet") else {}
    options.update({"noise_model": "normals"} if method in ("an", "mru") else {})
    whole = curv.estimate(torus_mesh, method, **options)
    tiled = estimate_tiled(torus_mesh, method, tile_size=700, **options)
    assert tiled.info["tiles"] >= 4
    assert_same(tiled, whole)


@pytest.mark.parametrize("method", ["csm", "qs", "mru", "meyer"])
def test_an_open_mesh_with_borders_equals_the_whole_call(method):
    mesh = tube(48, 30)
    options = {"noise_model": "normals", "standard_errors": True} if method == "mru" else {}
    whole = curv.estimate(mesh, method, **options)
    tiled = estimate_tiled(mesh, method, tile_size=300, **options)
    assert (whole.reason == Reason.BORDER).any()
    assert_same(tiled, whole)


@pytest.mark.parametrize("method", ["mru", "qs", "icc", "ru"])
def test_a_creased_mesh_with_features_equals_the_whole_call(method):
    mesh = make_surface("capped_cylinder", n_vertices=3000).mesh
    options = {"noise_model": "normals", "standard_errors": True} if method == "mru" else {}
    whole = curv.estimate(mesh, method, features=30, **options)
    tiled = estimate_tiled(mesh, method, tile_size=500, features=30, **options)
    assert (whole.reason == Reason.FEATURE).any()
    assert_same(tiled, whole)


@pytest.mark.parametrize("keywords", [{"method": "qs", "range": 3}, {"method": "mru", "normals": "fit", "noise_model": "normals",
                                                                       "standard_errors": True},
                                      {"method": "qs", "radius": 0.3}, {"method": "jet", "range": 2.5, "degree": 4}])
def test_a_tiny_halo_is_detected_and_its_points_redone(torus_mesh, keywords):
    whole = curv.estimate(torus_mesh, **keywords)
    tiled = estimate_tiled(torus_mesh, tile_size=700, halo=1e-3, **keywords)
    assert tiled.info["redone"] > 0  # the reach check caught the supports beyond the halo
    assert_same(tiled, whole)


def test_the_engine_keeps_only_what_its_halo_covered(torus_mesh):
    """One tile with no halo: the first pass keeps the core points whose reach stays inside, the
    second (wider) pass the others; the rows are the whole call's."""
    job = Job.checked("qs", 2)
    source = InMemoryInput(torus_mesh)
    plan = plan_for(source.points, 700)
    tile = plan.tiles[0]
    core = np.flatnonzero(plan.tile_of(source.points) == tile.index)
    from curv.core.jit import run_to_end

    rows = run_to_end(iter_run_tile(core, (tile.lo, tile.hi), plan.bounds, source.fetch, job, None, halo=0.0,
                                    points=False))
    assert rows.info["passes"] >= 2 and 0 < rows.info["redone"] < core.size
    whole = curv.estimate(torus_mesh, "qs", 2)
    assert np.array_equal(rows.ids, core)
    assert np.array_equal(rows.columns["k1"], whole.k1[core], equal_nan=True)


def test_a_numbering_too_scattered_for_the_caches_is_kept_as_the_whole_call_renumbers_it():
    mesh = torus_grid(500, 300)[0]
    perm = np.random.default_rng(0).permutation(mesh.n_vertices)
    rank = np.empty_like(perm)
    rank[perm] = np.arange(perm.size)
    shuffled = curv.Mesh(mesh.vertices[perm], rank[mesh.face_indices.reshape(-1, 3)])
    assert shuffled.scattered_order()
    whole = curv.estimate(shuffled, "qs")
    assert_same(estimate_tiled(shuffled, "qs", tile_size=40000), whole)


@pytest.fixture(scope="module")
def torus_cloud():
    return sample_points(Torus(), 6000, sampling="uniform", rng=3).cloud


SCANNER = (0.0, 0.0, 10.0)


@pytest.mark.parametrize("keywords", [{"method": "qs"}, {"method": "mru"}, {"method": "an"}, {"method": "nc"},
                                      {"method": "jet"}, {"method": "qs", "knn": 20}, {"method": "mru", "radius": 0.25},
                                      {"method": "qs", "normals": "pca"}])
def test_every_point_estimator_on_a_cloud_equals_the_whole_call(torus_cloud, keywords):
    whole = curv.estimate(torus_cloud, orient=SCANNER, **keywords)
    tiled = estimate_tiled(torus_cloud, orient=SCANNER, tile_size=1200, **keywords)
    assert tiled.info["tiles"] >= 4
    assert_same(tiled, whole, rounding=True)


def test_a_cloud_with_a_tiny_halo_equals_the_whole_call_to_rounding(torus_cloud):
    whole = curv.estimate(torus_cloud, "mru", orient=SCANNER)
    tiled = estimate_tiled(torus_cloud, "mru", orient=SCANNER, tile_size=1200, halo=1e-3)
    assert tiled.info["redone"] > 0
    assert_same(tiled, whole, rounding=True)


def test_a_cloud_with_its_own_normals_equals_the_whole_call():
    s = sample_points(Torus(), 6000, sampling="uniform", rng=4)
    cloud = curv.PointCloud(s.cloud.points, normals=s.truth.normals)
    for method in ("qs", "mru"):
        assert_same(estimate_tiled(cloud, method, tile_size=1200), curv.estimate(cloud, method), rounding=True)


def test_an_open_scan_with_borders_equals_the_whole_call():
    s = sample_points("quadratic", 5000, sampling="uniform", rng=2)
    whole = curv.estimate(s.cloud, "jet", orient=SCANNER)
    assert (whole.reason == Reason.BORDER).any()
    assert_same(estimate_tiled(s.cloud, "jet", orient=SCANNER, tile_size=900), whole, rounding=True)


def test_tiles_of_a_closed_cloud_oriented_outward_agree_with_the_whole_call(torus_cloud):
    """The spanning tree runs per tile; the tiles' parts are then turned to agree on their overlaps."""
    whole = curv.estimate(torus_cloud, "qs", orient="outward")
    tiled = estimate_tiled(torus_cloud, "qs", orient="outward", tile_size=1200)
    assert_same(tiled, whole, rounding=True, signless_directions=True)


def test_the_reach_covers_the_support_and_the_normals_of_its_points(torus_cloud, torus_mesh):
    from curv.core.ranges import ball_radii, resolve
    from curv.estimators import get_spec

    for shape in (torus_cloud, torus_mesh):
        for method in ("qs", "mru"):
            rng = resolve(get_spec(method), 2)
            radii = ball_radii(shape, rng, uses_normals=get_spec(method).uses_normals)
            reach = support_reach(shape, method, 2)
            assert np.all(reach >= radii)
    # the neighbours' normals reach one normal's fit beyond the support: mru's R3 reads beyond its 2 spacings
    assert np.median(support_reach(torus_cloud, "mru", 3)) > np.median(support_reach(torus_cloud, "qs", 2))


def test_a_region_that_covers_everything_has_unbounded_room():
    region = Region.around(np.zeros(3), np.ones(3), 5.0, (np.zeros(3), np.ones(3)))
    assert region.everything and np.isinf(region.room(np.full((1, 3), 0.5))).all()
    inner = Region.around(np.zeros(3), np.ones(3), 0.5, (np.full(3, -2.0), np.full(3, 2.0)))
    assert inner.room(np.array([[0.2, 0.5, 0.5]]))[0] == pytest.approx(0.7)


@pytest.mark.parametrize("keywords, words", [({"vertices": [1, 2]}, "region"), ({"smooth": "mesh"}, "smooth"),
                                             ({"features": np.zeros(5, bool)}, "angle")])
def test_what_tiles_cannot_run_is_refused_in_one_line(torus_mesh, keywords, words):
    with pytest.raises(EstimatorError, match=words):
        estimate_tiled(torus_mesh, "qs", tile_size=700, **keywords)


def test_a_quantised_scan_with_ties_everywhere_keeps_the_whole_calls_neighbours():
    """Coordinates on a 1 cm grid over a 10 cm lattice: most nearest neighbours tie in distance. A
    tile searches the whole cloud's grid cells in the whole cloud's order, so it keeps the same
    neighbours (a tile laying its own grid kept others: 107 directions of 14,400 points differed)."""
    rng = np.random.default_rng(1)
    x, y = np.meshgrid(np.arange(120) * 0.1, np.arange(120) * 0.1)
    pts = np.stack([x.ravel(), y.ravel(), np.round(0.3 * np.sin(x.ravel()) * np.cos(0.7 * y.ravel()), 2)], 1)
    cloud = curv.PointCloud(pts[rng.permutation(len(pts))])
    for method in ("qs", "mru"):
        whole = curv.estimate(cloud, method, orient=(5, 5, 50))
        assert_same(estimate_tiled(cloud, method, orient=(5, 5, 50), tile_size=2500), whole, rounding=True)


def test_tiles_hold_about_the_asked_count_and_every_point_once():
    from curv.tiles.memory import plan_for

    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(0, 100, 50000), rng.uniform(0, 40, 50000), rng.normal(0, 0.5, 50000)])
    plan = plan_for(pts, 6000)
    tile_of = plan.tile_of(pts)
    counts = np.bincount(tile_of, minlength=len(plan.tiles))
    assert counts.sum() == pts.shape[0] and counts.max() <= 6000 and counts.min() > 2000
    for t in plan.tiles:  # each tile's box holds its points
        mine = pts[tile_of == t.index]
        assert np.all(mine >= np.array(t.lo) - 1e-9) and np.all(mine <= np.array(t.hi) + 1e-9)


def test_a_memory_budget_is_read_and_shared_by_the_workers():
    from curv.tiles.budget import DRIVER_BYTES, parse_memory, plan_budget

    assert parse_memory("4GB") == 4_000_000_000 and parse_memory("1.5 GiB") == int(1.5 * 2**30)
    assert parse_memory("500mb") == 500_000_000 and parse_memory(123456) == 123456
    with pytest.raises(ValueError, match="4GB"):
        parse_memory("four gigabytes")
    budget = plan_budget(4 * 2**30, "qs", points=True, workers=2)
    assert budget.workers == 2 and budget.worker_bytes * 2 + DRIVER_BYTES <= 4 * 2**30
    assert 500_000 < budget.tile_size < 3_000_000
    with pytest.raises(ValueError, match="no room"):
        plan_budget(700 * 2**20, "qs", points=True)


def test_a_cloud_oriented_from_its_top_by_default_agrees_with_the_whole_call(torus_cloud):
    """A cloud that is not a georeferenced scan propagates its normals from each part's top
    (``orient="top"``): each tile along its own trees, then their parts turned to agree."""
    whole = curv.estimate(torus_cloud, "mru")
    assert whole.info["orientation"] == "top"
    assert_same(estimate_tiled(torus_cloud, "mru", tile_size=1200), whole, rounding=True, signless_directions=True)


def test_other_libraries_inputs_and_the_default_estimator_as_in_the_whole_call(torus_cloud, torus_mesh):
    trimesh = pytest.importorskip("trimesh")
    points = np.asarray(torus_cloud.points)
    for cloud in (points, trimesh.PointCloud(points)):
        tiled = estimate_tiled(cloud, orient=SCANNER, tile_size=1500)
        assert tiled.method == curv.estimators.DEFAULT_ESTIMATORS["points"] and tiled.info["tiles"] >= 3
        assert_same(tiled, curv.estimate(cloud, orient=SCANNER), rounding=True)
    mesh = trimesh.Trimesh(torus_mesh.vertices, torus_mesh.faces, process=False)
    tiled = estimate_tiled(mesh, tile_size=1500, noise_model="normals")  # the sampled one's errors: to 5-7 %
    assert tiled.method == curv.estimators.DEFAULT_ESTIMATORS["mesh"]
    assert_same(tiled, curv.estimate(mesh, noise_model="normals"))


@pytest.mark.parametrize("halo", [None, 1.0])
def test_each_part_of_a_tile_is_turned_on_its_own_as_the_whole_call_orients_it(halo):
    """A tile's region holds several parts (ground and ball; a roof apart): each is turned by its own
    votes and rooted as the whole call roots its points. Turning whole tiles left the ground and ball
    of the left tile upside down (19,568 of 20,560 points, the group rooted at the roof's top); a
    narrow halo redoes points on wider regions, whose trees are matched to the first pass's."""
    points = ground_ball_and_roof()
    whole = curv.estimate(curv.PointCloud(points), "qs")
    assert whole.info["orientation"] == "top"
    tiled = estimate_tiled(curv.PointCloud(points), "qs", tile_size=11000, halo=halo)
    assert tiled.info["tiles"] == 2
    if halo is not None:
        assert tiled.info["redone"] > 0
    assert np.mean(whole.normals[:20000, 2] > 0) > 0.95  # the ground up, as its top turns it
    assert (whole.normals[-110:, 2] > 0).all()  # the roof up, its own part
    assert_same(tiled, whole, rounding=True, signless_directions=True)



def test_a_group_of_parts_is_rooted_and_turned_by_the_normals_its_propagation_turned():
    """The whole call roots a part at its highest point with a finite propagated normal and turns
    that normal up; a jet fit shown there may lean the other way of the horizontal (4M terrain
    points: a roof's crest at nz = -0.115), so the rows' shown normals must not decide the turn."""
    from curv.tiles.orient import group_roots

    group = np.array([0, 0, 1])  # parts 0 and 1 in group 0, part 2 alone
    xyz = np.array([[0, 0, 5.0], [1, 0, 9.0], [2, 0, 3.0], [5, 5, 1.0], [6, 5, 2.0]])
    part = np.array([0, 1, 1, 2, 2])
    rooting = np.array([[0, 0, 1.0], [0.99, 0, -0.14], [0, 0, -1.0], [np.nan] * 3, [0, 0.6, -0.8]])
    root, sign = group_roots(group, "top", lambda: iter([(part, xyz, rooting)]))
    assert root.tolist() == [1, 2] and sign.tolist() == [-1, -1]
    centre = xyz[:3].mean(axis=0)
    root, sign = group_roots(group, "outward", lambda: iter([(part[:3], xyz[:3], rooting[:3]),
                                                              (part[3:], xyz[3:], rooting[3:])]))
    far = int(np.argmax(np.linalg.norm(xyz[:3] - centre, axis=1)))
    assert root[0] == part[far] and sign[0] == (1 if rooting[far] @ (xyz[far] - centre) >= 0 else -1)
    # part 2's centroid is its two points' (5.5, 5, 1.5); its one finite normal points towards it
    assert root[1] == 2 and sign[1] == -1
