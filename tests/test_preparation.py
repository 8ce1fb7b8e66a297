"""``curv.prepare``: what an application builds after loading, so that the first estimate finds it done."""

import numpy as np

import curv


def test_prepare_gives_a_meshs_default_normals_and_the_estimate_uses_them():
    mesh = curv.surfaces.make_surface("sphere", n_vertices=642).mesh
    normals = curv.prepare(mesh)
    np.testing.assert_allclose(normals, curv.vertex_normals(mesh), atol=1e-12)
    assert not normals.flags.writeable
    assert curv.prepare(mesh) is normals  # once per mesh
    assert curv.estimate(mesh, "mru", 2).normals is normals


def test_prepare_leaves_a_clouds_estimate_as_it_was():
    points = curv.surfaces.sample_points(curv.surfaces.SURFACES["sphere"](), 1500, sampling="uniform").cloud.points
    prepared, fresh = curv.PointCloud(points), curv.PointCloud(points)
    assert curv.prepare(prepared) is None
    a, b = curv.estimate(prepared, "qs", 2), curv.estimate(fresh, "qs", 2)
    np.testing.assert_array_equal(a.k1, b.k1)
    np.testing.assert_array_equal(a.valid, b.valid)
