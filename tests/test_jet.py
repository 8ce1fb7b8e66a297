"""The osculating jet (``jet``) against exact curvature: spheres, cylinders, tori, Monge patches."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import curv
from curv.estimators.jet import DEFAULT_DEGREE, iter_jet, unknowns
from curv.geometry.normals import vertex_normals
from curv.core.ranges import Range, ball_radii
from curv.study.testmesh import evaluated_vertices
from curv.surfaces import QuadraticPatch, TrigonometricPatch
from tests.meshes import hex_plane, icosphere, torus_exact, torus_grid, tube


def jet(mesh, k, degree, normals=None):
    """The raw jet result (k1 >= k2, reasons) at range k with any degree."""
    normals = vertex_normals(mesh) if normals is None else normals
    gen = iter_jet(mesh, normals, ball_radii(mesh, Range(k=float(k)), uses_normals=False), degree=degree)
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


def patch_error(surface, n_vertices, k, degree):
    """Largest e_abs / curvature scale over the evaluated vertices of a regular hexagon patch."""
    s = surface.mesh(n_vertices)
    ev = evaluated_vertices(s.mesh)
    scale = np.abs(s.truth.k1[ev]).max() + np.abs(s.truth.k2[ev]).max()
    if degree == "qs":
        res = curv.estimate(s.mesh, "qs", k)
        k1, k2, ok = res.k1, res.k2, res.valid
    else:
        raw = jet(s.mesh, k, degree)
        k1, k2, ok = raw.k1, raw.k2, raw.reason == curv.Reason.OK
    assert ok[ev].all()
    return np.max(np.abs(k1[ev] - s.truth.k1[ev]) + np.abs(k2[ev] - s.truth.k2[ev])) / scale


@pytest.mark.parametrize("radius", [0.5, 1.0, 3.0])
@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_sphere_sign_and_scale_default_degree(radius, k):
    res = curv.estimate(icosphere(4, radius), "jet", k)
    assert res.valid.all()
    assert np.all(res.k1 >= res.k2)
    np.testing.assert_allclose(res.k1 * radius, 1.0, rtol=0.04)
    np.testing.assert_allclose(res.k2 * radius, 1.0, rtol=0.04)


@pytest.mark.parametrize("degree, k, tol", [(3, 2, 0.01), (3, 4, 0.04), (4, 2, 1e-4), (4, 4, 2e-3)])
@pytest.mark.parametrize("radius", [0.5, 3.0])
def test_sphere_higher_degrees(degree, k, tol, radius):
    raw = jet(icosphere(4, radius), k, degree)
    assert np.all(raw.reason == curv.Reason.OK)
    np.testing.assert_allclose(np.concatenate([raw.k1, raw.k2]) * radius, 1.0, atol=tol)


@pytest.mark.parametrize("degree, bound", [(2, 0.35), (4, 0.12)])
def test_sphere_error_shrinks_with_the_order_of_the_jet(degree, bound):
    # R2 on icospheres of 642 and 2562 vertices (edges halve): degree 2 is second order on a
    # sphere (its odd terms vanish by symmetry), degree 4 fourth order
    errors = []
    for sub in (3, 4):
        raw = jet(icosphere(sub, 2.0), 2, degree)
        errors.append(np.max(np.abs(np.concatenate([raw.k1, raw.k2]) * 2.0 - 1.0)))
    assert errors[1] / errors[0] < bound, errors


@pytest.mark.parametrize("surface", [QuadraticPatch(), TrigonometricPatch()], ids=["quadratic", "trigonometric"])
def test_higher_degree_jets_converge_faster_than_qs(surface):
    # R3 on the regular hexagon at 817 and 3169 vertices (edges halve): qs and the degree-2 jet
    # are first order on a general patch, degree 3 second, degree 4 third
    ratio = {d: patch_error(surface, 3169, 3, d) / patch_error(surface, 817, 3, d) for d in ("qs", 3, 4)}
    assert ratio["qs"] > 0.4
    assert ratio[3] < 0.3 and ratio[3] < 0.6 * ratio["qs"], ratio
    assert ratio[4] < 0.2 and ratio[4] < 0.7 * ratio[3], ratio


def test_monge_patch_values():
    s = QuadraticPatch().mesh(3169)
    ev = evaluated_vertices(s.mesh)
    res = curv.estimate(s.mesh, "jet", 2)
    assert res.valid[ev].all()
    np.testing.assert_allclose(res.k1[ev], s.truth.k1[ev], atol=0.04)
    np.testing.assert_allclose(res.k2[ev], s.truth.k2[ev], atol=0.04)
    raw = jet(s.mesh, 3, 4)
    np.testing.assert_allclose(raw.k1[ev], s.truth.k1[ev], atol=1e-3)
    np.testing.assert_allclose(raw.k2[ev], s.truth.k2[ev], atol=1e-3)
    # directions: d1 along the exact d1 (up to sign) where the curvatures are well apart
    apart = ev & (s.truth.k1 - s.truth.k2 > 0.2)
    cos = np.abs(np.einsum("ij,ij->i", res.d1[apart], s.truth.d1[apart]))
    assert cos.min() > 0.99


def test_plane_is_flat_and_exact():
    m = hex_plane(12)
    ev = evaluated_vertices(m)
    for degree in (2, 3, 4):
        raw = jet(m, 3, degree)
        assert np.all(raw.reason[ev] == curv.Reason.OK)
        np.testing.assert_allclose(raw.k1[ev], 0.0, atol=1e-9)
        np.testing.assert_allclose(raw.k2[ev], 0.0, atol=1e-9)


@pytest.mark.parametrize("k", [2, 3])
def test_cylinder_values_and_directions(k):
    m = tube(80, 65, radius=1.0, height=4.0)
    res = curv.estimate(m, "jet", k)
    z = m.vertices[:, 2]
    inner = (z > 1.2) & (z < 2.8)
    assert res.valid[inner].all()
    np.testing.assert_allclose(res.k1[inner], 1.0, atol=0.02)
    np.testing.assert_allclose(res.k2[inner], 0.0, atol=0.02)
    d1 = res.d1[inner]
    assert np.all(np.abs(d1[:, 2]) < 0.02)
    radial = m.vertices[inner] * [1, 1, 0]
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    assert np.all(np.abs(np.einsum("ij,ij->i", d1, radial)) < 0.02)
    # d2 runs along the axis
    assert np.all(np.abs(res.d2[inner][:, 2]) > 0.999)


@pytest.mark.parametrize("quads", [False, True], ids=["triangles", "quads"])
def test_torus_signs_and_values(quads):
    m, theta, phi = torus_grid(200, 80, quads=quads)
    res = curv.estimate(m, "jet", 2)
    kmin, kmaj = torus_exact(theta, phi)
    exact = np.sort(np.stack([kmin, kmaj]), axis=0)[::-1]
    assert res.valid.all()
    assert np.all(res.gaussian[np.cos(phi) > 0.3] > 0)
    assert np.all(res.gaussian[np.cos(phi) < -0.3] < 0)
    # degree 2 keeps a first-order bias where the ball cuts the grid unevenly (a few rows of phi)
    np.testing.assert_allclose(res.k1, exact[0], atol=0.03)
    np.testing.assert_allclose(res.k2, exact[1], atol=0.03)
    raw = jet(m, 3, 4)
    assert np.all(raw.reason == curv.Reason.OK)
    np.testing.assert_allclose(raw.k1, exact[0], atol=3e-3)
    np.testing.assert_allclose(raw.k2, exact[1], atol=3e-3)


def test_reversed_faces_flip_the_sign():
    m = icosphere(3, 2.0)
    a = curv.estimate(m, "jet", 2)
    b = curv.estimate(m.flipped(), "jet", 2)
    np.testing.assert_allclose(b.k1, -a.k2, atol=1e-9)
    np.testing.assert_allclose(b.k2, -a.k1, atol=1e-9)
    np.testing.assert_allclose(b.normals, -a.normals, atol=1e-12)


def test_directions_orthonormal_and_tangent_to_the_reported_normals():
    m, _, _ = torus_grid(60, 24)
    m = m.with_vertices(m.vertices + np.random.default_rng(3).normal(scale=0.01, size=m.vertices.shape))
    res = curv.estimate(m, "jet", 2)
    v = res.valid
    assert v.all()
    for d in (res.d1, res.d2):
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-9)
        assert np.all(np.abs(np.einsum("ij,ij->i", d, res.normals)) < 1e-9)
    assert np.all(np.abs(np.einsum("ij,ij->i", res.d1, res.d2)) < 1e-9)


@pytest.mark.parametrize("degree", [2, 3, 4])
def test_too_few_points_is_invalid_with_its_reason(degree):
    # a quad grid's R1 support is the centre and its 4 edge neighbours: 5 points
    m, _, _ = torus_grid(40, 20, quads=True)
    raw = jet(m, 1, degree)
    assert unknowns(degree) > 5
    assert np.all(raw.reason == curv.Reason.TOO_FEW_NEIGHBOURS)
    assert np.isnan(raw.k1).all() and np.isnan(raw.d1).all()
    res = curv.estimate(m, "jet", 1)
    assert not res.valid.any() and np.all(res.reason == curv.Reason.TOO_FEW_NEIGHBOURS)


def test_triangle_one_ring_carries_a_quadratic_but_not_a_cubic():
    raw2, raw3 = jet(icosphere(3), 1, 2), jet(icosphere(3), 1, 3)
    assert np.all(raw2.reason == curv.Reason.OK)  # valence 5 or 6: 6 or 7 points for 6 unknowns
    assert np.all(raw3.reason == curv.Reason.TOO_FEW_NEIGHBOURS)


def test_points_on_two_lines_are_singular():
    # a strip of triangles: every support lies on two parallel lines, so the across-strip
    # quadratic term cannot be told from the constant and linear ones
    n = 30
    top = np.stack([np.arange(n), np.zeros(n), np.zeros(n)], axis=1)
    bottom = np.stack([np.arange(n) + 0.5, np.full(n, 0.9), np.zeros(n)], axis=1)
    faces = [[i, i + 1, n + i] for i in range(n - 1)] + [[i + 1, n + i + 1, n + i] for i in range(n - 1)]
    m = curv.Mesh(np.concatenate([top, bottom]), np.array(faces))
    raw = jet(m, 4, 2)
    assert np.all(raw.reason == curv.Reason.SINGULAR)
    assert np.isnan(raw.k1).all()


def test_unknown_degree_is_refused():
    m = icosphere(1)
    with pytest.raises(curv.EstimatorError, match="degree"):
        jet(m, 2, 5)
    with pytest.raises(curv.EstimatorError, match="degree"):
        jet(m, 2, True)


def test_default_degree_is_what_estimate_uses_and_degree_passes_through():
    m = icosphere(3, 1.5)
    for degree, options in ((DEFAULT_DEGREE, {}), (4, {"degree": 4})):
        res = curv.estimate(m, "jet", 3, **options)
        raw = jet(m, 3, degree)
        np.testing.assert_allclose(res.k1, raw.k1, rtol=1e-12)
        np.testing.assert_allclose(res.k2, raw.k2, rtol=1e-12)
    assert res.info["degree"] == 4
    with pytest.raises(curv.EstimatorError, match="degree must be one of 2, 3, 4"):
        curv.estimate(m, "jet", 3, degree=5)


def test_the_fit_does_not_depend_on_the_given_normals_beyond_their_side():
    # the given normals orient the fit; tilting them changes neither k1 nor k2
    m = icosphere(3, 1.0)
    tilted = vertex_normals(m) + np.random.default_rng(0).normal(scale=0.3, size=(m.n_vertices, 3))
    tilted /= np.linalg.norm(tilted, axis=1, keepdims=True)
    a, b = jet(m, 2, 3), jet(m, 2, 3, normals=tilted)
    np.testing.assert_allclose(a.k1, b.k1, rtol=1e-9)
    np.testing.assert_allclose(a.k2, b.k2, rtol=1e-9)


def test_chunk_size_does_not_change_the_result():
    m = icosphere(3, 1.0)
    a = curv.estimate(m, "jet", 2, block_size=257)
    b = curv.estimate(m, "jet", 2)
    np.testing.assert_array_equal(a.k1, b.k1)
    np.testing.assert_array_equal(a.d1, b.d1)


_SPHERE = icosphere(2)


@settings(max_examples=5, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(scale=st.floats(0.01, 100.0), seed=st.integers(0, 2**31 - 1), degree=st.sampled_from([2, 3, 4]))
def test_property_scale_and_rigid_motion(scale, seed, degree):
    rng = np.random.default_rng(seed)
    axes = rng.uniform(0.6, 1.8, 3)
    v = _SPHERE.vertices * axes + rng.normal(scale=0.02, size=_SPHERE.vertices.shape)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    base = jet(curv.Mesh(v, _SPHERE.triangles), 3, degree)
    moved = jet(curv.Mesh(scale * v @ q.T + rng.normal(size=3), _SPHERE.triangles), 3, degree)
    ok = base.reason == curv.Reason.OK
    np.testing.assert_array_equal(moved.reason, base.reason)
    tol = 1e-6 * np.abs(base.k1[ok]).max()
    np.testing.assert_allclose(moved.k1[ok] * scale, base.k1[ok], rtol=1e-6, atol=tol)
    np.testing.assert_allclose(moved.k2[ok] * scale, base.k2[ok], rtol=1e-6, atol=tol)
    # directions rotate with the mesh (up to sign), where the two curvatures are apart
    apart = ok & (base.k1 - base.k2 > 1e-3 * np.abs(base.k1).max())
    cos = np.abs(np.einsum("ij,ij->i", moved.d1[apart], base.d1[apart] @ q.T))
    np.testing.assert_allclose(cos, 1.0, atol=1e-5)
