"""Small meshes built in code for the core tests (no files, no dependence on curv.surfaces)."""

from __future__ import annotations

import numpy as np
import trimesh

import curv


def icosphere(subdivisions: int, radius: float = 1.0) -> curv.Mesh:
    """Closed outward triangle sphere."""
    tm = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return curv.Mesh(tm.vertices, tm.faces)


def torus_grid(n_major: int, n_minor: int, R: float = 2.0, r: float = 0.75, *, quads: bool = False):
    """Closed outward torus on a (major, minor) parameter grid; returns (mesh, theta, phi)."""
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    theta = 2 * np.pi * i.ravel() / n_major
    phi = 2 * np.pi * j.ravel() / n_minor
    ring = R + r * np.cos(phi)
    v = np.stack([ring * np.cos(theta), ring * np.sin(theta), r * np.sin(phi)], axis=1)
    a = (i * n_minor + j).ravel()
    b = (((i + 1) % n_major) * n_minor + j).ravel()
    c = (((i + 1) % n_major) * n_minor + (j + 1) % n_minor).ravel()
    d = (i * n_minor + (j + 1) % n_minor).ravel()
    faces = np.stack([a, b, c, d], axis=1) if quads else np.concatenate(
        [np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
    return curv.Mesh(v, faces), theta, phi


def torus_exact(theta, phi, R: float = 2.0, r: float = 0.75):
    """Exact principal curvatures (along the minor circle, along the major circle) for an outward torus."""
    k_minor = np.full_like(phi, 1.0 / r)
    k_major = np.cos(phi) / (R + r * np.cos(phi))
    return k_minor, k_major


def tube(n_around: int, n_along: int, radius: float = 1.0, height: float = 4.0, *, quads: bool = False):
    """Open cylinder along z (outward normals); returns the mesh."""
    i, j = np.meshgrid(np.arange(n_around), np.arange(n_along), indexing="ij")
    t = 2 * np.pi * i.ravel() / n_around
    # stagger alternate rows so the triangulation is close to equilateral
    v = np.stack([radius * np.cos(t), radius * np.sin(t), height * j.ravel() / (n_along - 1)], axis=1)
    ii, jj = np.meshgrid(np.arange(n_around), np.arange(n_along - 1), indexing="ij")
    a = (ii * n_along + jj).ravel()
    b = (((ii + 1) % n_around) * n_along + jj).ravel()
    c = (((ii + 1) % n_around) * n_along + jj + 1).ravel()
    d = (ii * n_along + jj + 1).ravel()
    faces = np.stack([a, b, c, d], axis=1) if quads else np.concatenate(
        [np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
    return curv.Mesh(v, faces)


def hex_plane(s: int):
    """Regular planar triangulation of the unit hexagon with s subdivisions per side (3s(s+1)+1 vertices)."""
    h = 1.0 / s
    pts = []
    for row in range(-s, s + 1):
        count = 2 * s + 1 - abs(row)
        x0 = -(count - 1) * h / 2
        pts += [(x0 + k * h, row * h * np.sqrt(3) / 2) for k in range(count)]
    pts = np.array(pts)
    from scipy.spatial import Delaunay

    tri = Delaunay(pts).simplices
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    cross = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]
    tri[cross < 0] = tri[cross < 0][:, ::-1]
    return curv.Mesh(np.column_stack([pts, np.zeros(len(pts))]), tri)


def noisy_torus(n_major: int, n_minor: int, *, scale: float = 0.03, seed: int = 0) -> curv.Mesh:
    """:func:`torus_grid` with Gaussian vertex noise of standard deviation ``scale`` (mesh units)."""
    mesh = torus_grid(n_major, n_minor)[0]
    rng = np.random.default_rng(seed)
    return curv.Mesh(mesh.vertices + rng.normal(scale=scale, size=mesh.vertices.shape), mesh.faces)


def paraboloid_patch(s: int) -> curv.Mesh:
    """The saddle-like cap z = 0.4 x² - 0.25 y² over :func:`hex_plane` (s): borders, and supports that
    reach them at the larger ranges."""
    flat = hex_plane(s)
    v = flat.vertices.copy()
    v[:, 2] = 0.4 * v[:, 0] ** 2 - 0.25 * v[:, 1] ** 2
    return curv.Mesh(v, flat.faces)
