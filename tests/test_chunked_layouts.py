"""The work layouts behind the estimators: corners grouped by vertex, segment ids, padded fit groups.

Each layout is checked against the plain computation it replaces, and the estimators built on them
are checked not to depend on how the work is cut (chunk size, block size, thread count).
"""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv import corners as corners_module
from curv.corners import map_vertex_chunks
from curv.estimators._lsq import padded_groups
from curv.neighbourhood import segment_ids
from curv.normals import unusable_normal_vertices, vertex_normals
from tests.meshes import icosphere, torus_grid


def _mixed_mesh() -> curv.Mesh:
    """Quads and triangles, plus an isolated vertex at the end (a vertex with no corner)."""
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0.3], [2, 1, 0.2], [5, 5, 5]], float)
    faces = [[0, 1, 2, 3], [1, 4, 5], [1, 5, 2]]
    return curv.Mesh(v, faces)


@pytest.mark.parametrize("mesh", [icosphere(2), _mixed_mesh()], ids=["sphere", "mixed"])
def test_vertex_corners_group_every_corner_once_by_vertex(mesh):
    indptr, corners = mesh.vertex_corners
    assert indptr[0] == 0 and indptr[-1] == mesh.face_indices.size
    assert np.array_equal(np.sort(corners), np.arange(mesh.face_indices.size))
    owner = np.repeat(np.arange(mesh.n_vertices), np.diff(indptr))
    assert np.array_equal(mesh.face_indices[corners], owner)


@pytest.mark.parametrize("chunk", [1, 3, 64, 100_000])
@pytest.mark.parametrize("workers", [1, 2])
def test_chunks_cover_every_vertex_and_sum_like_bincount(chunk, workers):
    mesh = _mixed_mesh() if chunk < 64 else icosphere(3)
    values = np.random.default_rng(0).normal(size=mesh.face_indices.size)
    summed = np.full(mesh.n_vertices, np.nan)
    touched = np.zeros(mesh.n_vertices, int)

    def work(ch):
        assert np.array_equal(ch.vertex, mesh.face_indices[ch.corners])
        assert np.array_equal(ch.nxt, mesh.face_indices[mesh.corner_next[ch.corners]])
        assert np.array_equal(ch.prv, mesh.face_indices[mesh.corner_prev[ch.corners]])
        assert np.array_equal(ch.expand(np.arange(mesh.n_vertices)), ch.vertex)
        summed[ch.start:ch.stop] = ch.sum(values[ch.corners])
        touched[ch.start:ch.stop] += 1

    map_vertex_chunks(mesh, work, chunk=chunk, workers=workers)
    assert (touched == 1).all()
    expected = np.bincount(mesh.face_indices, weights=values, minlength=mesh.n_vertices)
    assert np.allclose(summed, expected, rtol=0, atol=1e-12)


def test_chunk_errors_reach_the_caller():
    def work(ch):
        if ch.start > 0:
            raise RuntimeError("boom in a worker")

    with pytest.raises(RuntimeError, match="boom in a worker"):
        map_vertex_chunks(icosphere(2), work, chunk=16, workers=2)


@pytest.mark.parametrize("counts", [[3, 0, 2, 0, 0, 1], [0, 0], [5], [0, 4, 0]])
def test_segment_ids_match_repeat_with_empty_segments(counts):
    indptr = np.concatenate([[0], np.cumsum(counts)])
    expected = np.repeat(np.arange(len(counts)), counts)
    assert np.array_equal(segment_ids(indptr), expected)


def test_padded_groups_cover_each_centre_once_with_little_padding():
    counts = np.random.default_rng(1).integers(0, 400, 5000)
    groups = padded_groups(counts, min_group=1)
    rows = np.concatenate([r for r, _ in groups])
    assert np.array_equal(np.sort(rows), np.arange(counts.size))
    for r, width in groups:
        assert (counts[r] <= width).all()
        assert width <= np.maximum(counts[r], 1).min() * 9 / 8 + 1
    assert sum(r.size * w for r, w in groups) <= 1.15 * np.maximum(counts, 1).sum()


def test_small_padded_groups_merge_upwards():
    counts = np.array([1] * 3 + [10] * 300 + [50] * 2)
    groups = padded_groups(counts, min_group=256)
    assert len(groups) == 2
    widths = [w for _, w in groups]
    assert widths == sorted(widths) and widths[-1] >= 50
    assert sum(r.size for r, _ in groups) == counts.size


@pytest.mark.parametrize("method,k", [("meyer", 1), ("ru", 2), ("nc", 3), ("qs", 2), ("an", 3), ("mru", 2),
                                      ("csm", 2)])
def test_estimates_do_not_depend_on_how_the_work_is_cut(method, k, monkeypatch):
    mesh, _, _ = torus_grid(40, 18)
    reference = curv.estimate(mesh, method, k)
    monkeypatch.setenv("CURV_THREADS", "1")
    monkeypatch.setattr(corners_module, "CHUNK_VERTICES", 7)
    # small neighbourhood blocks as well (ignored by the 1-ring estimators)
    cut = curv.estimate(mesh, method, k, block_size=37)
    assert np.array_equal(reference.valid, cut.valid)
    ok = reference.valid
    assert np.allclose(reference.k1[ok], cut.k1[ok], rtol=0, atol=1e-10)
    assert np.allclose(reference.k2[ok], cut.k2[ok], rtol=0, atol=1e-10)


def test_meyer_computes_the_same_normals_as_vertex_normals():
    mesh = icosphere(3)
    # flip one face: its vertices' normals become unusable and must come back NaN
    faces = mesh.triangles.copy()
    faces[5] = faces[5, ::-1]
    broken = curv.Mesh(mesh.vertices, faces)
    result = curv.estimate(broken, "meyer", 1)
    expected = vertex_normals(broken)
    unusable = unusable_normal_vertices(broken)
    assert unusable.any()
    assert np.isnan(result.normals[unusable]).all()
    assert np.array_equal(result.normals[~unusable], expected[~unusable])
    # the same estimate with the normals passed in explicitly
    given = expected.copy()
    given[unusable] = np.nan
    explicit = curv.estimate(broken, "meyer", 1, normals=given)
    assert np.array_equal(explicit.reason, result.reason)
    ok = result.valid
    assert np.allclose(explicit.k1[ok], result.k1[ok], atol=1e-12)
