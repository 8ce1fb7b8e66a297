"""The csm kernel's pieces: exact clipping, chunking, fixed radii, reasons and cancel."""

from __future__ import annotations

import math

import numpy as np
import pytest

import curv
from curv.estimators._ball_clipping import disc_triangle_area, segment_in_ball
from curv.estimators.csm import iter_csm
from curv.geometry.normals import vertex_normals
from curv.core.ranges import Range, ball_radii
from curv.core.validity import Reason
from tests.clipping import triangle_in_ball_area
from tests.meshes import icosphere, torus_grid


def _drain(gen):
    fractions = []
    try:
        while True:
            fractions.append(float(next(gen)))
    except StopIteration as stop:
        return stop.value, fractions


def _csm(mesh, k=2.0, *, radius=None, chunk=None):
    rng = Range(radius=radius) if radius is not None else Range(k=k)
    return _drain(iter_csm(mesh, vertex_normals(mesh), ball_radii(mesh, rng, uses_normals=False), chunk=chunk))


# ---------------------------------------------------------------------------- clipping
@pytest.mark.parametrize("start, direction, radius, expected", [
    ((-2.0, 0.0, 0.0), (4.0, 0.0, 0.0), 1.0, 0.5),     # through the centre: 2 of 4
    ((0.0, 0.0, 0.0), (3.0, 0.0, 0.0), 1.0, 1 / 3),    # from the centre outwards
    ((0.1, 0.0, 0.0), (0.5, 0.0, 0.0), 1.0, 1.0),      # wholly inside
    ((-2.0, 1.5, 0.0), (4.0, 0.0, 0.0), 1.0, 0.0),     # misses
    ((-2.0, 0.6, 0.0), (4.0, 0.0, 0.0), 1.0, 0.4),     # chord of half-length 0.8
])
def test_segment_in_ball(start, direction, radius, expected):
    assert segment_in_ball(start, direction, radius ** 2) == pytest.approx(expected, abs=1e-14)


def test_disc_triangle_area_known_cases():
    big = (-10.0, -10.0, 20.0, -10.0, -10.0, 20.0)  # contains the unit disc
    assert disc_triangle_area(*big, 1.0) == pytest.approx(math.pi, rel=1e-14)
    tri = (0.1, 0.1, 0.4, 0.1, 0.1, 0.3)  # inside the unit disc
    assert disc_triangle_area(*tri, 1.0) == pytest.approx(0.5 * 0.3 * 0.2, rel=1e-14)
    # centre at a corner of angle 90 degrees, small disc: a quarter disc
    assert disc_triangle_area(0.0, 0.0, 5.0, 0.0, 0.0, 5.0, 0.25) == pytest.approx(math.pi * 0.25 / 4, rel=1e-14)
    # centre on an edge: half a disc
    assert disc_triangle_area(-5.0, 0.0, 5.0, 0.0, 0.0, 5.0, 0.01) == pytest.approx(math.pi * 0.01 / 2, rel=1e-13)
    # disc away from the triangle
    assert disc_triangle_area(3.0, 3.0, 4.0, 3.0, 3.0, 4.0, 1.0) == 0.0


def test_triangle_in_ball_area_matches_sampling():
    rng = np.random.default_rng(4)
    a, b, c = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.2, 0.1]), np.array([0.3, 0.9, -0.2])
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    # barycentric samples of the triangle, area-uniform
    u, v = rng.random(400_000), rng.random(400_000)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    pts = a + u[:, None] * (b - a) + v[:, None] * (c - a)
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a))
    for centre, radius in [((0.5, 0.4, 0.3), 0.45), ((0.0, 0.0, 0.0), 0.7), ((1.2, 0.0, 0.0), 0.6)]:
        centre = np.asarray(centre)
        inside = (np.linalg.norm(pts - centre, axis=1) <= radius).mean() * area
        got = triangle_in_ball_area(a, b, c, centre, radius)
        assert got == pytest.approx(inside, abs=3e-3 * area)
    # a ball that holds the whole triangle, and one that misses its plane
    assert triangle_in_ball_area(a, b, c, np.zeros(3), 10.0) == pytest.approx(area, rel=1e-13)
    assert triangle_in_ball_area(a, b, c, a + n * 2.0, 1.0) == 0.0


def _in_frame(a, b, c, centre, radius):
    """The same area through ``disc_triangle_area`` in a frame of the triangle's plane (the general clip)."""
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    u = (b - a) / np.linalg.norm(b - a)
    v = np.cross(n, u)
    h = np.dot(a - centre, n)
    flat = [float(np.dot(p - centre, w)) for p in (a, b, c) for w in (u, v)]
    return disc_triangle_area(*flat, radius ** 2 - h ** 2)


@pytest.mark.parametrize("inside", [1, 2])
def test_one_or_two_corners_inside_agree_with_the_general_clip(inside):
    """The 3-D clip of a face with one or two corners in the ball (chords and arcs from which
    corners are in, no frame) equals the general clip in the face's frame; with one corner inside
    the far edge sometimes passes through the disc too (a second chord, two arcs)."""
    rng = np.random.default_rng(7 + inside)
    dips = checked = 0
    while checked < 3000:
        a, b, c = rng.normal(size=(3, 3))
        centre = rng.normal(size=3) * 0.5
        d = np.linalg.norm(np.array([a, b, c]) - centre, axis=1)
        radius = rng.uniform(0.05, 2.0)
        if int((d <= radius).sum()) != inside:
            continue
        checked += 1
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a))
        want = _in_frame(a, b, c, centre, radius)
        assert triangle_in_ball_area(a, b, c, centre, radius) == pytest.approx(want, abs=1e-12 * area)
        if inside == 1:
            # the far edge (both ends outside) passes through the ball between its ends
            j, k = [p for p, dist in zip((a, b, c), d) if dist > radius]
            t = np.clip(np.dot(centre - j, k - j) / np.dot(k - j, k - j), 0.0, 1.0)
            dips += np.linalg.norm(j + t * (k - j) - centre) < radius
    assert inside == 2 or dips > 20


# ---------------------------------------------------------------------------- the estimator
def test_chunks_do_not_change_the_result():
    mesh = icosphere(3)
    ref, _ = _csm(mesh, 2.5)
    for chunk in (1, 7, 300):
        got, fractions = _csm(mesh, 2.5, chunk=chunk)
        np.testing.assert_array_equal(got.reason, ref.reason)
        np.testing.assert_array_equal(got.k1, ref.k1)
        np.testing.assert_array_equal(got.d2, ref.d2)
        assert fractions == sorted(fractions) and fractions[-1] == 1.0
        assert len(fractions) >= mesh.n_vertices // chunk


def test_fixed_radius_on_a_sphere():
    mesh = icosphere(4, radius=2.0)
    res, _ = _csm(mesh, radius=0.4)
    assert (res.reason == Reason.OK).all()
    # ka <= kb, both close to 1/2 (within the lattice bias of a ball of some 2.5 edges)
    assert (res.k1 <= res.k2).all()
    np.testing.assert_allclose(res.k1, 0.5, rtol=0.08)
    np.testing.assert_allclose(res.k2, 0.5, rtol=0.08)
    # a ball twice as large: the same radius everywhere, so the same support size everywhere
    wide, _ = _csm(mesh, radius=0.8)
    np.testing.assert_allclose(wide.k2, 0.5, rtol=0.08)
    assert np.ptp(wide.k2) < np.ptp(res.k2)


def test_results_change_continuously_with_the_range():
    mesh = icosphere(3)
    a, _ = _csm(mesh, 2.0)
    b, _ = _csm(mesh, 2.0 + 1e-7)
    np.testing.assert_allclose(b.k1, a.k1, atol=1e-5)
    np.testing.assert_allclose(b.k2, a.k2, atol=1e-5)


def test_border_and_degenerate_reasons():
    full = icosphere(3)
    tri = full.triangles
    holed = curv.Mesh(full.vertices, tri[1:])
    res, _ = _csm(holed, 2.0)
    hole = tri[0]
    assert (res.reason[hole] == Reason.BORDER).all()
    far = np.linalg.norm(full.vertices - full.vertices[hole].mean(axis=0), axis=1) > 1.0
    assert (res.reason[far] == Reason.OK).all()
    # a zero-area face (a vertex moved onto the opposite edge): the supports that touch it are DEGENERATE
    a, b, c = tri[0]
    v = full.vertices.copy()
    v[a] = 0.5 * (v[b] + v[c])
    res, _ = _csm(curv.Mesh(v, tri), 1.0)
    assert (res.reason[[a, b, c]] == Reason.DEGENERATE).all()
    assert (res.reason[far] == Reason.OK).all()


def test_closing_the_generator_stops_early():
    mesh = icosphere(4)
    gen = iter_csm(mesh, vertex_normals(mesh), ball_radii(mesh, Range(k=2.0), uses_normals=False), chunk=64)
    for _ in range(5):
        next(gen)
    gen.close()  # a cancel: no error, nothing left running


@pytest.mark.parametrize("cut", [1 - 1e-9, 0.999999, 0.9, 0.3, -0.3, -0.9, -0.999999, -1 + 1e-9])
def test_disc_triangle_area_with_one_edge_through_the_disc(cut):
    """A large triangle below its edge at ``y = cut`` holds the part of the unit disc below it: pi
    less the cap above, from almost the whole disc (the arc inside the triangle near 2 pi) to a
    sliver (an arc near 0)."""
    theta = 2.0 * math.acos(cut)  # angle of the cap's arc above the line
    below = math.pi - 0.5 * (theta - math.sin(theta))
    # counter-clockwise: (-50, cut) -> (0, -50) -> (50, cut)
    got = disc_triangle_area(-50.0, cut, 0.0, -50.0, 50.0, cut, 1.0)
    assert got == pytest.approx(below, abs=1e-13)  # absolute: the expected value itself cancels


@pytest.mark.parametrize("poke", [1e-12, 1e-7, 1e-3, 0.2])
def test_disc_triangle_area_with_a_corner_just_outside(poke):
    """A corner barely outside the disc: the two arcs around it are tiny, and the area is the
    triangle's less the sliver beyond the circle (two tiny arcs, never a full turn)."""
    top = 1.0 + poke
    tri = (-0.5, 0.0, 0.5, 0.0, 0.0, top)
    got = disc_triangle_area(*tri, 1.0)
    whole = 0.5 * top
    sliver = poke * math.sqrt(2 * poke)  # at most the triangle of height poke over the chord
    assert -1e-15 <= whole - got <= sliver + 1e-15


def test_a_region_computes_only_the_triangles_and_edges_its_supports_touch():
    from curv.estimators._ball_sums import touched_elements
    from curv.geometry.neighbourhood import expansion_adjacency, supports

    mesh = icosphere(3)
    radii = ball_radii(mesh, Range(k=2.0), uses_normals=False)
    centres = np.array([0, 5, 17], np.int64)
    indptr, indices = expansion_adjacency(mesh)
    vertices, faces, edges = touched_elements(mesh, centres, radii, indptr, indices, edges=True)
    ptr, support = supports(mesh, radii, centres)
    reached = np.zeros(mesh.n_vertices, bool)
    reached[np.concatenate([centres, support])] = True
    np.testing.assert_array_equal(np.sort(vertices), np.flatnonzero(reached))
    np.testing.assert_array_equal(np.sort(faces), np.flatnonzero(reached[mesh.triangles].any(axis=1)))
    np.testing.assert_array_equal(np.sort(edges), np.flatnonzero(reached[mesh.edges].any(axis=1)))
    assert faces.size < mesh.n_faces / 2


def _fast_and_walked(mesh, k, monkeypatch):
    """csm at range k on ``mesh`` as it runs (clean supports from the star terms) and with every
    support taken as unclean (the walk over every face and edge)."""
    from curv.estimators import csm

    fast, _ = _csm(mesh, k)
    real = csm.star_terms

    def unclean(*args, **kwargs):
        half, star, clean = real(*args, **kwargs)
        return half, star, np.zeros_like(clean)

    monkeypatch.setattr(csm, "star_terms", unclean)
    walked, _ = _csm(mesh, k)
    np.testing.assert_array_equal(fast.reason, walked.reason)
    scale = np.nanmax(np.abs(walked.k2))
    np.testing.assert_allclose(fast.k1, walked.k1, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(fast.k2, walked.k2, rtol=0, atol=1e-12 * scale)
    return fast


@pytest.mark.parametrize("k", [1.0, 2.0, 4.0])
def test_star_sums_equal_the_edge_by_edge_walk(k, monkeypatch):
    # clean supports take the per-vertex star terms and clip only the faces leaving the ball; the
    # walk over every face and edge (kept for supports that are not clean) must give the same values
    from tests.meshes import torus_grid

    rng = np.random.default_rng(3)
    mesh = torus_grid(40, 24)[0]
    mesh = curv.Mesh(mesh.vertices + rng.normal(scale=0.01, size=mesh.vertices.shape), mesh.triangles)
    _fast_and_walked(mesh, k, monkeypatch)


@pytest.mark.parametrize("k", [1.0, 2.0, 4.0])
def test_star_sums_equal_the_walk_on_an_open_patch(k, monkeypatch):
    # next to the border a face's edge v -> u may have no face at v beyond it: the crossing faces
    # then read u itself instead of v's ring (curv.estimators._ball_mesh.crossing_faces)
    from tests.meshes import hex_plane

    flat = hex_plane(16)
    xy = flat.vertices[:, :2]
    mesh = curv.Mesh(np.column_stack([xy, 0.4 * np.sin(3 * xy[:, 0]) * np.cos(2 * xy[:, 1])]), flat.triangles)
    fast = _fast_and_walked(mesh, k, monkeypatch)
    assert (fast.reason == Reason.BORDER).any() and (fast.reason == Reason.OK).any()


def test_corner_rings_name_each_corners_far_end_and_its_faces_other_edge():
    from curv.estimators._ball_mesh import corner_rings
    from tests.meshes import hex_plane

    mesh = hex_plane(5)
    after, link = corner_rings(mesh)
    ptr, corners = mesh.vertex_corners
    tri = mesh.triangles
    border_edges = 0
    for v in range(mesh.n_vertices):
        for j in range(ptr[v], ptr[v + 1]):
            f, c = divmod(int(corners[j]), 3)
            assert tri[f, c] == v and after[j] == tri[f, (c + 1) % 3]
            u = tri[f, (c + 2) % 3]
            ring = list(after[ptr[v]:ptr[v + 1]])
            if u in ring:
                assert link[j] == ring.index(u)
            else:
                assert link[j] == -1
                border_edges += 1
    assert border_edges == 6 * 5  # each border edge once, from the end it leaves


# ---------------------------------------------------------------------------- the paper in numpy
def _normal_cycle_in_numpy(mesh, normals, radii):
    """Cohen-Steiner & Morvan's estimate written as the paper states it, in plain numpy.

    ``T(p) = 1 / area(B ∩ mesh) sum_e beta(e) |e ∩ B| ê êᵀ`` over the edges with an end in the ball B
    (the edges csm reaches from its support), beta the signed dihedral angle, ``|e ∩ B|`` the
    segment/sphere intersection; the eigenvector nearest the normal dropped, each remaining eigenvalue
    given the other eigenvector as its direction. The area inside the ball is the library's exact clip
    (tested against sampling above).
    """
    from curv.estimators._ball_clipping import face_in_ball_area
    from curv.estimators._ball_mesh import ball_mesh

    ball = ball_mesh(mesh)
    v, edges, faces = mesh.vertices, mesh.edges, mesh.edge_faces
    inner = mesh.edge_face_count == 2
    n0, n1 = mesh.face_normals[faces[:, 0]], mesh.face_normals[faces[:, 1]]
    d = v[edges[:, 1]] - v[edges[:, 0]]
    length = np.linalg.norm(d, axis=1)
    unit = d / length[:, None]
    beta = np.arctan2(np.einsum("ij,ij->i", np.cross(n0, n1), unit), np.einsum("ij,ij->i", n0, n1))
    k1, k2 = np.full(mesh.n_vertices, np.nan), np.full(mesh.n_vertices, np.nan)
    for p in range(mesh.n_vertices):
        r = radii[p]
        s = v[edges[:, 0]] - v[p]
        near = inner & ((np.linalg.norm(s, axis=1) <= r) | (np.linalg.norm(s + d, axis=1) <= r))
        a, b, c = (d[near] ** 2).sum(1), (d[near] * s[near]).sum(1), (s[near] ** 2).sum(1) - r * r
        root = np.sqrt(np.maximum(b * b - a * c, 0.0))
        t = np.clip((-b + root) / a, 0, 1) - np.clip((-b - root) / a, 0, 1)
        e = unit[near]
        tensor = np.einsum("i,ij,ik->jk", beta[near] * t * length[near], e, e)
        touching = np.flatnonzero((np.linalg.norm(v[mesh.triangles] - v[p], axis=2) <= r).any(axis=1))
        area = sum(face_in_ball_area(ball, f, tuple(v[p]), r * r) for f in touching)
        values, vectors = np.linalg.eigh(tensor / area)
        keep = np.delete(np.arange(3), np.argmax(np.abs(vectors.T @ normals[p])))
        k1[p], k2[p] = values[keep]
    return k1, k2


@pytest.mark.parametrize("k", [1.0, 2.5])
def test_the_estimate_is_the_papers_formula(k):
    # a noisy torus: every vertex in a ball is joined to its centre inside it, so the edges csm reaches
    # from its support are all the edges with an end in the ball
    mesh = torus_grid(24, 12)[0]
    rng = np.random.default_rng(8)
    mesh = curv.Mesh(mesh.vertices + rng.normal(scale=0.01, size=mesh.vertices.shape), mesh.triangles)
    normals = vertex_normals(mesh)
    radii = ball_radii(mesh, Range(k=k), uses_normals=False)
    got, _ = _drain(iter_csm(mesh, normals, radii))
    assert (got.reason == Reason.OK).all()
    k1, k2 = _normal_cycle_in_numpy(mesh, normals, radii)
    scale = np.abs(k2).max()
    np.testing.assert_allclose(got.k1, k1, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(got.k2, k2, rtol=0, atol=1e-9 * scale)
