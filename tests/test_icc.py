"""icc, the interpolated corrected curvature measures, against exact curvature and a plain re-computation."""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest

import curv
from curv.estimators.icc import face_measures, icc_mean_gaussian, iter_icc
from curv.geometry.normals import vertex_normals
from curv.core.ranges import Range, ball_radii
from curv.surfaces import make_surface
from curv.core.validity import Reason
from tests.clipping import triangle_in_ball_area
from tests.meshes import icosphere, torus_exact, torus_grid, tube


def _run(mesh, k=2.0, *, normals=None, chunk=None, from_measures=True):
    normals = vertex_normals(mesh) if normals is None else normals
    gen = iter_icc(mesh, normals, ball_radii(mesh, Range(k=k), uses_normals=False), chunk=chunk,
                   from_measures=from_measures)
    try:
        while True:
            next(gen)
    except StopIteration as stop:
        return stop.value


def _mean_gaussian(mesh, k=2.0, normals=None):
    normals = vertex_normals(mesh) if normals is None else normals
    return icc_mean_gaussian(mesh, normals, ball_radii(mesh, Range(k=k), uses_normals=False))


def test_registered():
    spec = curv.ESTIMATORS["icc"]
    assert spec.ranges == (1, 2, 3, 4)
    assert spec.has_support and spec.triangles_only and spec.closed_ring and not spec.uses_normals
    assert spec.kernels and spec.function is iter_icc
    assert "Lachaud" in spec.reference


@pytest.mark.parametrize("radius", [0.3, 1.0, 4.0])
@pytest.mark.parametrize("k", [1, 2, 4])
def test_sphere_sign_and_scale(radius, k):
    res = curv.estimate(icosphere(4, radius), "icc", k)
    assert res.valid.all()
    # mu1 and mu2 are exact on a sphere whose normals are exact (Max normals on an icosphere)
    np.testing.assert_allclose(res.k1 * radius, 1.0, atol=1e-7)
    np.testing.assert_allclose(res.k2 * radius, 1.0, atol=1e-7)
    mean, gaussian, reason = _mean_gaussian(icosphere(4, radius), k)
    assert (reason == Reason.OK).all()
    np.testing.assert_allclose(mean * radius, 1.0, rtol=1e-12)
    np.testing.assert_allclose(gaussian * radius**2, 1.0, rtol=1e-12)


@pytest.mark.parametrize("k", [1, 2, 4])
def test_anisotropic_measure_converges_on_spheres(k):
    # the eigenvalues of M carry an O(h^2) tilt bias: a refinement step (h / 2) divides it by ~4
    errors = []
    for sub in (3, 4, 5):
        res = _run(icosphere(sub, 2.0), k, from_measures=False)
        assert (res.reason == Reason.OK).all()
        errors.append(np.abs(np.concatenate([res.k1, res.k2]) * 2.0 - 1.0).max())
    assert errors[1] / errors[0] < 0.35 and errors[2] / errors[1] < 0.35, errors
    assert errors[0] < 0.12


@pytest.mark.parametrize("k", [1, 2])
def test_torus_error_shrinks_under_refinement(k):
    errors = []
    for n_major, n_minor in ((60, 24), (120, 48)):
        m, theta, phi = torus_grid(n_major, n_minor)
        res = curv.estimate(m, "icc", k)
        kmin, kmaj = torus_exact(theta, phi)
        assert res.valid.all()
        errors.append(max(np.abs(res.k1 - np.maximum(kmin, kmaj)).max(),
                          np.abs(res.k2 - np.minimum(kmin, kmaj)).max()))
    assert errors[1] / errors[0] < 0.4, errors


def test_torus_signs():
    m, theta, phi = torus_grid(160, 64)
    mean, gaussian, reason = _mean_gaussian(m, 2)
    assert (reason == Reason.OK).all()
    outside, inside = np.cos(phi) > 0.2, np.cos(phi) < -0.2
    assert (gaussian[outside] > 0).all() and (gaussian[inside] < 0).all()
    kmin, kmaj = torus_exact(theta, phi)
    assert (mean > 0).all()  # R = 2, r = 0.75: H > 0 everywhere
    np.testing.assert_allclose(mean, 0.5 * (kmin + kmaj), atol=0.01)
    np.testing.assert_allclose(gaussian, kmin * kmaj, atol=0.02)


def test_cylinder_values_and_directions():
    m = tube(80, 65, radius=1.0, height=4.0)
    res = curv.estimate(m, "icc", 3)
    z = m.vertices[:, 2]
    inner = (z > 1.3) & (z < 2.7)
    assert res.valid[inner].all()
    np.testing.assert_allclose(res.k1[inner], 1.0, atol=0.01)
    np.testing.assert_allclose(res.k2[inner], 0.0, atol=0.01)
    assert (np.abs(res.d2[inner, 2]) > 0.99).all()  # along the axis
    assert (np.abs(res.d1[inner, 2]) < 0.01).all()  # around it
    # a ball that reaches the rims is one-sided: BORDER
    assert (res.reason[m.border_vertices] == Reason.BORDER).all()
    near = (z < 0.05) | (z > 3.95)
    assert not res.valid[near].any()


@pytest.mark.parametrize("name, anisotropic", [("quadratic", True), ("ellipsoid_patch", False),
                                               ("trigonometric", True)])
def test_monge_patches(name, anisotropic):
    s = make_surface(name, n_vertices=3169, seed=5, random_params=True)
    res = curv.estimate(s.mesh, "icc", 2)
    t = s.truth
    ok = res.valid
    assert 0.4 < ok.mean() < 1.0  # the rim of the patch is BORDER
    assert set(np.unique(res.reason[~ok])) <= {Reason.BORDER}
    e = (np.abs(res.k1 - t.k1) + np.abs(res.k2 - t.k2)) / (np.abs(t.k1) + np.abs(t.k2))
    assert np.median(e[ok]) < 0.03
    if not anisotropic:  # this ellipsoid cap is nearly umbilic: no directions to compare
        return
    # principal directions where the curvatures are well apart
    apart = ok & (np.abs(t.k1 - t.k2) > 0.1 * (np.abs(t.k1) + np.abs(t.k2)))
    assert apart.sum() > 100
    assert np.median(np.abs(np.einsum("ij,ij->i", res.d1[apart], t.d1[apart]))) > 0.99


def test_flipped_faces_flip_the_signs():
    m, _, _ = torus_grid(60, 24)
    a = curv.estimate(m, "icc", 2)
    b = curv.estimate(m.flipped(), "icc", 2)
    np.testing.assert_allclose(b.k1, -a.k2, atol=1e-9)
    np.testing.assert_allclose(b.k2, -a.k1, atol=1e-9)
    ha, ka, _ = _mean_gaussian(m, 2)
    hb, kb, _ = _mean_gaussian(m.flipped(), 2, normals=-vertex_normals(m))
    np.testing.assert_allclose(hb, -ha, atol=1e-12)
    np.testing.assert_allclose(kb, ka, atol=1e-12)


def _reference_mean_gaussian(mesh, normals, k, p):
    """H and K at vertex p by plain Python: BFS in the ball, touched faces weighted by their area inside."""
    v = mesh.vertices
    r = k * mesh.longest_edge[p] * (1 + 1e-9)
    adj = mesh.adjacency.tolil().rows
    seen, queue = {p}, deque([p])
    while queue:
        q = queue.popleft()
        for w in adj[q]:
            if w not in seen and np.linalg.norm(v[w] - v[p]) <= r:
                seen.add(w)
                queue.append(w)
    tri = mesh.triangles
    faces = sorted({f for f in range(tri.shape[0]) if seen & set(tri[f].tolist())})
    meas = face_measures(mesh, normals)
    total = np.zeros(3)
    for f in faces:
        a, b, c = v[tri[f]]
        n = np.cross(b - a, c - a)
        area = 0.5 * np.linalg.norm(n)
        inside = triangle_in_ball_area(a, b, c, v[p], r)
        total += min(inside / area, 1.0) * meas[f, :3]
    return 0.5 * total[1] / total[0], total[2] / total[0]


def test_matches_a_plain_recomputation_on_an_irregular_noisy_patch():
    s = make_surface("trigonometric", n_vertices=817, irregularity=25, noise=0.1, seed=2, random_params=True)
    m = s.mesh
    normals = vertex_normals(m)
    for k in (1.0, 2.5):
        mean, gaussian, reason = icc_mean_gaussian(m, normals, ball_radii(m, Range(k=k), uses_normals=False))
        ok = np.flatnonzero(reason == Reason.OK)
        for p in ok[:: max(1, ok.size // 12)]:
            h, kk = _reference_mean_gaussian(m, normals, k, p)
            assert mean[p] == pytest.approx(h, rel=1e-9, abs=1e-12)
            assert gaussian[p] == pytest.approx(kk, rel=1e-9, abs=1e-12)


def test_chunks_do_not_change_the_result():
    m, _, _ = torus_grid(40, 16)
    ref = _run(m, 2.5)
    for chunk in (1, 13, 500):
        got = _run(m, 2.5, chunk=chunk)
        np.testing.assert_array_equal(got.k1, ref.k1)
        np.testing.assert_array_equal(got.d1, ref.d1)
        np.testing.assert_array_equal(got.reason, ref.reason)


def test_a_missing_normal_in_the_ball_makes_the_centre_degenerate():
    m = icosphere(3)
    normals = vertex_normals(m)
    normals[0] = np.nan
    res = _run(m, 1.0, normals=normals)
    ring = m.adjacency[0].indices
    assert res.reason[0] == Reason.DEGENERATE
    assert (res.reason[ring] == Reason.DEGENERATE).all()
    far = np.linalg.norm(m.vertices - m.vertices[0], axis=1) > 0.8
    assert (res.reason[far] == Reason.OK).all()


def test_polygons_are_refused():
    m, _, _ = torus_grid(20, 8, quads=True)
    with pytest.raises(curv.MeshError, match="needs a triangle mesh"):
        curv.estimate(m, "icc", 2)


def test_principal_curvatures_from_the_anisotropic_measure_as_an_option():
    m, theta, phi = torus_grid(120, 48)
    kmin, kmaj = torus_exact(theta, phi)
    default = curv.estimate(m, "icc", 4)
    aniso = curv.estimate(m, "icc", 4, from_measures=False)
    assert aniso.valid.all()
    # the same directions; M's eigenvalues carry the tilt bias of a large ball (tube curvature low)
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", aniso.d1, default.d1)), 1.0, atol=1e-9)
    err_default = np.abs(default.k1 - np.maximum(kmin, kmaj)).max()
    err_aniso = np.abs(aniso.k1 - np.maximum(kmin, kmaj)).max()
    assert err_default < 0.5 * err_aniso
    assert (aniso.k1 < np.maximum(kmin, kmaj)).mean() > 0.9
    with pytest.raises(curv.EstimatorError, match="from_measures"):
        curv.estimate(m, "icc", 4, from_measures="yes")


@pytest.mark.parametrize("k", [1.0, 2.0, 4.0])
def test_star_sums_equal_the_face_by_face_walk(k, monkeypatch):
    # clean supports take the per-vertex thirds of the face measures and clip only the faces leaving
    # the ball; the walk over every face (kept for supports that are not clean) must agree
    from curv.estimators import icc

    rng = np.random.default_rng(5)
    mesh = torus_grid(40, 24)[0]
    mesh = curv.Mesh(mesh.vertices + rng.normal(scale=0.01, size=mesh.vertices.shape), mesh.triangles)
    normals = vertex_normals(mesh)
    fast_h, fast_k, fast_reason = icc_mean_gaussian(mesh, normals, ball_radii(mesh, Range(k=k), uses_normals=False))
    real = icc.star_measures

    def unclean(*args, **kwargs):
        star, clean = real(*args, **kwargs)
        return star, np.zeros_like(clean)

    monkeypatch.setattr(icc, "star_measures", unclean)
    walk_h, walk_k, walk_reason = icc_mean_gaussian(mesh, normals, ball_radii(mesh, Range(k=k), uses_normals=False))
    np.testing.assert_array_equal(fast_reason, walk_reason)
    np.testing.assert_allclose(fast_h, walk_h, rtol=0, atol=1e-12 * np.abs(walk_h).max())
    np.testing.assert_allclose(fast_k, walk_k, rtol=0, atol=1e-12 * np.abs(walk_k).max())
