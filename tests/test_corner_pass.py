"""The fused fresh-mesh kernels against plain definitions: the one walk over the corners (flags,
neighbours, longest edge, Max normals), the report's edge counts without the edge table, the hash
count of duplicate positions, the union-find components and the corner links."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import curv
from curv.core import connectivity
from curv.core.jit import launch
from curv.geometry.normals import _vertex_normals, MAX
from tests.test_connectivity_kernels import IDS, MESHES


def _grid_soup(seed: int) -> curv.Mesh:
    """Vertices on a small integer grid (many repeated positions, some at -0.0), random faces."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 80))
    v = rng.integers(-1, 2, size=(n, 3)).astype(float)
    v[rng.random(v.shape) < 0.2] = -0.0
    return curv.Mesh(v, rng.integers(0, n, size=(int(rng.integers(1, 60)), 3)))


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_corner_pass_normals_are_the_max_normals(mesh):
    indptr, corners = mesh.vertex_corners
    expected = np.empty((mesh.n_vertices, 3))
    launch(_vertex_normals, indptr, corners, mesh.face_indices, mesh.corner_next, mesh.corner_prev, mesh.corner_face,
           mesh.vertices, MAX, np.zeros((0, 3)), expected)
    assert np.array_equal(mesh.corner_pass.max_normals, expected, equal_nan=True)
    assert not mesh.corner_pass.max_normals.flags.writeable


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_report_edge_counts_equal_the_edge_table(mesh):
    from curv.core.features import SHARP_DEGREES

    rep = mesh.report()
    two = mesh.edge_face_count == 2
    assert rep.edges == mesh.edges.shape[0]
    assert rep.border_edges == int(mesh.border_edges.sum())
    assert rep.nonmanifold_edges == int(mesh.nonmanifold_edges.sum())
    assert rep.inconsistent_edges == int(mesh.inconsistent_edges.sum())
    assert rep.sharp_edges == int((mesh.dihedral_angles[two] > SHARP_DEGREES).sum())


@pytest.mark.parametrize("seed", range(30))
def test_duplicate_vertices_are_the_later_copies_of_a_position(seed):
    mesh = _grid_soup(seed)
    v = mesh.vertices
    same = np.all(v[:, None, :] == v[None, :, :], axis=2)  # -0.0 == 0.0, as positions
    expected = np.tril(same, k=-1).any(axis=1)  # equal to a vertex with a lower index
    assert np.array_equal(mesh.duplicate_vertices, expected)
    assert mesh.report().duplicate_vertices == int(expected.sum())


@pytest.mark.parametrize("mesh", MESHES + [_grid_soup(s) for s in range(10)])
def test_components_match_scipy(mesh):
    count, labels = mesh.components
    expected_count, expected = sp.csgraph.connected_components(mesh.adjacency, directed=False)
    assert count == expected_count
    assert np.array_equal(labels, expected)


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_corner_links_walk_each_face_in_a_cycle(mesh):
    h = np.arange(mesh.face_indices.size)
    assert np.array_equal(mesh.corner_face[mesh.corner_next], mesh.corner_face)
    assert np.array_equal(mesh.corner_prev[mesh.corner_next], h)
    step = mesh.corner_next - h  # +1 inside a face, back to its first corner at its last
    last = mesh.face_offsets[1:] - 1
    assert np.all(step[np.setdiff1d(h, last)] == 1)
    assert np.array_equal(mesh.corner_next[last], mesh.face_offsets[:-1])


def test_dihedral_angles_kernel_matches_numpy():
    mesh = MESHES[-1]
    faces = mesh.edge_faces
    n0, n1 = mesh.face_normals[faces[:, 0]], mesh.face_normals[faces[:, 1]]
    expected = np.degrees(np.arctan2(np.linalg.norm(np.cross(n0, n1), axis=1), np.einsum("ij,ij->i", n0, n1)))
    assert np.allclose(mesh.dihedral_angles, expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("mesh", MESHES + [_grid_soup(s) for s in range(10)])
def test_flags_from_the_fans_alone_are_the_corner_pass_flags(mesh):
    # a fresh mesh asked only for its flags (meyer) skips the neighbours and normals
    fresh = curv.Mesh(mesh.vertices, mesh.faces if not mesh.is_triangular else mesh.triangles)
    alone = (fresh.nonmanifold_vertices, fresh.border_vertices, fresh.inconsistent_vertices)
    assert "corner_pass" not in fresh.__dict__
    walked = fresh.corner_pass
    for got, want in zip(alone, (walked.nonmanifold, walked.border, walked.inconsistent)):
        assert np.array_equal(got, want)


@pytest.mark.parametrize("mesh", MESHES + [_grid_soup(s) for s in range(10)])
def test_triangle_corners_step_by_arithmetic(mesh):
    steps = mesh.corner_steps
    if not mesh.is_triangular:
        assert steps[0] is mesh.corner_next and steps[1] is mesh.corner_prev
        return
    assert steps[0] is None and steps[1] is None
    c = np.arange(mesh.face_indices.size)
    nxt = np.array([connectivity.next_corner.py_func(int(k), steps[0]) for k in c])
    prv = np.array([connectivity.prev_corner.py_func(int(k), steps[1]) for k in c])
    assert np.array_equal(nxt, mesh.corner_next) and np.array_equal(prv, mesh.corner_prev)


@pytest.mark.parametrize("h, n", [(0, 4), (7, 60), (200_000, 3), (300_000, 70_000)])
def test_grouping_by_vertex_is_a_stable_sort(h, n):
    keys = np.random.default_rng(h).integers(0, n, h)
    indptr, items = connectivity.group_corners(keys, n)
    assert np.array_equal(items, np.argsort(keys, kind="stable"))
    assert np.array_equal(indptr, np.concatenate([[0], np.cumsum(np.bincount(keys, minlength=n))]))


def _hinges(degrees: np.ndarray) -> curv.Mesh:
    """One pair of triangles per angle, sharing an edge along x, their normals ``degrees`` apart."""
    v, f = [], []
    for i, angle in enumerate(np.radians(degrees)):
        o = 3.0 * i
        v += [[o, 0, 0], [o + 1, 0, 0], [o + 0.5, 1, 0], [o + 0.5, -np.cos(angle), np.sin(angle)]]
        f += [[4 * i, 4 * i + 1, 4 * i + 2], [4 * i + 1, 4 * i, 4 * i + 3]]
    return curv.Mesh(np.array(v), np.array(f))


def test_edge_counts_sharp_near_the_threshold_and_beyond_a_right_angle():
    # the report's edge walk clears most edges by a test without atan2: its count must be what the
    # angles say, at the threshold (within rounding of it) and where the normals point apart (> 90 degrees)
    from curv.core.features import SHARP_DEGREES

    sweep = SHARP_DEGREES + np.concatenate([np.linspace(-10, 10, 81), [-1e-9, -1e-12, 0, 1e-12, 1e-9],
                                            np.linspace(50, 150, 21)])
    mesh = _hinges(sweep)
    angles = mesh.dihedral_angles[mesh.edge_face_count == 2]
    assert np.allclose(np.sort(angles), np.sort(sweep), atol=1e-6)
    indptr, corners = mesh.vertex_corners
    for threshold in (SHARP_DEGREES, 0.5 * SHARP_DEGREES, 100.0):
        counts = connectivity.edge_counts(indptr, corners, mesh.face_indices, *mesh.corner_steps, None,
                                          mesh.face_vector_areas, mesh.face_areas, mesh.degenerate_faces, threshold)
        assert counts["sharp"] == int((angles > threshold).sum())
