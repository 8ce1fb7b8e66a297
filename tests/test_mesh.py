import numpy as np
import pytest

import curv
from tests.meshes import hex_plane, icosphere, torus_grid

SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)


@pytest.mark.parametrize(
    "vertices, faces, message",
    [
        (np.zeros((0, 3)), [[0, 1, 2]], "no vertices"),
        (SQUARE, np.zeros((0, 3), int), "no faces"),
        (np.zeros((4, 2)), [[0, 1, 2]], "shape (n, 3)"),
        (np.vstack([SQUARE] * 5)[:18].copy(), [[0, 1, 2]], None),
        (SQUARE, [[0, 1, 7]], "face 0 refers to vertex 7, but the mesh has only 4 vertices"),
        (SQUARE, [[0, 1, 2], [0, -3, 2]], "face 1 has a negative vertex index -3"),
        (SQUARE, [[0, 1]], "face 0 has 2 vertices"),
        (SQUARE, [[0, 1.5, 2]], "non-integer"),
    ],
)
def test_construction_errors_say_what_and_where(vertices, faces, message):
    if message is None:
        v = vertices
        v[17] = [0, np.nan, 0]
        with pytest.raises(curv.MeshError, match="vertex 17 has a NaN coordinate"):
            curv.Mesh(v, faces)
        return
    with pytest.raises(curv.MeshError) as err:
        curv.Mesh(vertices, faces)
    assert message in str(err.value)
    assert isinstance(err.value, ValueError)


def test_infinite_coordinate_named():
    v = SQUARE.copy()
    v[2, 0] = np.inf
    with pytest.raises(curv.MeshError, match="vertex 2 has an infinite coordinate"):
        curv.Mesh(v, [[0, 1, 2]])


def test_square_connectivity():
    m = curv.Mesh(SQUARE, [[0, 1, 2], [0, 2, 3]])
    assert m.edges.tolist() == [[0, 1], [0, 2], [0, 3], [1, 2], [2, 3]]
    assert m.edge_face_count.tolist() == [1, 2, 1, 1, 1]
    assert m.border_vertices.all()
    assert m.adjacency.toarray().sum(axis=1).tolist() == [3, 2, 3, 2]
    np.testing.assert_allclose(m.longest_edge, [np.sqrt(2), 1, np.sqrt(2), 1])
    np.testing.assert_allclose(m.face_areas, [0.5, 0.5])
    np.testing.assert_allclose(m.face_normals, [[0, 0, 1], [0, 0, 1]])
    # slot 0 of edge_faces is the face in which the edge runs low -> high: edge (0, 2) runs 2->0 in face 0
    assert m.edge_faces[1].tolist() == [1, 0]


def test_polygons_padded_and_mixed():
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [0, 1, 0], [1, 2, 0]], float)
    polys = [[0, 1, 4, 5], [1, 2, 3, 4], [5, 4, 6]]
    m = curv.Mesh(v, polys)
    assert m.face_sizes.tolist() == [4, 4, 3]
    assert not m.is_triangular
    padded = curv.Mesh(v, m.faces)
    assert padded.face_sizes.tolist() == [4, 4, 3]
    assert m.faces[2].tolist() == [5, 4, 6, -1]
    np.testing.assert_allclose(m.face_areas, [1, 1, 0.5])
    with pytest.raises(curv.MeshError, match=r"needs a triangle mesh.*\[4\]"):
        m.triangles
    assert m.report().polygon_kinds == {3: 1, 4: 2}


def test_polygon_geometry_is_newells_and_flags_every_degenerate_polygon():
    rng = np.random.default_rng(3)
    v = rng.normal(size=(40, 3))
    v[30:34] = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]  # on a line: a zero-area quad
    polys = [list(rng.choice(30, size=k, replace=False)) for k in rng.integers(3, 8, size=60)]
    polys += [[30, 31, 32, 33], [0, 1, 0, 2], [3, 4, 5, 6, 4], [7, 7, 8, 9]]  # zero area, repeated indices
    m = curv.Mesh(v, polys)
    assert not m.is_triangular
    # Newell's sum, corner by corner in the face's order (the kernel's order: equal to the last bit)
    want = np.array([0.5 * np.sum([np.cross(v[p[c]], v[p[(c + 1) % len(p)]]) for c in range(len(p))], axis=0)
                     for p in polys])
    want_area = np.linalg.norm(want, axis=1)
    np.testing.assert_allclose(m.face_vector_areas, want, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(m.face_areas, want_area, rtol=1e-13, atol=1e-15)
    longest2 = np.array([max(np.sum((v[p[(c + 1) % len(p)]] - v[p[c]]) ** 2) for c in range(len(p))) for p in polys])
    repeated = np.array([len(set(p)) < len(p) for p in polys])
    assert m.degenerate_faces.tolist() == (repeated | (want_area <= 1e-12 * longest2)).tolist()
    assert m.degenerate_faces[-4:].tolist() == [True] * 4 and not m.degenerate_faces[:-4].any()


def test_defects_detected_not_fatal():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [3, 0, 0], [9, 9, 9],
                  [-1, 0, 0], [0, -1, 0]], float)
    # face 1 is collinear (zero area), face 2 repeats an index; vertex 5 is isolated;
    # faces 0 and 3 touch only at vertex 0 (bow tie)
    m = curv.Mesh(v, [[0, 1, 2], [1, 3, 4], [0, 0, 1], [0, 6, 7]])
    assert m.degenerate_faces.tolist() == [False, True, True, False]
    assert m.isolated_vertices.tolist() == [False] * 5 + [True, False, False]
    assert m.nonmanifold_vertices[0]
    rep = m.report()
    assert rep.degenerate_faces == 2 and rep.isolated_vertices == 1 and rep.nonmanifold_vertices >= 1
    assert any("isolated" in line for line in rep.lines())


def test_nonmanifold_edge_and_border_loops():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
    m = curv.Mesh(v, [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    assert m.nonmanifold_edges.sum() == 1
    assert m.border_vertices[[0, 1]].all()
    torus, _, _ = torus_grid(12, 8)
    rep = torus.report()
    assert rep.border_edges == 0 and rep.components == 1
    assert torus.report().lines()[2] == "closed (no border)"
    plane = hex_plane(4)
    assert plane.report().border_loops == 1
    assert plane.border_vertices.sum() == 6 * 4


def test_flipped_reverses_normals_and_keeps_data():
    m = icosphere(2)
    f = m.flipped()
    np.testing.assert_allclose(f.face_normals, -m.face_normals)
    assert f.n_vertices == m.n_vertices and np.array_equal(f.edges, m.edges)


def test_with_vertices_keeps_connectivity_and_validates():
    m = icosphere(1)
    m2 = m.with_vertices(2 * m.vertices)
    np.testing.assert_allclose(m2.longest_edge, 2 * m.longest_edge)
    with pytest.raises(curv.MeshError, match="expected 42 vertices"):
        m.with_vertices(m.vertices[:-1])


def test_arrays_are_read_only():
    m = icosphere(1)
    with pytest.raises(ValueError):
        m.vertices[0, 0] = 1.0
