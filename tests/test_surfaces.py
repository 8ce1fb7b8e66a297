"""Analytic surfaces: exact curvature against hand-derived values and finite differences; meshing."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.surfaces import (
    PAPER_VERTEX_COUNTS, SURFACES, CreasedSurface, Cylinder, Ellipsoid, EllipsoidPatch, MongePatch, QuadraticPatch,
    Saddle, Sphere, Torus, TrigonometricPatch, angle_irregularity, hexagon_grid, hexagon_mesh, make_surface,
)
from curv.surfaces.tessellate import geodesic_sphere, sphere_frequency

SQRT3 = np.sqrt(3.0)


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def rowdot(a, b):
    return np.einsum("ij,ij->i", a, b)


def assert_frames(truth):
    """d1, d2 unit, tangent, orthogonal; normals unit; k1 >= k2."""
    for d in (truth.d1, truth.d2, truth.normals):
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)
    assert np.abs(rowdot(truth.d1, truth.normals)).max() < 1e-12
    assert np.abs(rowdot(truth.d2, truth.normals)).max() < 1e-12
    assert np.abs(rowdot(truth.d1, truth.d2)).max() < 1e-12
    assert np.all(truth.k1 >= truth.k2)
    assert truth.method == "exact" and truth.range is None
    assert truth.valid.all() and not truth.reason.any()


def face_normals_agree(sampled, minimum=0.9):
    """Each face normal points the way of the exact normals at its corners."""
    mesh = sampled.mesh
    exact = unit(sampled.truth.normals[mesh.triangles].sum(axis=1))
    return rowdot(mesh.face_normals, exact).min() > minimum


# ---------------------------------------------------------------------------------- closed surfaces
def test_sphere_exact_and_closed_outward_mesh():
    s = Sphere(2.5).mesh(642)
    v = s.mesh.vertices
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 2.5)
    np.testing.assert_allclose(s.truth.k1, 0.4)
    np.testing.assert_allclose(s.truth.k2, 0.4)
    np.testing.assert_allclose(s.truth.normals, v / 2.5, atol=1e-12)
    assert_frames(s.truth)
    assert s.mesh.n_vertices == 642 and not s.mesh.border_vertices.any()
    assert not s.mesh.nonmanifold_edges.any() and not s.mesh.degenerate_faces.any()
    assert face_normals_agree(s, 0.99)
    assert s.mesh.report().components == 1


def test_geodesic_sphere_counts():
    for f in (1, 2, 5, 16):
        v, faces = geodesic_sphere(f)
        assert v.shape == (10 * f * f + 2, 3) and faces.shape == (20 * f * f, 3)
        assert curv.Mesh(v, faces).report().border_edges == 0
    assert sphere_frequency(2562) == 16 and sphere_frequency(2500) == 16 and sphere_frequency(5) == 1


def test_cylinder_open_tube_circumference_direction():
    s = Cylinder(radius=0.5, height=3.0).mesh(1500)
    v, t = s.mesh.vertices, s.truth
    np.testing.assert_allclose(t.k1, 2.0)
    np.testing.assert_allclose(t.k2, 0.0, atol=1e-12)
    around = unit(np.column_stack([-v[:, 1], v[:, 0], np.zeros(len(v))]))
    np.testing.assert_allclose(np.abs(rowdot(t.d1, around)), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.abs(t.d2[:, 2]), 1.0, atol=1e-12)
    np.testing.assert_allclose(t.normals, unit(v * [1, 1, 0]), atol=1e-12)
    assert_frames(t)
    # the border is exactly the two end circles
    border = s.mesh.border_vertices
    np.testing.assert_allclose(np.abs(v[border, 2]), 1.5)
    assert np.all(np.abs(v[~border, 2]) < 1.5 - 1e-9)
    assert s.mesh.report().border_loops == 2
    assert face_normals_agree(s, 0.99)
    assert abs(s.mesh.n_vertices - 1500) < 100


def test_torus_exact_values_at_known_points():
    R, r = 2.0, 0.5
    torus = Torus(major=R, minor=r)
    points = np.array([[R + r, 0, 0], [-(R - r), 0, 0], [0, R, r], [0, -R, -r]])
    t = torus.exact(points)
    np.testing.assert_allclose(t.k1, [1 / r, 1 / r, 1 / r, 1 / r])
    np.testing.assert_allclose(t.k2, [1 / (R + r), -1 / (R - r), 0, 0], atol=1e-12)
    # the inner equator at x = -(R - r) faces the axis: +x
    np.testing.assert_allclose(t.normals, [[1, 0, 0], [1, 0, 0], [0, 0, 1], [0, 0, -1]], atol=1e-12)
    # on the outer equator the tube circle (k1 = 1/r) runs along z, the big circle along y
    np.testing.assert_allclose(np.abs(t.d1[0]), [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(np.abs(t.d2[0]), [0, 1, 0], atol=1e-12)
    assert_frames(t)


def test_torus_general_formula_and_gaussian_sign():
    R, r = 1.0, 0.4
    torus = Torus(major=R, minor=r)
    rng = np.random.default_rng(5)
    u, v = rng.uniform(0, 2 * np.pi, (2, 200))
    t = torus.exact(torus.point(u, v))
    along = np.cos(v) / (R + r * np.cos(v))
    np.testing.assert_allclose(np.sort([np.full_like(v, 1 / r), along], axis=0)[::-1], [t.k1, t.k2], atol=1e-12)
    outside, inside = np.cos(v) > 0.05, np.cos(v) < -0.05
    assert np.all(t.gaussian[outside] > 0) and np.all(t.gaussian[inside] < 0)


def test_torus_mesh_closed_and_outward():
    s = Torus(major=1.0, minor=0.4).mesh(2000)
    rep = s.mesh.report()
    assert rep.border_edges == 0 and rep.nonmanifold_edges == 0 and rep.degenerate_faces == 0
    assert not s.mesh.border_vertices.any()
    assert face_normals_agree(s, 0.95)
    assert abs(s.mesh.n_vertices - 2000) < 100
    # every vertex lies on the torus
    v = s.mesh.vertices
    np.testing.assert_allclose((np.hypot(v[:, 0], v[:, 1]) - 1.0) ** 2 + v[:, 2] ** 2, 0.16, atol=1e-12)


def test_ellipsoid_exact_axes_and_gaussian_formula():
    a, b, c = 3.0, 2.0, 1.0
    e = Ellipsoid(a, b, c)
    t = e.exact([[a, 0, 0], [0, 0, c]])
    np.testing.assert_allclose(t.k1, [a / c**2, c / b**2])
    np.testing.assert_allclose(t.k2, [a / b**2, c / a**2])
    np.testing.assert_allclose(np.abs(t.d1), [[0, 0, 1], [0, 1, 0]], atol=1e-12)
    s = e.mesh(642)
    v = s.mesh.vertices
    np.testing.assert_allclose(((v / [a, b, c]) ** 2).sum(axis=1), 1.0)
    # K = 1 / (a b c (x²/a⁴ + y²/b⁴ + z²/c⁴))², an independent closed form
    expected_k = 1.0 / (a * b * c * ((v**2 / np.array([a, b, c]) ** 4).sum(axis=1))) ** 2
    np.testing.assert_allclose(s.truth.gaussian, expected_k, rtol=1e-10)
    assert_frames(s.truth)
    assert not s.mesh.border_vertices.any()
    assert face_normals_agree(s, 0.95)


def test_closed_surfaces_reject_bad_parameters():
    with pytest.raises(ValueError, match="minor < major"):
        Torus(major=1.0, minor=1.5)
    with pytest.raises(ValueError, match="radius"):
        Sphere(-1.0)
    with pytest.raises(ValueError, match="hexagon patches only"):
        Sphere().mesh(100, irregularity_deg=14)


# ---------------------------------------------------------------------------------- Monge patches
def test_quadratic_at_origin_hand_derived():
    # f = x² - y²/2 + 0: flat tangent plane, Hess = diag(2, -1), k = -eig(Hess) (normal up)
    t = QuadraticPatch(A=1, B=0, C=0, D=0, E=-0.5).exact([0.0], [0.0])
    np.testing.assert_allclose([t.k1[0], t.k2[0]], [1.0, -2.0])
    np.testing.assert_allclose(np.abs(t.d1[0]), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(np.abs(t.d2[0]), [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(t.normals[0], [0, 0, 1])
    # f = x² + x: slope 1 along x, the xz-section z = x² + x has curvature 2 / (1 + 1)^(3/2)
    # and bends towards the normal (-1, 0, 1)/√2, so k2 = -1/√2 along (1, 0, 1)/√2; k1 = 0 along y
    t = QuadraticPatch(A=1, B=1, C=0, D=0, E=0).exact([0.0], [0.0])
    np.testing.assert_allclose([t.k1[0], t.k2[0]], [0.0, -1 / np.sqrt(2)], atol=1e-15)
    np.testing.assert_allclose(t.normals[0], [-1 / np.sqrt(2), 0, 1 / np.sqrt(2)])
    np.testing.assert_allclose(np.abs(t.d1[0]), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(np.abs(t.d2[0]), [1 / np.sqrt(2), 0, 1 / np.sqrt(2)])
    # f = xy: saddle with k = ±1 along the diagonals
    t = QuadraticPatch(A=0, B=0, C=1, D=0, E=0).exact([0.0], [0.0])
    np.testing.assert_allclose([t.k1[0], t.k2[0]], [1.0, -1.0])
    np.testing.assert_allclose(np.abs(t.d1[0]), [1 / np.sqrt(2), 1 / np.sqrt(2), 0])


def test_saddle_and_ellipsoid_patch_at_origin():
    t = Saddle(a=2.0, b=0.5).exact([0.0], [0.0])
    np.testing.assert_allclose([t.k1[0], t.k2[0]], [0.5, -2.0])
    # C sqrt(1 - A²x² - B²y²) at the top: curvature C A², C B² (bending away from the up normal)
    t = EllipsoidPatch(A=0.6, B=0.3, C=2.0).exact([0.0], [0.0])
    np.testing.assert_allclose([t.k1[0], t.k2[0]], [0.72, 0.18])
    # the cap of a sphere of radius r: A = B = 1/r, C = r
    r = 1.25
    x, y = np.array([0.3, -0.5, 0.1]), np.array([0.2, 0.4, -0.7])
    t = EllipsoidPatch(A=1 / r, B=1 / r, C=r).exact(x, y)
    np.testing.assert_allclose(t.k1, 1 / r)
    np.testing.assert_allclose(t.k2, 1 / r)
    p = np.column_stack([x, y, np.sqrt(r * r - x * x - y * y)])
    np.testing.assert_allclose(t.normals, p / r)


def numerical_curvature(patch: MongePatch, x, y, h=1e-5, hn=1e-3):
    """Principal curvatures from finite differences of ``height`` alone.

    The normal field N(x, y) comes from central-difference slopes; its central differences N_x, N_y
    and the tangents X_x, X_y give the shape operator in the parameter basis through
    ``[N_x N_y] = [X_x X_y] S`` (dN = W dX), whose eigenvalues are the curvatures.
    """
    f = patch.height

    def slopes(x, y):
        return (f(x + h, y) - f(x - h, y)) / (2 * h), (f(x, y + h) - f(x, y - h)) / (2 * h)

    def normal(x, y):
        p, q = slopes(x, y)
        return unit(np.stack([-p, -q, np.ones_like(p)], axis=-1))

    nx = (normal(x + hn, y) - normal(x - hn, y)) / (2 * hn)
    ny = (normal(x, y + hn) - normal(x, y - hn)) / (2 * hn)
    p, q = slopes(x, y)
    one, zero = np.ones_like(p), np.zeros_like(p)
    jac = np.stack([np.stack([one, zero, p], -1), np.stack([zero, one, q], -1)], axis=-1)  # (n, 3, 2)
    dn = np.stack([nx, ny], axis=-1)
    shape = np.linalg.pinv(jac) @ dn
    k = np.sort(np.linalg.eigvals(shape).real, axis=1)[:, ::-1]
    return k, normal(x, y), jac, shape


@pytest.mark.parametrize("cls", [QuadraticPatch, EllipsoidPatch, TrigonometricPatch, Saddle])
def test_monge_exact_matches_finite_differences(cls):
    rng = np.random.default_rng(11)
    hexagon = hexagon_grid(217)
    for _ in range(5):
        patch = cls.random(rng)
        # random points of the hexagon: the grid jittered a little, corners included
        xy = hexagon.xy * 0.999 + rng.uniform(-5e-4, 5e-4, hexagon.xy.shape)
        x, y = xy[:, 0], xy[:, 1]
        t = patch.exact(x, y)
        k, normals, jac, shape = numerical_curvature(patch, x, y)
        scale = 1.0 + np.abs(k).max(axis=1)
        assert np.all(np.abs(t.k1 - k[:, 0]) < 1e-5 * scale), patch
        assert np.all(np.abs(t.k2 - k[:, 1]) < 1e-5 * scale), patch
        np.testing.assert_allclose(t.normals, normals, atol=1e-8)
        # d1 is an eigenvector of the numerical shape operator for k1 (where k1, k2 are apart)
        apart = (t.k1 - t.k2) > 0.05 * scale
        coords = np.einsum("nij,nj->ni", np.linalg.pinv(jac), t.d1)
        residual = np.einsum("nij,nj->ni", shape, coords) - t.k1[:, None] * coords
        assert np.abs(residual[apart]).max() < 1e-4 * scale.max()
        assert_frames(t)


def test_trigonometric_patch_is_smooth_and_real_on_hexagon():
    rng = np.random.default_rng(3)
    x = np.linspace(-1, 1, 401)
    for _ in range(50):
        patch = TrigonometricPatch.random(rng)
        assert 1.0 <= patch.A <= 2.0 and -2.0 <= patch.B <= 2.0
        fxx = patch.hessian(x, np.zeros_like(x))[0]
        assert np.all(np.isfinite(fxx)) and np.abs(fxx).max() < 2.5
    # a non-integer exponent stays real left of the origin
    assert np.isfinite(TrigonometricPatch(A=1.37, B=1).height(np.array([-1.0]), np.array([0.0]))).all()


def test_random_parameters_follow_the_paper():
    rng = np.random.default_rng(0)
    corners = np.stack([np.cos(np.arange(6) * np.pi / 3), np.sin(np.arange(6) * np.pi / 3)], axis=1)
    for _ in range(300):
        q = QuadraticPatch.random(rng)
        assert all(-2 <= v <= 2 for v in q.parameters.values())
        e = EllipsoidPatch.random(rng)
        assert e.A**2 + e.B**2 <= 1 and -10 <= e.C <= 10
        radicand = 1 - (e.A * corners[:, 0]) ** 2 - (e.B * corners[:, 1]) ** 2
        assert radicand.min() >= 0.5 - 1e-12
    with pytest.raises(ValueError, match="undefined on the unit hexagon"):
        EllipsoidPatch(A=1.0, B=0.0, C=1.0)
    assert QuadraticPatch.random(7) == QuadraticPatch.random(7)
    assert QuadraticPatch.random(7) != QuadraticPatch.random(8)


def test_patch_mesh_lifts_hexagon_with_upward_ccw_faces():
    patch = TrigonometricPatch(A=1.7, B=-1.5)
    s = patch.mesh(817, irregularity_deg=14, rng=2)
    v = s.mesh.vertices
    np.testing.assert_allclose(v[:, 2], patch.height(v[:, 0], v[:, 1]))
    assert np.all(s.mesh.face_normals[:, 2] > 0)
    assert face_normals_agree(s, 0.99)
    expected = patch.exact(v[:, 0], v[:, 1])
    np.testing.assert_array_equal(s.truth.k1, expected.k1)
    assert abs(s.irregularity_deg - 14) < 2
    # a plain Mesh works as the planar input too (its z is replaced)
    flat = hexagon_grid(217).mesh
    lifted = patch.sample(flat)
    np.testing.assert_array_equal(lifted.mesh.faces, flat.faces)
    np.testing.assert_allclose(lifted.mesh.vertices[:, 2], patch.height(flat.vertices[:, 0], flat.vertices[:, 1]))


# ---------------------------------------------------------------------------------- hexagon meshes
def triangle_corner_angles(xy, tris):
    """Angles (degrees) by the law of cosines: independent of the library's measure."""
    p = xy[tris]
    a = np.linalg.norm(p[:, 1] - p[:, 2], axis=1)
    b = np.linalg.norm(p[:, 2] - p[:, 0], axis=1)
    c = np.linalg.norm(p[:, 0] - p[:, 1], axis=1)
    alpha = np.arccos(np.clip((b * b + c * c - a * a) / (2 * b * c), -1, 1))
    beta = np.arccos(np.clip((a * a + c * c - b * b) / (2 * a * c), -1, 1))
    return np.degrees(np.stack([alpha, beta, np.pi - alpha - beta], axis=1))


def signed_areas(xy, tris):
    p = xy[tris]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def on_hexagon_border(xy):
    angles = np.pi / 6 + np.arange(6) * np.pi / 3
    reach = xy @ np.stack([np.cos(angles), np.sin(angles)])
    return np.isclose(reach.max(axis=1), SQRT3 / 2, atol=1e-12)


@pytest.mark.parametrize("n, s", list(zip(PAPER_VERTEX_COUNTS, (8, 16, 32, 64))))
def test_regular_hexagon_grid(n, s):
    g = hexagon_grid(n)
    assert g.n_vertices == n == 3 * s * (s + 1) + 1 and g.subdivisions == s
    assert g.triangles.shape == (6 * s * s, 3)
    np.testing.assert_allclose(triangle_corner_angles(g.xy, g.triangles), 60.0, atol=1e-9)
    assert angle_irregularity(g.xy, g.triangles) < 1e-9
    np.testing.assert_allclose(signed_areas(g.xy, g.triangles), SQRT3 / 4 / s**2)
    np.testing.assert_array_equal(g.border, on_hexagon_border(g.xy))
    assert g.border.sum() == 6 * s
    np.testing.assert_array_equal(g.mesh.border_vertices, g.border)
    np.testing.assert_allclose(np.abs(g.xy).max(axis=0), [1.0, SQRT3 / 2])
    interior = ~g.border
    assert np.all(g.mesh.valence[interior] == 6)


def test_hexagon_rejects_other_counts():
    with pytest.raises(ValueError, match="217, 817, 3169, 12481"):
        hexagon_grid(800)
    assert hexagon_grid(3 * 5 * 6 + 1).subdivisions == 5


@pytest.mark.parametrize("n", [217, 817])
@pytest.mark.parametrize("target", [14.0, 25.0])
def test_irregular_hexagon_hits_target(n, target):
    regular = hexagon_grid(n)
    g = hexagon_mesh(n, irregularity_deg=target, rng=42)
    angles = triangle_corner_angles(g.xy, g.triangles)
    measured = np.sqrt(np.mean((angles - 60) ** 2))
    assert abs(measured - target) < 2.0
    assert measured == pytest.approx(g.irregularity_deg, abs=1e-9)
    # border fixed, interior moved, still a triangulated hexagon without flat or flipped triangles
    np.testing.assert_array_equal(g.xy[g.border], regular.xy[regular.border])
    assert np.abs(g.xy[~g.border] - regular.xy[~regular.border]).max() > 0.1 / g.subdivisions
    areas = signed_areas(g.xy, g.triangles)
    assert areas.min() > 1e-6 / g.subdivisions**2
    assert areas.sum() == pytest.approx(1.5 * SQRT3, rel=1e-12)
    mesh = g.mesh
    assert not mesh.degenerate_faces.any()
    rep = mesh.report()
    assert rep.border_loops == 1 and rep.nonmanifold_edges == 0 and rep.isolated_vertices == 0
    np.testing.assert_array_equal(mesh.border_vertices, g.border)
    assert np.all(mesh.face_normals[:, 2] > 0)


def test_irregular_hexagon_is_deterministic():
    a = hexagon_mesh(217, irregularity_deg=14, rng=7)
    b = hexagon_mesh(217, irregularity_deg=14, rng=np.random.default_rng(7))
    c = hexagon_mesh(217, irregularity_deg=14, rng=8)
    np.testing.assert_array_equal(a.xy, b.xy)
    np.testing.assert_array_equal(a.triangles, b.triangles)
    assert not np.array_equal(a.xy, c.xy)
    s1 = make_surface("quadratic", irregularity=14, noise=0.1, seed=3, random_params=True)
    s2 = make_surface("quadratic", irregularity=14, noise=0.1, seed=3, random_params=True)
    np.testing.assert_array_equal(s1.mesh.vertices, s2.mesh.vertices)
    assert s1.surface == s2.surface


def test_irregularity_out_of_reach():
    with pytest.raises(ValueError, match="out of reach"):
        hexagon_mesh(217, irregularity_deg=80, rng=0)
    with pytest.raises(ValueError, match=">= 0"):
        hexagon_mesh(217, irregularity_deg=-1)


# ---------------------------------------------------------------------------------- registry
def test_registry_names_and_defaults():
    assert set(SURFACES) == {
        "sphere", "cylinder", "torus", "ellipsoid", "saddle", "quadratic", "ellipsoid_patch", "trigonometric",
        "capped_cylinder", "box", "hemisphere", "cone",
    }
    for name, cls in SURFACES.items():
        surface = cls()
        assert surface.name == name
        assert surface.parameters == {p.name: p.default for p in cls.params}
        for p in cls.params:
            assert p.low <= p.default <= p.high


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_every_surface_takes_its_params_in_order_or_by_name(name):
    cls = SURFACES[name]
    values = [int(p.default) if p.default == int(p.default) else p.default for p in cls.params]
    by_order, by_name = cls(*values), cls(**{p.name: v for p, v in zip(cls.params, values)})
    assert by_order == by_name == cls()
    assert all(type(getattr(by_order, p.name)) is float for p in cls.params)
    with pytest.raises(TypeError, match="takes at most"):
        cls(*values, 1.0)
    with pytest.raises(TypeError, match="no parameter nosuch"):
        cls(nosuch=1.0)
    if cls.positive:  # lengths: a finite value > 0 or a one-line ValueError naming the parameter
        first = cls.params[0].name
        for bad in (0.0, -1.0, float("nan"), float("inf")):
            with pytest.raises(ValueError, match=f"{first} must be a finite value > 0"):
                cls(**{first: bad})


@pytest.mark.parametrize("name", sorted(n for n, cls in SURFACES.items() if not issubclass(cls, CreasedSurface)))
def test_make_surface_every_registered_surface(name):  # creased ones: tests/test_creased_surfaces.py
    s = make_surface(name, n_vertices=217 if issubclass(SURFACES[name], MongePatch) else 400)
    assert s.truth.n == s.mesh.n_vertices
    assert_frames(s.truth)
    assert face_normals_agree(s, 0.9)
    assert not s.mesh.degenerate_faces.any()
    assert s.mesh.border_vertices.any() == (not SURFACES[name].closed)
    assert name.split("_")[0] in s.describe().lower()


def test_make_surface_noise_keeps_truth():
    clean = make_surface("sphere", n_vertices=642)
    noisy = make_surface("sphere", n_vertices=642, noise=0.2, seed=1)
    np.testing.assert_array_equal(noisy.truth.k1, clean.truth.k1)
    np.testing.assert_array_equal(noisy.truth.normals, clean.truth.normals)
    np.testing.assert_array_equal(noisy.mesh.faces, clean.mesh.faces)
    offsets = noisy.mesh.vertices - clean.mesh.vertices
    assert offsets.std() == pytest.approx(0.2 * clean.mesh.mean_edge_length, rel=0.1)
    assert abs(offsets.mean()) < 0.1 * offsets.std()
    assert noisy.noise == 0.2 and "noise 0.2" in noisy.describe()


def test_make_surface_errors_and_parameters():
    with pytest.raises(ValueError, match="sphere, cylinder"):
        make_surface("blob")
    with pytest.raises(ValueError, match="parameters are A, B, C"):
        make_surface("ellipsoid_patch", radius=2)
    with pytest.raises(ValueError, match="hexagon patches only"):
        make_surface("torus", irregularity=14)
    with pytest.raises(TypeError):
        make_surface("sphere", 100)
    s = make_surface("saddle", n_vertices=217, a=3.0, b=0.5)
    assert s.surface == Saddle(a=3.0, b=0.5)
    origin = np.argmin(np.linalg.norm(s.mesh.vertices, axis=1))
    np.testing.assert_allclose([s.truth.k1[origin], s.truth.k2[origin]], [0.5, -3.0])
