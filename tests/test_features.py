"""Sharp features: the feature rule, FEATURE reasons, supports that stop at creases, smooth meshes unchanged."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.estimators import ESTIMATORS
from curv.core.features import feature_set, sector_corner_normals
from curv.geometry.neighbourhood import supports
from curv.core.ranges import Range, ball_radii
from creased_meshes import box, folded_strip, mirrored_sheet
from meshes import icosphere, torus_grid

METHODS = sorted(ESTIMATORS)
FIELDS = ("k1", "k2", "d1", "d2", "reason", "valid", "normals")


def test_box_dihedral_angles_are_exactly_0_or_90():
    mesh = box(3)
    angles = curv.dihedral_angles(mesh)
    assert np.isfinite(angles).all()  # closed: no border edge
    sharp = angles > 45
    assert np.allclose(angles[sharp], 90.0) and np.allclose(angles[~sharp], 0.0, atol=1e-6)
    assert sharp.sum() == 12 * 3  # 12 cube edges of 3 mesh edges each


def test_box_feature_vertices_and_corners():
    mesh = box(3)
    edges = curv.feature_edges(mesh, 30)
    on_edge = curv.feature_vertices(mesh, edges)
    corners = curv.feature_corners(mesh, edges)
    v = mesh.vertices
    # a vertex lies on a cube edge when two of its coordinates are 0 or 1
    extreme = (np.isclose(v, 0) | np.isclose(v, 1)).sum(axis=1)
    assert np.array_equal(on_edge, extreme >= 2)
    assert np.array_equal(corners, extreme == 3)
    assert corners.sum() == 8


def test_folded_strip_angle_threshold_and_borders():
    mesh, fold = folded_strip(40.0, n=4)
    angles = curv.dihedral_angles(mesh)
    assert np.isnan(angles[mesh.border_edges]).all()
    on_fold = np.all(fold[mesh.edges], axis=1) & ~mesh.border_edges
    assert np.allclose(angles[on_fold], 40.0)
    assert np.allclose(angles[~on_fold & ~mesh.border_edges], 0.0, atol=1e-6)
    assert np.array_equal(curv.feature_edges(mesh, 39.0), on_fold)
    assert not curv.feature_edges(mesh, 41.0).any()
    # border edges are never features, even when a mask says so
    all_edges = np.ones(mesh.edges.shape[0], bool)
    assert np.array_equal(curv.feature_edges(mesh, all_edges), ~mesh.border_edges)
    assert not curv.feature_corners(mesh, on_fold).any()


def test_bad_feature_arguments():
    mesh = box(2)
    with pytest.raises(curv.EstimatorError, match="between 0 and 180"):
        curv.feature_edges(mesh, -5)
    with pytest.raises(curv.EstimatorError, match="shape"):
        curv.feature_edges(mesh, np.zeros(3, bool))
    with pytest.raises(curv.EstimatorError, match="angle"):
        curv.estimate(mesh, "qs", features="sharp")


def test_suggest_threshold():
    assert curv.suggest_threshold(box(3)) == 45.0
    assert curv.suggest_threshold(icosphere(2)) is None
    mesh, _ = folded_strip(70.0, n=4)
    assert curv.suggest_threshold(mesh) == 35.0


def test_report_counts_sharp_edges():
    assert box(3).report().sharp_edges == 36
    assert icosphere(2).report().sharp_edges == 0
    assert any("sharp" in line for line in box(3).report().lines())


@pytest.mark.parametrize("method", METHODS)
def test_crease_and_corner_vertices_are_feature(method):
    mesh = box(4)
    res = curv.estimate(mesh, method, features=30)
    on_edge = curv.feature_vertices(mesh, curv.feature_edges(mesh, 30))
    assert np.all(res.reason[on_edge] == curv.Reason.FEATURE)
    assert np.isnan(res.k1[on_edge]).all() and not res.valid[on_edge].any()
    # every other vertex is on a flat face, estimated from its own face only: zero curvature
    assert res.valid[~on_edge].all()
    assert np.allclose(res.k1[~on_edge], 0.0, atol=1e-9) and np.allclose(res.k2[~on_edge], 0.0, atol=1e-9)
    assert res.info["features"] == 30.0 and res.info["feature_edges"] == 48


@pytest.mark.parametrize("method", METHODS)
def test_flat_fold_is_exact_next_to_the_crease(method):
    """Both sides are planes: with features on every estimate off the crease is exactly 0."""
    mesh, fold = folded_strip(60.0, n=6)
    on = curv.estimate(mesh, method, features=30)
    off = curv.estimate(mesh, method)
    near = on.valid & ~fold
    assert near.sum() >= 10  # the closed-ring estimators lose the vertices near the border
    assert np.abs(on.mean[near]).max() < 1e-9
    if method != "meyer":  # meyer's 1-ring never reaches across; everyone else's support does
        assert np.nanmax(np.abs(off.mean[~fold])) > 0.1


@pytest.mark.parametrize("method", METHODS)
def test_curved_crease_error_near_the_crease_like_the_interior(method):
    mesh, ring = mirrored_sheet(30.0, n=9, curvature=0.8)
    y = mesh.vertices[:, 1]
    exact = 0.8 / (1 + (0.8 * y) ** 2) ** 1.5  # |k1 + k2| on both (mirror-image) sides
    inner = np.abs(y) < 0.6  # keep away from the borders
    res = curv.estimate(mesh, method, features=30)
    err = np.abs(np.abs(res.k1 + res.k2) - exact)
    assert np.all(res.reason[ring == 0] == curv.Reason.FEATURE)
    interior = np.nanmax(err[inner & (ring >= 4) & (ring <= 6)])
    near = np.nanmax(err[inner & (ring >= 1) & (ring <= 2)])
    assert near <= 2.0 * interior + 1e-12


def test_supports_do_not_cross_a_crease():
    mesh, fold = folded_strip(60.0, n=6)
    x = mesh.vertices[:, 0]
    left = (x < -1e-9) & ~fold
    fs = feature_set(mesh, 30)
    from curv.geometry.neighbourhood import expansion_adjacency

    radii = ball_radii(mesh, Range(k=3.0), uses_normals=False)
    centres = np.flatnonzero(left)
    indptr, indices = supports(mesh, radii, centres, blocked=fs.vertices)
    reached = np.zeros(mesh.n_vertices, bool)
    reached[indices] = True
    assert reached[fold].any()  # the crease's own vertices are in the supports
    assert not reached[~left & ~fold].any()  # the other side never is
    # without features the same balls do reach the other side
    _, plain = supports(mesh, radii, centres)
    assert (~left & ~fold)[plain].any()
    # the adjacency the search expands along has the crease rows emptied
    ptr, _ = expansion_adjacency(mesh, fs.vertices)
    assert np.all(np.diff(ptr)[fs.vertices] == 0)


def test_sector_normals_are_the_sides_normals():
    mesh, fold = folded_strip(60.0, n=4)
    fs = feature_set(mesh, 30)
    normals = curv.vertex_normals(mesh)
    corner = sector_corner_normals(mesh, normals, fs)
    face_normal = mesh.face_normals[mesh.corner_face]
    at_fold = fold[mesh.face_indices]
    # on a flat side every corner's sector normal is its face's normal
    assert np.allclose(corner[at_fold], face_normal[at_fold])
    assert np.array_equal(corner[~at_fold], normals[mesh.face_indices][~at_fold])
    # the blended vertex normal is not
    assert not np.allclose(normals[mesh.face_indices][at_fold], face_normal[at_fold])


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("normals", [None, "fit"])
def test_smooth_mesh_unchanged_bit_for_bit(method, normals):
    mesh = torus_grid(40, 20)[0]
    assert not curv.feature_edges(mesh, 30).any()
    plain = curv.estimate(mesh, method, normals=normals)
    with_features = curv.estimate(mesh, method, normals=normals, features=30)
    for name in FIELDS:
        assert np.array_equal(getattr(plain, name), getattr(with_features, name), equal_nan=True), name


@pytest.mark.parametrize("method", METHODS)
def test_a_feature_far_away_changes_nothing_here(method):
    """The feature path (blocked search, crease normals left out, sector normals) leaves every
    vertex whose range cannot reach the crease bit-for-bit as it was."""
    import scipy.sparse.csgraph as csgraph

    mesh = torus_grid(40, 20)[0]
    mask = np.zeros(mesh.edges.shape[0], bool)
    mask[0] = True
    plain = curv.estimate(mesh, method)
    res = curv.estimate(mesh, method, features=mask)
    assert res.info["features"] == "mask" and res.info["feature_edges"] == 1
    rings = csgraph.shortest_path(mesh.adjacency, unweighted=True, indices=mesh.edges[0]).min(axis=0)
    assert np.all(res.reason[rings == 0] == curv.Reason.FEATURE)
    # icc and csm leave out every face touching a crease vertex: one ring further than the support reaches
    far = rings > (5 if method in ("icc", "csm") else 4)
    for name in FIELDS:
        assert np.array_equal(getattr(plain, name)[far], getattr(res, name)[far], equal_nan=True), name


def test_fit_normals_honour_features():
    mesh, fold = folded_strip(60.0, n=6)
    res = curv.estimate(mesh, "mru", normals="fit", features=30)
    near = res.valid & ~fold
    assert np.abs(res.mean[near]).max() < 1e-9
    assert np.all(res.reason[fold] == curv.Reason.FEATURE)


def test_dihedral_angles_are_computed_once_per_mesh_and_read_only():
    mesh = curv.surfaces.SURFACES["box"]().mesh(n_vertices=1500).mesh
    first = curv.dihedral_angles(mesh)
    assert curv.dihedral_angles(mesh) is first and not first.flags.writeable
    # any threshold reads the same angles: an angle and its mask give the same estimate
    mask = curv.feature_edges(mesh, 30.0)
    by_angle = curv.estimate(mesh, "qs", 2, features=30.0)
    by_mask = curv.estimate(mesh, "qs", 2, features=mask)
    np.testing.assert_array_equal(by_angle.k1, by_mask.k1)
    np.testing.assert_array_equal(by_angle.reason, by_mask.reason)
    assert mask.sum() > 0
