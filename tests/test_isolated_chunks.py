"""Regression guard: chunks of vertices made only of unreferenced vertices, for every estimator.

A mesh file such as airplane.obj lists thousands of vertices no face uses; a chunk of the work may
then hold nothing but them. Every estimator, at every chunk size, must give the same values on the
referenced part as on the mesh without them, and call the unreferenced ones degenerate.
"""

import numpy as np
import pytest

import curv
from curv.core.validity import Reason
from tests.meshes import icosphere

CHUNKS = [1, 256, 2000, None]


@pytest.fixture(scope="module")
def padded():
    sphere = icosphere(3)
    pad = 2500
    rng = np.random.default_rng(7)
    v = np.concatenate([rng.normal(size=(pad, 3)) + 5.0, sphere.vertices, rng.normal(size=(pad, 3)) - 5.0])
    return sphere, curv.Mesh(v, sphere.triangles + pad), pad


@pytest.mark.parametrize("method", list(curv.ESTIMATORS))
@pytest.mark.parametrize("chunk", CHUNKS)
def test_unreferenced_vertices_filling_whole_chunks(padded, method, chunk):
    sphere, mesh, pad = padded
    spec = curv.ESTIMATORS[method]
    k = 2 if 2 in spec.ranges else spec.ranges[0]
    alone = curv.estimate(sphere, method, k)
    res = curv.estimate(mesh, method, k, block_size=chunk)
    used = slice(pad, pad + sphere.n_vertices)
    assert np.array_equal(res.valid[used], alone.valid)
    ok = alone.valid
    np.testing.assert_allclose(res.k1[used][ok], alone.k1[ok], rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.k2[used][ok], alone.k2[ok], rtol=0, atol=1e-12)
    isolated = mesh.isolated_vertices
    assert isolated.sum() == 2 * pad
    assert (res.reason[isolated] == Reason.DEGENERATE).all()
    assert np.isnan(res.k1[isolated]).all()
