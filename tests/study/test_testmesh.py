"""The test meshes of §5.1: vertex counts, achieved irregularity, noise scale, border exclusion."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from curv.study.protocol import NOISE_FRACTION, Task
from curv.study.testmesh import build_test_mesh, evaluated_vertices
from curv.surfaces import hexagon_mesh


@pytest.mark.parametrize("n", [217, 817, 3169, 12481])
def test_regular_hexagon_has_the_papers_vertex_counts(n):
    planar = hexagon_mesh(n)
    assert planar.mesh.n_vertices == n
    s = round((np.sqrt(12 * n - 3) - 3) / 6)  # n = 3 s (s + 1) + 1
    assert planar.mesh.n_faces == 6 * s * s


@pytest.mark.parametrize("density", [217, 817])
@pytest.mark.parametrize("target", [0.0, 14.0, 25.0])
def test_measured_irregularity_hits_the_target(density, target):
    for sample in range(2):
        tm = build_test_mesh(Task(3, "trigonometric", density, target, 0.0, sample))
        assert tm.mesh.n_vertices == density
        assert abs(tm.irregularity - target) <= 2.0


def test_task_mesh_is_deterministic_and_paired():
    a = build_test_mesh(Task(1, "quadratic", 817, 14.0, 1.0, 0))
    b = build_test_mesh(Task(1, "quadratic", 817, 14.0, 1.0, 0))
    assert np.array_equal(a.mesh.vertices, b.mesh.vertices)
    clean = build_test_mesh(Task(1, "quadratic", 817, 14.0, 0.0, 0))
    half = build_test_mesh(Task(1, "quadratic", 817, 14.0, 0.5, 0))
    # same surface and mesh: the noise-free one has the same connectivity and evaluated set
    assert np.array_equal(clean.mesh.face_indices, a.mesh.face_indices)
    assert np.array_equal(clean.evaluated, a.evaluated)
    # same noise field, scaled by the level
    np.testing.assert_allclose(half.mesh.vertices - clean.mesh.vertices,
                               0.5 * (a.mesh.vertices - clean.mesh.vertices), atol=1e-12)


@pytest.mark.parametrize("level", [0.33, 1.0])
def test_noise_is_gaussian_with_sigma_a_tenth_of_the_mean_edge(level):
    clean = build_test_mesh(Task(2, "ellipsoid_patch", 3169, 0.0, 0.0, 0))
    noisy = build_test_mesh(Task(2, "ellipsoid_patch", 3169, 0.0, level, 0))
    d = noisy.mesh.vertices - clean.mesh.vertices
    sigma = level * NOISE_FRACTION * clean.mesh.mean_edge_length
    assert noisy.noise_sigma == pytest.approx(sigma)
    # 3 * 3169 draws: the sample std is within a few percent of sigma, per coordinate, mean ~ 0
    np.testing.assert_allclose(d.std(axis=0), sigma, rtol=0.06)
    assert np.all(np.abs(d.mean(axis=0)) < 4 * sigma / np.sqrt(d.shape[0]))
    # the truth stays that of the clean surface
    np.testing.assert_array_equal(noisy.truth.k1, clean.truth.k1)


def test_border_exclusion_on_a_regular_plane_matches_brute_force():
    mesh = hexagon_mesh(817).mesh
    h = mesh.edge_lengths.max()
    ev = evaluated_vertices(mesh)
    border = np.flatnonzero(mesh.border_vertices)
    # regular and planar: R4 is the Euclidean ball of radius 4 h (convex, so the BFS reaches it all)
    dist, _ = cKDTree(mesh.vertices[border]).query(mesh.vertices)
    expected = dist > 4 * h * (1 + 1e-6)
    assert np.array_equal(ev, expected)
    # s = 16 rings: ring 11 is 5 rings (4.33 h) from the border line, ring 12 only 3.46 h,
    # so rings 0..11 are evaluated: 3 * 11 * 12 + 1 vertices
    assert ev.sum() == 3 * 11 * 12 + 1


def test_evaluated_vertices_have_no_border_vertex_in_their_r4_support():
    from tests.supports import neighbourhood_matrix

    tm = build_test_mesh(Task(0, "trigonometric", 817, 25.0, 0.0, 0))
    mesh = tm.sampled.mesh
    support = neighbourhood_matrix(mesh, 4)
    touches = (support @ mesh.border_vertices.astype(np.int64)) > 0
    assert tm.evaluated.any()
    assert not np.any(tm.evaluated & (touches | mesh.border_vertices))
    assert np.all(tm.evaluated | touches | mesh.border_vertices)


def test_kept_meshes_equal_a_fresh_build():
    """The planar mesh and the clean mesh are kept for the tasks that share them: a task built after
    its neighbours equals the same task built from scratch through the surface's own ``mesh``."""
    from curv.study import testmesh
    from curv.study.testmesh import random_surface

    task = Task(2, "quadratic", 217, 25.0, 0.66, 1)
    for noise in (0.0, 1.0):  # fills the caches with this mesh
        build_test_mesh(Task(2, "quadratic", 217, 25.0, noise, 1))
    kept = build_test_mesh(task)
    testmesh._planar_mesh.cache_clear()
    testmesh._clean_mesh.cache_clear()
    clean = random_surface(task.function, task.surface_rng()).mesh(
        task.density, irregularity_deg=task.irregularity, rng=task.mesh_rng())
    assert np.array_equal(kept.evaluated, evaluated_vertices(clean.mesh))
    assert kept.irregularity == clean.irregularity_deg
    fresh = build_test_mesh(task)
    assert np.array_equal(kept.mesh.vertices, fresh.mesh.vertices)
    assert np.array_equal(kept.mesh.face_indices, clean.mesh.face_indices)
    assert np.array_equal(kept.truth.k1, fresh.truth.k1, equal_nan=True)
