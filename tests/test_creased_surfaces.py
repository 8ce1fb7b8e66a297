"""Creased solids: closed outward meshes with shared crease vertices, exact curvature on the smooth parts."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import curv
from curv.core.features import dihedral_angles
from curv.surfaces import (
    SURFACES, Box, CappedCylinder, Cone, CreasedSurface, HemisphereOnDisc, Sphere, crease_distance_rings,
    make_surface,
)

CREASED = sorted(name for name, cls in SURFACES.items() if issubclass(cls, CreasedSurface))
DENSITIES = (500, 2562, 6000)
VOLUMES = {
    "capped_cylinder": lambda s: np.pi * s.radius**2 * s.height,
    "box": lambda s: s.size_x * s.size_y * s.size_z,
    "hemisphere": lambda s: 2.0 / 3.0 * np.pi * s.radius**3,
    "cone": lambda s: np.pi * s.radius**2 * s.height / 3.0,
}


def rowdot(a, b):
    return np.einsum("ij,ij->i", a, b)


def enclosed_volume(mesh):
    p = mesh.vertices[mesh.triangles]
    return rowdot(p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0


def crease_edges(sampled):
    return sampled.surface.crease_edges(sampled.mesh)


def corner_angles_degrees(mesh):
    """(m, 3) interior angle of each triangle at each corner."""
    p = mesh.vertices[mesh.triangles]
    after, before = np.roll(p, -1, axis=1) - p, np.roll(p, 1, axis=1) - p
    cos = np.einsum("mki,mki->mk", after, before) / (np.linalg.norm(after, axis=2) * np.linalg.norm(before, axis=2))
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


# ---------------------------------------------------------------------------------- meshes
def test_registry_offers_the_creased_solids():
    assert CREASED == ["box", "capped_cylinder", "cone", "hemisphere"]
    for name in CREASED:
        assert SURFACES[name].closed


@pytest.mark.parametrize("n", DENSITIES)
@pytest.mark.parametrize("name", CREASED)
def test_mesh_is_closed_manifold_outward_without_duplicates(name, n):
    s = make_surface(name, n_vertices=n)
    mesh, surface = s.mesh, s.surface
    report = mesh.report()
    assert report.border_edges == 0 and report.nonmanifold_edges == 0 and report.nonmanifold_vertices == 0
    assert report.components == 1 and report.degenerate_faces == 0 and report.inconsistent_edges == 0
    assert report.duplicate_vertices == 0
    # nor nearly coincident ones: every two vertices at least a third of the shortest edge apart
    assert not cKDTree(mesh.vertices).query_pairs(mesh.edge_lengths.min() / 3)
    assert abs(mesh.n_vertices - n) <= 0.1 * n
    # convex solids: outward faces look away from the centroid, and enclose the exact volume
    centroid = mesh.vertices.mean(axis=0)
    assert (rowdot(mesh.face_normals, mesh.vertices[mesh.triangles].mean(axis=1) - centroid) > 0).all()
    exact = VOLUMES[name](surface)
    assert exact * (1 - 30 / n) < enclosed_volume(mesh) <= exact * (1 + 1e-12)   # inscribed
    # faces away from the features follow the exact normals of their corners
    smooth = s.truth.valid[mesh.triangles].all(axis=1)
    exact = s.truth.normals[mesh.triangles[smooth]].sum(axis=1)
    assert smooth.mean() > 0.5
    assert rowdot(mesh.face_normals[smooth], exact / np.linalg.norm(exact, axis=1, keepdims=True)).min() > 0.9


@pytest.mark.parametrize("name", CREASED)
def test_density_sets_the_edge_length(name):
    coarse, fine = (make_surface(name, n_vertices=n).mesh for n in (1000, 4000))
    assert coarse.mean_edge_length / fine.mean_edge_length == pytest.approx(2.0, rel=0.1)
    angles = corner_angles_degrees(fine)
    assert angles.min() > 35 and angles.max() < 100    # near-regular, no slivers


def test_crease_vertices_are_shared_by_both_sides():
    s = CappedCylinder(radius=1.0, height=2.0).mesh(2000)
    mesh, part, parts = s.mesh, s.info["part"], s.info["parts"]
    rim = part == -1
    assert rim.sum() == 2 * s.info["rim_vertices"]
    # neighbours of each rim vertex, counted per part: its cap and the side, never the other cap
    touching = (mesh.adjacency @ (part[:, None] == np.arange(len(parts))).astype(int)) > 0
    bottom, side, top = (parts.index(name) for name in ("bottom", "side", "top"))
    low = mesh.vertices[:, 2] < 0
    assert touching[rim, side].all()
    assert touching[rim & low, bottom].all() and not touching[rim & low, top].any()
    assert touching[rim & ~low, top].all() and not touching[rim & ~low, bottom].any()


@pytest.mark.parametrize("n", DENSITIES)
def test_box_and_capped_cylinder_creases_are_right_angles(n):
    box = Box().mesh(n)
    angle = dihedral_angles(box.mesh)
    crease = crease_edges(box)
    np.testing.assert_allclose(angle[crease], 90.0, atol=1e-9)
    np.testing.assert_allclose(angle[~crease], 0.0, atol=1e-6)
    cyl = CappedCylinder().mesh(n)
    angle = dihedral_angles(cyl.mesh)
    crease = crease_edges(cyl)
    assert crease.sum() == 2 * cyl.info["rim_vertices"]            # the two rim loops, nothing else
    np.testing.assert_allclose(angle[crease], 90.0, atol=3.0)
    assert angle[~crease].max() < 30.0                             # a 30° threshold finds the rims exactly


def test_hemisphere_and_cone_rims():
    dome = HemisphereOnDisc().mesh(2562)
    angle = dihedral_angles(dome.mesh)
    crease = crease_edges(dome)
    np.testing.assert_allclose(angle[crease], 90.0, atol=6.0)
    assert angle[~crease].max() < 30.0
    cone = Cone(radius=1.0, height=1.5)
    s = cone.mesh(2562)
    angle = dihedral_angles(s.mesh)
    rim = crease_edges(s) & (s.mesh.vertices[s.mesh.edges, 2] == 0).all(axis=1)
    np.testing.assert_allclose(angle[rim], 90.0 + np.degrees(cone.half_angle), atol=3.0)


# ---------------------------------------------------------------------------------- truth
def test_truth_values_per_part():
    r, height = 0.8, 3.0
    s = CappedCylinder(radius=r, height=height).mesh(3000)
    v, t, part, parts = s.mesh.vertices, s.truth, s.info["part"], s.info["parts"]
    side, caps = part == parts.index("side"), np.isin(part, [parts.index("bottom"), parts.index("top")])
    assert side.any() and caps.any() and (side | caps | (part == -1)).all()
    np.testing.assert_allclose(t.k1[side], 1 / r)
    np.testing.assert_allclose(t.k2[side], 0.0)
    np.testing.assert_allclose(np.abs(t.d2[side, 2]), 1.0)                         # along the axis
    np.testing.assert_allclose(t.normals[side], v[side] * [1, 1, 0] / r, atol=1e-12)
    np.testing.assert_allclose(t.k1[caps], 0.0)
    np.testing.assert_allclose(t.normals[caps], np.sign(v[caps, 2:]) * [0, 0, 1])
    dome = HemisphereOnDisc(radius=2.0).mesh(2000)
    sphere = dome.info["part"] == dome.info["parts"].index("sphere")
    np.testing.assert_allclose(dome.truth.k1[sphere], 0.5)
    np.testing.assert_allclose(dome.truth.k2[sphere], 0.5)
    np.testing.assert_allclose(dome.truth.normals[sphere], dome.mesh.vertices[sphere] / 2.0, atol=1e-12)
    cone = Cone(radius=1.0, height=2.0)
    s = cone.mesh(2000)
    side = s.info["part"] == s.info["parts"].index("side")
    rho = np.hypot(*s.mesh.vertices[side, :2].T)
    np.testing.assert_allclose(s.truth.k1[side], np.cos(np.arctan(0.5)) / rho)
    np.testing.assert_allclose(s.truth.k2[side], 0.0)
    box = Box(1.0, 2.0, 3.0).mesh(2000)
    smooth = box.truth.valid
    np.testing.assert_array_equal(box.truth.k1[smooth], 0.0)
    assert (np.abs(box.truth.normals[smooth]).max(axis=1) == 1.0).all()            # an axis


@pytest.mark.parametrize("name", CREASED)
def test_truth_frames_and_features(name):
    s = make_surface(name, n_vertices=1500)
    t, part = s.truth, s.info["part"]
    ok = t.valid
    assert ok.mean() > 0.8 and (~ok).any()
    np.testing.assert_array_equal(ok, part >= 0)
    for d in (t.d1, t.d2, t.normals):
        np.testing.assert_allclose(np.linalg.norm(d[ok], axis=1), 1.0, atol=1e-12)
    assert np.abs(rowdot(t.d1, t.normals)[ok]).max() < 1e-12
    assert np.abs(rowdot(t.d2, t.normals)[ok]).max() < 1e-12
    np.testing.assert_allclose(np.cross(t.d1, t.d2)[ok], t.normals[ok], atol=1e-12)  # right-handed
    assert np.all(t.k1[ok] >= t.k2[ok])
    assert np.isnan(t.k1[~ok]).all() and np.isnan(t.d1[~ok]).all() and np.isnan(t.normals[~ok]).all()
    np.testing.assert_array_equal(t.reason[~ok], curv.Reason.FEATURE)
    np.testing.assert_array_equal(t.reason[ok], curv.Reason.OK)
    assert t.method == "exact"


def test_feature_vertices_are_exactly_the_creases_corners_and_apex():
    box = Box(2.0, 1.5, 1.0)
    s = box.mesh(2000)
    on_faces = (np.isclose(np.abs(s.mesh.vertices), box.sizes / 2, rtol=0, atol=1e-12)).sum(axis=1)
    np.testing.assert_array_equal(~s.truth.valid, on_faces >= 2)
    corners = on_faces == 3
    assert corners.sum() == 8
    cyl = CappedCylinder(radius=1.0, height=2.0).mesh(2000)
    v = cyl.mesh.vertices
    rim = np.isclose(np.abs(v[:, 2]), 1.0, rtol=0, atol=1e-12) & np.isclose(np.hypot(*v[:, :2].T), 1.0, atol=1e-12)
    np.testing.assert_array_equal(~cyl.truth.valid, rim)
    cone = Cone(radius=1.0, height=1.5).mesh(2000)
    v = cone.mesh.vertices
    apex = np.flatnonzero((v == [0, 0, 1.5]).all(axis=1))
    assert apex.size == 1 and not cone.truth.valid[apex[0]]
    rim = (v[:, 2] == 0) & np.isclose(np.hypot(*v[:, :2].T), 1.0, atol=1e-12)
    np.testing.assert_array_equal(~cone.truth.valid, rim | (np.arange(len(v)) == apex[0]))


def _shape_operator(surface, point_at, u, v, eps=1e-5):
    """The 2x2 shape operator in the truth's (d1, d2) frame, from central differences of the exact normals."""
    truth = surface.exact_at(point_at(u, v))
    frame = np.stack([truth.d1, truth.d2], axis=1)                                 # (n, 2, 3)
    derivs = []
    for du, dv in ((eps, 0.0), (0.0, eps)):
        plus, minus = surface.exact_at(point_at(u + du, v + dv)), surface.exact_at(point_at(u - du, v - dv))
        x_t = (point_at(u + du, v + dv) - point_at(u - du, v - dv)) / (2 * eps)
        n_t = (plus.normals - minus.normals) / (2 * eps)
        derivs.append((x_t, n_t))
    x = np.einsum("nij,knj->nik", frame, np.stack([d[0] for d in derivs]))        # (n, 2, 2) tangents
    dn = np.einsum("nij,knj->nik", frame, np.stack([d[1] for d in derivs]))
    return truth, dn @ np.linalg.inv(x)                                            # dN = W t


def _cylinder_side(s):
    return lambda u, v: np.stack([s.radius * np.cos(u), s.radius * np.sin(u), v], axis=1)


def _dome(s):
    return lambda u, v: s.radius * np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], axis=1)


def _cone_side(s):
    alpha = s.half_angle
    return lambda u, v: np.stack(
        [v * np.sin(alpha) * np.cos(u), v * np.sin(alpha) * np.sin(u), s.height - v * np.cos(alpha)], axis=1)


@pytest.mark.parametrize("surface, point_at, v_range", [
    (CappedCylinder(radius=0.7, height=2.0), _cylinder_side, (-0.9, 0.9)),
    (HemisphereOnDisc(radius=1.3), _dome, (0.1, 1.4)),
    (Cone(radius=1.0, height=1.5), _cone_side, (0.1, 1.7)),
    (Cone(radius=2.0, height=0.5), _cone_side, (0.1, 2.0)),
])
def test_truth_matches_finite_differences_of_the_normals(surface, point_at, v_range):
    rng = np.random.default_rng(4)
    u, v = rng.uniform(0, 2 * np.pi, 50), rng.uniform(*v_range, 50)
    truth, shape = _shape_operator(surface, point_at(surface), u, v)
    assert truth.valid.all()
    expected = np.zeros_like(shape)
    expected[:, 0, 0], expected[:, 1, 1] = truth.k1, truth.k2
    np.testing.assert_allclose(shape, expected, atol=1e-6 * np.abs(truth.k1).max())


def test_cone_curvature_against_a_fine_mesh():
    """cos(alpha) / rho, estimated: the mean curvature of a fine mesh away from the rim and apex."""
    s = Cone(radius=1.0, height=1.0).mesh(5000)          # alpha = 45°: 1/rho would be 41 % too large
    res = curv.estimate(s.mesh, "nc", 2)
    side = s.info["part"] == s.info["parts"].index("side")
    far = side & (crease_distance_rings(s.mesh, ~s.truth.valid) >= 3)
    assert far.sum() > 0.4 * s.mesh.n_vertices
    assert np.median(np.abs(res.k1[far] - s.truth.k1[far]) / s.truth.k1[far]) < 0.01
    assert np.median(np.abs(res.k2[far]) / s.truth.k1[far]) < 0.01


def test_exact_at_rejects_points_off_the_surface():
    cyl = CappedCylinder()
    with pytest.raises(ValueError, match="off it"):
        cyl.exact_at([[0.0, 0.0, 0.0]])                          # inside
    with pytest.raises(ValueError, match="off it"):
        cyl.exact_at([[0.0, 0.0, 1.5]])                          # outside, on the line of the axis
    got = cyl.exact_at([[1.0, 0.0, 0.0], [0.3, 0.2, 1.0], [0.0, 1.0, -1.0]])
    np.testing.assert_array_equal(got.valid, [True, True, False])


# ---------------------------------------------------------------------------------- rings and API
def test_crease_distance_rings_count_rows_from_the_rims():
    s = CappedCylinder(radius=1.0, height=2.0).mesh(2562)
    rings = crease_distance_rings(s.mesh, ~s.truth.valid)
    np.testing.assert_array_equal(rings == 0, ~s.truth.valid)
    side = s.info["part"] == s.info["parts"].index("side")
    z = s.mesh.vertices[side, 2]
    rows = np.unique(s.mesh.vertices[:, 2][np.isclose(np.hypot(*s.mesh.vertices[:, :2].T), 1.0)])
    row = np.searchsorted(rows, z)
    np.testing.assert_array_equal(rings[side], np.minimum(row, rows.size - 1 - row))
    # neighbours differ by at most one ring
    ends = rings[s.mesh.edges]
    assert np.abs(ends[:, 0] - ends[:, 1]).max() == 1
    smooth = Sphere().mesh(642)
    np.testing.assert_array_equal(crease_distance_rings(smooth.mesh, np.zeros(642, bool)), -1)


def test_make_surface_options_and_errors():
    s = make_surface("box", n_vertices=800, size_x=1.0, size_y=1.0, size_z=1.0)
    assert s.surface == Box(1.0, 1.0, 1.0) and "box" in s.describe().lower()
    noisy = make_surface("box", n_vertices=800, noise=0.1, seed=3, size_x=1.0, size_y=1.0, size_z=1.0)
    np.testing.assert_array_equal(noisy.truth.valid, s.truth.valid)
    np.testing.assert_array_equal(noisy.info["part"], s.info["part"])
    assert not np.array_equal(noisy.mesh.vertices, s.mesh.vertices)
    with pytest.raises(ValueError, match="hexagon patches only"):
        make_surface("cone", irregularity=10)
    with pytest.raises(ValueError, match="radius must be"):
        make_surface("capped_cylinder", radius=-1)
    with pytest.raises(ValueError, match="n_vertices must be"):
        make_surface("hemisphere", n_vertices=3)
    assert CappedCylinder().mesh().mesh.n_vertices == pytest.approx(CappedCylinder.default_vertices, rel=0.1)
