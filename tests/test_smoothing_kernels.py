"""The cotan-Laplacian kernels (curv.geometry.smoothing) against the per-triangle sparse definition."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import curv
from curv.geometry.smoothing import _cotan_data, smooth_positions, smooth_values
from tests.meshes import icosphere, torus_grid, tube


def _reference_weights(mesh: curv.Mesh) -> np.ndarray:
    """Dense (n, n): every triangle adds cot(angle at o) / 2 to its edge (i, j) opposite o; clamped at 0."""
    t, v = mesh.triangles, mesh.vertices
    rows, cols, vals = [], [], []
    for c in range(3):
        o, i, j = t[:, c], t[:, (c + 1) % 3], t[:, (c + 2) % 3]
        a, b = v[i] - v[o], v[j] - v[o]
        with np.errstate(invalid="ignore", divide="ignore"):
            cot = np.einsum("ij,ij->i", a, b) / np.linalg.norm(np.cross(a, b), axis=1)
        cot = np.where(np.isfinite(cot), cot, 0.0)
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * cot, 0.5 * cot]
    w = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(mesh.n_vertices,) * 2).toarray()
    return np.maximum(w, 0.0)


def cotan_weights(mesh: curv.Mesh) -> sp.csr_matrix:
    """The smoothing kernel's per-edge weights (:func:`curv.geometry.smoothing._cotan_data`) as an
    (n, n) sparse matrix on :attr:`curv.Mesh.adjacency`'s pattern."""
    mesh.triangles  # raises on polygons
    adjacency = mesh.adjacency
    return sp.csr_matrix((_cotan_data(mesh), adjacency.indices, adjacency.indptr), shape=adjacency.shape)


def _soup() -> curv.Mesh:
    rng = np.random.default_rng(2)
    return curv.Mesh(rng.normal(size=(25, 3)), rng.integers(0, 25, size=(40, 3)))


MESHES = [icosphere(2), torus_grid(16, 9)[0], tube(12, 6), _soup()]
IDS = ["sphere", "torus", "tube", "soup"]


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_cotan_weights_match_the_triangle_definition(mesh):
    w = cotan_weights(mesh)
    assert np.array_equal(w.indptr, mesh.adjacency.indptr) and np.array_equal(w.indices, mesh.adjacency.indices)
    np.testing.assert_allclose(w.toarray(), _reference_weights(mesh), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_one_step_moves_towards_the_weighted_average(mesh):
    w = _reference_weights(mesh)
    total = w.sum(axis=1)
    x = mesh.vertices
    with np.errstate(invalid="ignore", divide="ignore"):
        avg = (w @ x) / total[:, None]
    moves = (total > 0) & ~mesh.border_vertices
    expected = np.where(moves[:, None], x + 0.3 * (avg - x), x)
    np.testing.assert_allclose(smooth_positions(mesh, strength=0.3).vertices, expected, rtol=0, atol=1e-12)


def test_value_smoothing_uses_only_valid_neighbours():
    mesh = icosphere(2)
    rng = np.random.default_rng(1)
    values = rng.normal(size=mesh.n_vertices)
    valid = rng.random(mesh.n_vertices) > 0.3
    w = _reference_weights(mesh) * valid[None, :]
    total = w.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        avg = (w @ np.where(valid, values, 0.0)) / total
    expected = np.where(total > 0, values + 0.5 * (avg - values), values)
    expected[~valid] = np.nan
    out = smooth_values(mesh, values, valid)
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-12)
    # a constant stays constant wherever it is smoothed
    flat = smooth_values(mesh, np.full((mesh.n_vertices, 2), 3.0), valid, iterations=3)
    assert np.allclose(flat[valid], 3.0, rtol=0, atol=1e-12)
