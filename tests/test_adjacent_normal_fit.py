"""an (the adjacent-normal cubic fit) on a surface it models exactly: a cubic height field over a
flat hexagon grid (jittered, so that no odd moment of the offsets cancels), with the surface's own normals. At the vertex above the origin the field is a
cubic in that vertex's tangent frame, so every height and slope equation holds exactly and the fit
must return the exact curvatures; any wrong entry of its normal equations or of its solve moves them."""

import numpy as np
import pytest

import curv
from meshes import hex_plane

A, B, C, D, E, F, G = 0.8, 0.3, -0.5, 0.2, -0.35, 0.15, 0.25
"""w = A/2 x² + B xy + C/2 y² + D x³ + E x²y + F xy² + G y³ (the seven unknowns of an)."""


def _cubic_patch(s: int):
    flat = hex_plane(s)
    v = flat.vertices.copy()
    moved = np.linalg.norm(v[:, :2], axis=1) > 1e-12  # the vertex at the origin stays
    v[moved, :2] += np.random.default_rng(0).uniform(-0.2 / s, 0.2 / s, (int(moved.sum()), 2))
    x, y = v[:, 0], v[:, 1]
    v[:, 2] = (0.5 * A * x * x + B * x * y + 0.5 * C * y * y
               + D * x ** 3 + E * x * x * y + F * x * y * y + G * y ** 3)
    zx = A * x + B * y + 3 * D * x * x + 2 * E * x * y + F * y * y
    zy = B * x + C * y + E * x * x + 2 * F * x * y + 3 * G * y * y
    normals = np.column_stack([-zx, -zy, np.ones_like(x)])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return curv.Mesh(v, flat.faces), normals


@pytest.mark.parametrize("rng", [2, 3, 4])
@pytest.mark.parametrize("standard_errors", [True, False])
def test_an_is_exact_on_a_cubic_height_field(rng, standard_errors):
    mesh, normals = _cubic_patch(8)
    centre = int(np.argmin(np.linalg.norm(mesh.vertices[:, :2], axis=1)))
    assert np.linalg.norm(mesh.vertices[centre]) < 1e-12
    res = curv.estimate(mesh, "an", rng, normals=normals, standard_errors=standard_errors)
    # the height along the normal +z has Hessian [[A, B], [B, C]] at the origin; W is its negative
    exact = np.sort(np.linalg.eigvalsh(-np.array([[A, B], [B, C]])))[::-1]
    assert res.reason[centre] == curv.Reason.OK
    assert np.allclose([res.k1[centre], res.k2[centre]], exact, rtol=0, atol=1e-9)


def test_an_ranges_in_one_walk_are_exact_on_a_cubic_height_field():
    """The ranges' shared walk (heights and slopes summed apart, one solve per level) too."""
    mesh, normals = _cubic_patch(8)
    centre = int(np.argmin(np.linalg.norm(mesh.vertices[:, :2], axis=1)))
    exact = np.sort(np.linalg.eigvalsh(-np.array([[A, B], [B, C]])))[::-1]
    for res in curv.estimate_ranges(mesh, "an", (2, 3, 4), normals=normals, standard_errors=False):
        assert np.allclose([res.k1[centre], res.k2[centre]], exact, rtol=0, atol=1e-9)
