"""The adjacency and the longest 1-ring edge come from the corners, without the edge table: they
must equal what the edge table gives, on meshes with polygons, repeated indices and fins."""

import numpy as np
import pytest

import curv
from curv.core import connectivity
from tests.meshes import icosphere, torus_grid


def _from_edge_table(mesh):
    indptr, neighbours, _ = connectivity.vertex_incidence(mesh.edges, mesh.n_vertices)
    longest = np.zeros(mesh.n_vertices)
    for end in (0, 1):
        np.maximum.at(longest, mesh.edges[:, end], mesh.edge_lengths)
    return indptr, neighbours, longest


def _soups(count=200, seed=0):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        nv = int(rng.integers(6, 30))
        faces = [list(rng.choice(nv, size=int(rng.integers(3, 6)), replace=bool(rng.random() < 0.2)))
                 for _ in range(int(rng.integers(1, 30)))]
        try:
            yield curv.Mesh(rng.normal(size=(nv, 3)), faces)
        except curv.MeshError:  # e.g. a face that repeats all its indices
            continue


@pytest.mark.parametrize("mesh", [icosphere(2), torus_grid(12, 8, quads=True)[0], *_soups()])
def test_corner_neighbours_equal_the_edge_table(mesh):
    indptr, neighbours, longest = _from_edge_table(mesh)
    assert np.array_equal(mesh.adjacency.indptr.astype(np.int64), indptr)
    assert np.array_equal(mesh.adjacency.indices.astype(np.int64), neighbours)
    assert np.array_equal(mesh.longest_edge, longest)
    assert np.array_equal(mesh.valence, np.diff(indptr))


def test_a_fresh_fit_never_builds_the_edge_table():
    mesh = icosphere(3)
    curv.estimate(mesh, "qs", 2)
    assert "_edge_data" not in mesh.__dict__
