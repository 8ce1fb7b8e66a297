"""How the work is cut must not show in the results: chunks of vertices per kernel call, threads.

The 1-ring kernels (normals, meyer, ru) compute every vertex from its own corners only, so their
results are identical to the bit whatever the chunks and the thread count; the support-based
estimators are checked to rounding. A mesh whose unreferenced vertices fill whole chunks guards
against chunks without a single corner.
"""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.estimators.meyer import iter_meyer
from curv.estimators.rusinkiewicz import iter_ru
from curv.geometry.normals import unusable_normal_vertices, vertex_normals
from curv.core.validity import Reason
from tests.meshes import icosphere, torus_grid

CHUNKS = [1, 7, 256, 1000, 3000, None]
"""Vertices per kernel call (None: the adaptive default)."""


def _run(generator):
    while True:
        try:
            next(generator)
        except StopIteration as stop:
            return stop.value


def _mixed_mesh() -> curv.Mesh:
    """Quads and triangles, plus an isolated vertex at the end (a vertex with no corner)."""
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0.3], [2, 1, 0.2], [5, 5, 5]], float)
    faces = [[0, 1, 2, 3], [1, 4, 5], [1, 5, 2]]
    return curv.Mesh(v, faces)


def _assert_same(a, b):
    for name in ("k1", "k2", "d1", "d2", "reason"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=name != "reason"), name


@pytest.mark.parametrize("mesh", [icosphere(2), _mixed_mesh()], ids=["sphere", "mixed"])
def test_vertex_corners_group_every_corner_once_by_vertex(mesh):
    indptr, corners = mesh.vertex_corners
    assert indptr[0] == 0 and indptr[-1] == mesh.face_indices.size
    assert np.array_equal(np.sort(corners), np.arange(mesh.face_indices.size))
    owner = np.repeat(np.arange(mesh.n_vertices), np.diff(indptr))
    assert np.array_equal(mesh.face_indices[corners], owner)


@pytest.mark.parametrize("chunk", CHUNKS)
def test_meyer_and_ru_do_not_depend_on_the_chunks_or_threads(chunk, monkeypatch):
    mesh, _, _ = torus_grid(40, 18)
    normals = vertex_normals(mesh)
    reference = {"meyer": _run(iter_meyer(mesh, None, None)), "ru": _run(iter_ru(mesh, normals, None))}
    monkeypatch.setenv("CURV_THREADS", "1")
    meyer = _run(iter_meyer(mesh, None, None, chunk=chunk))
    _assert_same(reference["meyer"], meyer)
    assert np.array_equal(reference["meyer"].normals, meyer.normals)
    _assert_same(reference["ru"], _run(iter_ru(mesh, normals, None, chunk=chunk)))


@pytest.mark.parametrize("weighting", ["max", "area", "angle"])
def test_normals_do_not_depend_on_the_threads(weighting, monkeypatch):
    mesh, _, _ = torus_grid(40, 18)
    reference = vertex_normals(mesh, weighting=weighting)
    monkeypatch.setenv("CURV_THREADS", "1")
    assert np.array_equal(vertex_normals(mesh, weighting=weighting), reference)


@pytest.mark.parametrize("method,k", [("nc", 3), ("qs", 2), ("an", 3), ("mru", 2), ("csm", 2)])
def test_estimates_do_not_depend_on_how_the_work_is_cut(method, k, monkeypatch):
    mesh, _, _ = torus_grid(40, 18)
    reference = curv.estimate(mesh, method, k)
    monkeypatch.setenv("CURV_THREADS", "1")
    cut = curv.estimate(mesh, method, k, block_size=37)
    assert np.array_equal(reference.valid, cut.valid)
    ok = reference.valid
    assert np.allclose(reference.k1[ok], cut.k1[ok], rtol=0, atol=1e-10)
    assert np.allclose(reference.k2[ok], cut.k2[ok], rtol=0, atol=1e-10)


def _padded_sphere(pad: int = 3000):
    """An icosphere with ``pad`` unreferenced vertices before it and ``pad`` after it."""
    sphere = icosphere(3)
    rng = np.random.default_rng(0)
    v = np.concatenate([rng.normal(size=(pad, 3)) + 5.0, sphere.vertices, rng.normal(size=(pad, 3)) - 5.0])
    return sphere, curv.Mesh(v, sphere.triangles + pad), pad


@pytest.mark.parametrize("chunk", CHUNKS)
def test_isolated_vertices_filling_whole_chunks(chunk):
    sphere, padded, pad = _padded_sphere()
    used = slice(pad, pad + sphere.n_vertices)
    isolated = padded.isolated_vertices
    assert isolated.sum() == 2 * pad and not isolated[used].any()

    normals = vertex_normals(padded)
    assert np.array_equal(normals[used], vertex_normals(sphere))
    assert np.isnan(normals[isolated]).all()

    for method, k in (("meyer", 1), ("ru", 2)):
        alone = curv.estimate(sphere, method, k)
        res = curv.estimate(padded, method, k, block_size=chunk)
        for name in ("k1", "k2", "d1", "d2", "normals", "reason"):
            assert np.array_equal(getattr(res, name)[used], getattr(alone, name), equal_nan=True), (method, name)
        assert alone.valid.all()
        assert not res.valid[isolated].any()
        assert (res.reason[isolated] == Reason.DEGENERATE).all()
        assert np.isnan(res.k1[isolated]).all() and np.isnan(res.normals[isolated]).all()

    # the estimators themselves, before the API's rules, already call them degenerate
    raw = _run(iter_meyer(padded, None, None, chunk=chunk))
    assert (raw.reason[isolated] == Reason.DEGENERATE).all()
    raw = _run(iter_ru(padded, normals, None, chunk=chunk))
    assert (raw.reason[isolated] == Reason.DEGENERATE).all()


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
