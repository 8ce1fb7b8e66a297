"""Small meshes with creases whose dihedral angles are known exactly (for the feature tests)."""

from __future__ import annotations

import numpy as np

import curv


def grid_faces(nu: int, nv: int) -> np.ndarray:
    """(2 (nu-1)(nv-1), 3) triangles of an nu x nv grid of vertices numbered ``i * nv + j``."""
    i, j = np.meshgrid(np.arange(nu - 1), np.arange(nv - 1), indexing="ij")
    a = (i * nv + j).ravel()
    b, c, d = a + nv, a + nv + 1, a + 1
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def folded_strip(angle_deg: float, n: int = 9, curvature: float = 0.0):
    """A strip over x in [-1, 1], y in [-1, 1] folded along x = 0 by ``angle_deg``.

    The half x <= 0 is the sheet z = curvature y^2 / 2; the half x >= 0 is the same sheet rotated
    about the y axis, so the dihedral angle along the fold is exactly ``angle_deg`` (for
    ``curvature=0``) and every point away from the fold has k1 = curvature / (1 + (curvature y)^2)^1.5
    about the y direction. ``n`` (odd) vertices per unit. Returns ``(mesh, fold vertices (n,) bool)``.
    """
    xs = np.linspace(-1.0, 1.0, 2 * n - 1)
    ys = np.linspace(-1.0, 1.0, 2 * n - 1)
    x, y = np.meshgrid(xs, ys, indexing="ij")
    z = 0.5 * curvature * y**2
    t = np.radians(angle_deg)
    right = x > 0
    # rotate the right half about the y axis: (x, z) -> (x cos t - z sin t... ) keeping x = 0 fixed
    xr = x * np.cos(t) + z * np.sin(t)
    zr = -x * np.sin(t) + z * np.cos(t)
    pts = np.stack([np.where(right, xr, x), y, np.where(right, zr, z)], -1).reshape(-1, 3)
    mesh = curv.Mesh(pts, grid_faces(xs.size, ys.size))
    return mesh, np.isclose(x, 0.0).ravel()


def box(n: int = 4, size: float = 1.0) -> curv.Mesh:
    """The surface of the cube [0, size]^3, each face an n x n grid of squares cut in two, outward."""
    s = np.linspace(0.0, size, n + 1)
    u, v = np.meshgrid(s, s, indexing="ij")
    u, v = u.ravel(), v.ravel()
    zero, full = np.zeros_like(u), np.full_like(u, size)
    tri = grid_faces(n + 1, n + 1)
    sheets = [  # (points, flip) for the six faces; flip so that every face's normal points outward
        (np.stack([u, v, zero], 1), True), (np.stack([u, v, full], 1), False),
        (np.stack([u, zero, v], 1), False), (np.stack([u, full, v], 1), True),
        (np.stack([zero, u, v], 1), True), (np.stack([full, u, v], 1), False),
    ]
    points, faces = [], []
    for k, (p, flip) in enumerate(sheets):
        faces.append((tri[:, ::-1] if flip else tri) + k * p.shape[0])
        points.append(p)
    points = np.concatenate(points)
    faces = np.concatenate(faces)
    # merge the shared edge vertices
    keys = np.round(points / size * n).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return curv.Mesh(points[first], inverse.ravel()[faces])


def mirrored_sheet(alpha_deg: float = 30.0, n: int = 9, curvature: float = 0.8):
    """The sheet z = curvature y^2 / 2 cut by a plane P through the y axis and mirrored across it.

    P is the plane ``x cos(alpha) + z sin(alpha) = 0``; the sheet's part on the side x < 0 and its
    mirror image meet along the curve sheet ∩ P, a crease of dihedral angle about ``2 alpha``. Both
    sides are exact copies of the sheet, so ``|H| = curvature / (2 (1 + (curvature y)^2)^1.5)`` at
    every vertex off the crease. ``n`` vertices per unit. Returns ``(mesh, ring (n,) int)``: the
    number of grid columns between each vertex and the crease (0 on it).
    """
    t = np.radians(alpha_deg)
    ys = np.linspace(-1.0, 1.0, 2 * n - 1)
    s = np.linspace(-1.0, 0.0, n)
    sv, y = np.meshgrid(s, ys, indexing="ij")
    z = 0.5 * curvature * y**2
    x = sv - z * np.tan(t)  # the last column lies on P
    left = np.stack([x, y, z], -1)
    normal = np.array([np.cos(t), 0.0, np.sin(t)])
    mirrored = left - 2.0 * (left @ normal)[..., None] * normal
    pts = np.concatenate([left, mirrored[-2::-1]]).reshape(-1, 3)
    columns = 2 * n - 1
    ring = np.repeat(np.abs(np.arange(columns) - (n - 1)), ys.size)
    return curv.Mesh(pts, grid_faces(columns, ys.size)), ring
