"""Point clouds of other libraries go in as clouds (issue 36, item 4): a vertex-only pyvista PolyData,
a trimesh PointCloud, an (n, 3) array; what needs faces says so in words about clouds."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import curv
from curv.convert import as_input, as_mesh
from curv.surfaces import Sphere, sample_points


@pytest.fixture(scope="module")
def cloud():
    """2000 uniform random points of a sphere of radius 2, no normals."""
    return sample_points(Sphere(2.0), 2000, sampling="uniform", rng=3).cloud


@pytest.fixture(scope="module")
def reference(cloud):
    return curv.estimate(curv.PointCloud(cloud.points), "qs", 2)


def _same(result, reference) -> None:
    np.testing.assert_array_equal(result.valid, reference.valid)
    np.testing.assert_array_equal(result.reason, reference.reason)
    np.testing.assert_allclose(result.k1, reference.k1, equal_nan=True)
    np.testing.assert_allclose(result.k2, reference.k2, equal_nan=True)


def test_an_array_of_points_is_estimated_as_a_cloud(cloud, reference):
    _same(curv.estimate(cloud.points, "qs", 2), reference)
    _same(curv.estimate(cloud.points.tolist(), "qs", 2), reference)


def test_a_trimesh_point_cloud_is_estimated_as_a_cloud(cloud, reference):
    _same(curv.estimate(trimesh.PointCloud(cloud.points), "qs", 2), reference)


def test_a_pyvista_polydata_of_points_is_estimated_as_a_cloud(cloud, reference):
    pv = pytest.importorskip("pyvista")
    _same(curv.estimate(pv.PolyData(cloud.points), "qs", 2), reference)
    # its active normals are the cloud's normals, as a file's would be
    normals = cloud.points / np.linalg.norm(cloud.points, axis=1, keepdims=True)
    data = pv.PolyData(cloud.points)
    data.point_data["Normals"] = normals
    data.point_data.active_normals_name = "Normals"
    converted = as_input(data)
    assert isinstance(converted, curv.PointCloud)
    np.testing.assert_allclose(converted.normals, normals)
    res = curv.estimate(data, "qs", 2)
    assert res.info["normals"] == "file"


def test_a_meshio_mesh_of_vertex_cells_is_a_cloud(cloud):
    import meshio

    points = meshio.Mesh(cloud.points, [("vertex", np.arange(len(cloud.points))[:, None])])
    assert isinstance(as_input(points), curv.PointCloud)
    assert isinstance(as_input(meshio.Mesh(cloud.points, [])), curv.PointCloud)


def test_meshes_stay_meshes_and_the_defaults_follow_the_kind(cloud):
    tm = trimesh.creation.icosphere(subdivisions=2)
    assert isinstance(as_input(tm), curv.Mesh)
    assert curv.estimate(tm).method == "mru"
    assert curv.estimate(cloud.points).method == "jet"


def test_what_needs_faces_says_it_got_a_cloud(cloud):
    for obj in (cloud.points, trimesh.PointCloud(cloud.points), curv.PointCloud(cloud.points)):
        with pytest.raises(curv.MeshError, match=r"needs a mesh's faces; got a point cloud \(\w+ of 2,000 points\)"):
            as_mesh(obj)
    with pytest.raises(curv.MeshError, match="estimator 'csm' needs a mesh's faces"):
        curv.estimate(trimesh.PointCloud(cloud.points), "csm")


def test_what_is_neither_is_refused_naming_every_kind():
    for bad in ("a file name", object(), np.zeros((4, 2)), [[0, 0], [1, 1]]):
        with pytest.raises(curv.MeshError) as info:
            as_input(bad)
        text = str(info.value)
        assert "(n, 3)" in text
    with pytest.raises(curv.MeshError, match="trimesh.PointCloud, a pyvista.PolyData, a meshio.Mesh"):
        curv.estimate(object())
