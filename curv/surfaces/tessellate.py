"""Triangulations of the closed surfaces: geodesic spheres and periodic parameter grids."""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

__all__ = ["geodesic_sphere", "sphere_frequency", "parameter_grid"]


def _icosahedron() -> tuple[np.ndarray, np.ndarray]:
    """Unit icosahedron: (12, 3) vertices, (20, 3) outward counter-clockwise faces."""
    phi = (1.0 + np.sqrt(5.0)) / 2.0
    base = []
    for a in (-1.0, 1.0):
        for b in (-phi, phi):
            base += [(0.0, a, b), (a, b, 0.0), (b, 0.0, a)]
    v = np.array(base)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    f = ConvexHull(v).simplices.astype(np.int64)
    return v, _orient_outward(v, f)


def _orient_outward(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Flip the faces of a star-shaped (around the origin) mesh whose normal points inwards."""
    p = v[f]
    inward = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p.sum(axis=1)) < 0
    f = f.copy()
    f[inward] = f[inward][:, [0, 2, 1]]
    return f


def sphere_frequency(n_vertices: int) -> int:
    """The geodesic frequency ``f`` whose sphere (``10 f^2 + 2`` vertices) is closest to ``n_vertices``."""
    return max(1, int(round(np.sqrt(max(n_vertices - 2, 0) / 10.0))))


def geodesic_sphere(frequency: int) -> tuple[np.ndarray, np.ndarray]:
    """A unit sphere from an icosahedron whose faces are split into ``frequency^2`` triangles.

    Parameters
    ----------
    frequency : int
        Edges along each icosahedron edge, >= 1.

    Returns
    -------
    vertices : (10 f^2 + 2, 3) float64
        Unit vectors.
    faces : (20 f^2, 3) int64
        Counter-clockwise seen from outside.
    """
    f = int(frequency)
    if f < 1:
        raise ValueError(f"frequency must be >= 1, got {frequency}")
    ico, faces = _icosahedron()
    i, j = np.meshgrid(np.arange(f + 1), np.arange(f + 1), indexing="ij")
    keep = i + j <= f
    i, j = i[keep], j[keep]
    local = np.full((f + 1, f + 1), -1, dtype=np.int64)
    local[i, j] = np.arange(i.size)
    k = f - i - j
    # Integer barycentric weights over the 12 icosahedron vertices name each point exactly, so
    # points on shared edges and corners merge without any floating-point tolerance.
    weights = np.zeros((faces.shape[0], i.size, 12), dtype=np.int64)
    rows, points = np.arange(faces.shape[0])[:, None], np.arange(i.size)[None, :]
    for corner, w in enumerate((k, i, j)):
        weights[rows, points, faces[:, corner : corner + 1]] = w[None, :]
    weights = weights.reshape(-1, 12)
    unique, index = np.unique(weights, axis=0, return_inverse=True)
    index = index.reshape(faces.shape[0], -1)
    vertices = unique @ ico
    vertices /= np.linalg.norm(vertices, axis=1, keepdims=True)
    # sub-triangles of one face, in its (i, j) lattice; both kinds are counter-clockwise like the face
    a, b = np.meshgrid(np.arange(f), np.arange(f), indexing="ij")
    up = a + b <= f - 1
    down = a + b <= f - 2
    tri = np.concatenate([
        np.stack([local[a[up], b[up]], local[a[up] + 1, b[up]], local[a[up], b[up] + 1]], axis=1),
        np.stack([local[a[down] + 1, b[down]], local[a[down] + 1, b[down] + 1], local[a[down], b[down] + 1]], axis=1),
    ])
    return vertices, index[:, tri].reshape(-1, 3)


def parameter_grid(n_u: int, n_v: int, *, close_v: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangles of a grid periodic in u (and in v when ``close_v``).

    Vertex ``(a, b)`` has index ``a * n_v + b``. Each cell ``(a, b) -> (a+1, b+1)`` gives two
    triangles counter-clockwise in the (u, v) plane, so the mesh is oriented along
    ``X_u x X_v``.

    Parameters
    ----------
    n_u, n_v : int
        Vertices along u (>= 3) and along v (>= 3 when closed, >= 2 otherwise).
    close_v : bool
        Wrap around in v too (a torus) or not (a tube with two border loops).

    Returns
    -------
    u : (n_u * n_v,) float64
        Parameter in [0, 1) along u.
    v : (n_u * n_v,) float64
        Parameter in [0, 1) (closed) or [0, 1] (open) along v.
    faces : (2 * n_u * cells_v, 3) int64
    """
    a, b = np.meshgrid(np.arange(n_u), np.arange(n_v), indexing="ij")
    u = (a / n_u).ravel()
    v = (b / n_v if close_v else b / (n_v - 1)).ravel()
    cells_v = n_v if close_v else n_v - 1
    a, b = np.meshgrid(np.arange(n_u), np.arange(cells_v), indexing="ij")
    a, b = a.ravel(), b.ravel()
    a1, b1 = (a + 1) % n_u, (b + 1) % n_v
    p00, p10, p11, p01 = a * n_v + b, a1 * n_v + b, a1 * n_v + b1, a * n_v + b1
    faces = np.concatenate([np.stack([p00, p10, p11], 1), np.stack([p00, p11, p01], 1)])
    return u, v, faces
