"""Vertex normals from local jet fits (curv.fitted_normals) against exact normals."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import curv
from curv.metrics import relative_error
from curv.fitted_normals import fitted_normals
from curv.geometry.normals import vertex_normals
from curv.study.testmesh import evaluated_vertices
from curv.surfaces import QuadraticPatch
from tests.meshes import icosphere, torus_grid, tube


def angle_deg(a, b):
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0)))


def test_sphere_normals_are_radial_and_converge():
    errors = []
    for sub in (3, 4):
        m = icosphere(sub, 2.0)
        n = fitted_normals(m, range=2, degree=2)
        exact = m.vertices / np.linalg.norm(m.vertices, axis=1, keepdims=True)
        np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
        errors.append(angle_deg(n, exact).max())
    assert errors[0] < 0.1
    assert errors[1] / errors[0] < 0.3, errors


def test_orientation_follows_the_max_normals():
    m = icosphere(3, 1.0)
    for mesh in (m, m.flipped()):
        n = fitted_normals(mesh, range=3, degree=3)
        assert np.all(np.einsum("ij,ij->i", n, vertex_normals(mesh)) > 0.99)


def test_irregular_mesh_fitted_normals_beat_the_max_normals():
    # on an irregular (25 degree) patch the face weighting biases the Max normal; a cubic or
    # quartic jet carries the surface's own tangent plane
    s = QuadraticPatch().mesh(3169, irregularity_deg=25.0, rng=1)
    ev = evaluated_vertices(s.mesh)
    max_err = np.median(angle_deg(vertex_normals(s.mesh)[ev], s.truth.normals[ev]))
    fit = fitted_normals(s.mesh, range=3, degree=4)[ev]
    assert np.isfinite(fit).all()
    fit_err = np.median(angle_deg(fit, s.truth.normals[ev]))
    assert fit_err < 0.1 * max_err, (fit_err, max_err)


def test_noise_is_averaged_out_at_a_larger_range():
    s = QuadraticPatch().mesh(3169)
    ev = evaluated_vertices(s.mesh)
    rng = np.random.default_rng(5)
    noisy = s.mesh.with_vertices(s.mesh.vertices + rng.normal(scale=0.1 * s.mesh.mean_edge_length,
                                                              size=s.mesh.vertices.shape))
    max_err = np.median(angle_deg(vertex_normals(noisy)[ev], s.truth.normals[ev]))
    fit_err = np.median(angle_deg(fitted_normals(noisy, range=4, degree=2)[ev], s.truth.normals[ev]))
    assert fit_err < 0.2 * max_err, (fit_err, max_err)


def test_cylinder_normals_are_radial():
    m = tube(60, 40, radius=1.5)
    n = fitted_normals(m, range=2)
    z = m.vertices[:, 2]
    inner = (z > 1.0) & (z < 3.0)
    radial = m.vertices * [1, 1, 0]
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    assert angle_deg(n[inner], radial[inner]).max() < 0.05


def test_polygon_mesh_and_nan_where_the_fit_is_undefined():
    m, theta, phi = torus_grid(80, 40, quads=True)
    n = fitted_normals(m, range=2, degree=2)
    ring = 2.0 * np.stack([np.cos(theta), np.sin(theta), 0 * theta], axis=1)
    exact = m.vertices - ring  # from the tube's centre circle (R = 2)
    exact /= np.linalg.norm(exact, axis=1, keepdims=True)
    assert np.isfinite(n).all()
    assert angle_deg(n, exact).max() < 0.5
    # a quad R1 support has 5 points: too few for the 6 terms of a quadratic jet
    assert np.isnan(fitted_normals(m, range=1, degree=2)).all()


def test_isolated_vertex_gets_nan():
    m = icosphere(2)
    v = np.concatenate([m.vertices, [[5.0, 5.0, 5.0]]])
    n = fitted_normals(curv.Mesh(v, m.triangles))
    assert np.isnan(n[-1]).all() and np.isfinite(n[:-1]).all()


def test_bad_arguments():
    m = icosphere(1)
    with pytest.raises(curv.EstimatorError):
        fitted_normals(m, range=0.5)
    with pytest.raises(curv.EstimatorError):
        fitted_normals(m, degree=7)


def test_radius_is_a_ball_in_mesh_units():
    m = icosphere(3, 1.0)
    tight = fitted_normals(m, radius=1e-6)
    assert np.isnan(tight).all()  # no neighbour within the ball: no fit
    wide = fitted_normals(m, radius=0.3)
    exact = m.vertices / np.linalg.norm(m.vertices, axis=1, keepdims=True)
    assert angle_deg(wide, exact).max() < 0.1


def test_estimate_with_fitted_normals_improves_mru_on_noise():
    s = QuadraticPatch().mesh(3169)
    ev = evaluated_vertices(s.mesh)
    rng = np.random.default_rng(7)
    noisy = s.mesh.with_vertices(s.mesh.vertices + rng.normal(scale=0.1 * s.mesh.mean_edge_length,
                                                              size=s.mesh.vertices.shape))
    errors = []
    for normals in (None, fitted_normals(noisy, range=4)):
        res = curv.estimate(noisy, "mru", 3, normals=normals)
        e = relative_error(s.truth.k1[ev], s.truth.k2[ev], res.k1[ev], res.k2[ev])
        errors.append(np.nanmedian(e))
    assert errors[1] < 0.5 * errors[0], errors


_SPHERE = icosphere(2)


@settings(max_examples=5, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(scale=st.floats(0.01, 100.0), seed=st.integers(0, 2**31 - 1), degree=st.sampled_from([2, 3, 4]))
def test_property_normals_move_with_the_mesh(scale, seed, degree):
    rng = np.random.default_rng(seed)
    v = _SPHERE.vertices * rng.uniform(0.6, 1.8, 3) + rng.normal(scale=0.02, size=_SPHERE.vertices.shape)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    base = fitted_normals(curv.Mesh(v, _SPHERE.triangles), range=3, degree=degree)
    moved = fitted_normals(curv.Mesh(scale * v @ q.T + rng.normal(size=3), _SPHERE.triangles), range=3, degree=degree)
    ok = np.isfinite(base).all(axis=1)
    assert ok.mean() > 0.9
    np.testing.assert_array_equal(np.isfinite(moved).all(axis=1), ok)
    np.testing.assert_allclose(moved[ok], base[ok] @ q.T, atol=1e-7)


def _bunny():
    """pymeshlab's sample bunny (a real scan nobody here made), else a noisy sphere made here."""
    try:
        import pymeshlab
        from pathlib import Path

        path = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "bunny.obj"
        if path.is_file():
            return curv.load(path)
    except ImportError:
        pass
    m = icosphere(4, 1.0)
    return m.with_vertices(m.vertices + np.random.default_rng(3).normal(scale=0.01, size=m.vertices.shape))


@pytest.mark.parametrize("range_", [2, 4])
def test_normals_fitted_at_some_vertices_are_the_whole_calls_bit_for_bit(range_):
    """A fit reads only its own vertex's support: the normals asked for equal the whole call's exactly,
    the others are NaN (the advisor's check fits only where its calls read)."""
    mesh = _bunny()
    every = fitted_normals(mesh, range=range_)
    asked = np.random.default_rng(0).choice(mesh.n_vertices, mesh.n_vertices // 3, replace=False)
    some = fitted_normals(mesh, range=range_, vertices=asked)
    assert np.isfinite(every[asked]).all(axis=1).mean() > 0.99
    np.testing.assert_array_equal(some[asked], every[asked])
    others = np.ones(mesh.n_vertices, bool)
    others[asked] = False
    assert np.isnan(some[others]).all()
    with pytest.raises(curv.CurvError, match="vertex indices"):
        fitted_normals(mesh, vertices=[mesh.n_vertices])
