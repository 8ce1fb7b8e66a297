"""Closed (and tube) analytic surfaces: sphere, ellipsoid, torus, open cylinder.

Each is a level set ``F(x) = 0`` with ``F < 0`` inside, so :func:`implicit_principal` gives exact
curvature with the outward normal at any point. Off the surface, the values are those of the level
set of ``F`` through the point (for a sphere: the sphere of radius ``|p|``).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from ..core.mesh import Mesh
from ..core.result import Curvature
from .base import Param, SampledSurface, Surface
from .geometry import exact_curvature, implicit_principal
from .tessellate import geodesic_sphere, parameter_grid, sphere_frequency

__all__ = ["ImplicitSurface", "Sphere", "Ellipsoid", "Torus", "Cylinder"]


class ImplicitSurface(Surface):
    """A surface ``F = 0`` given by ``grad F`` and ``Hess F``; subclasses add the meshing."""

    closed: ClassVar[bool] = True
    default_vertices: ClassVar[int] = 2562
    positive: ClassVar[bool] = True

    def implicit_derivatives(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``grad F`` (n, 3) and ``Hess F`` (n, 3, 3) at the points."""
        raise NotImplementedError

    def exact(self, points) -> Curvature:
        """Exact curvature at points of the surface, with outward normals.

        Parameters
        ----------
        points : (n, 3) array_like
            Points on the surface.

        Returns
        -------
        Curvature
            ``k1 >= k2``, unit ``d1, d2``, outward unit ``normals``.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        k1, k2, d1, d2, normals = implicit_principal(*self.implicit_derivatives(p))
        return exact_curvature(k1, k2, d1, d2, normals, surface=self.describe())

    exact_at = exact

    def _sampled(self, vertices: np.ndarray, faces: np.ndarray, **info) -> SampledSurface:
        return SampledSurface(mesh=Mesh(vertices, faces), truth=self.exact(vertices), surface=self, info=info)

    @staticmethod
    def _regular_only(irregularity_deg: float) -> None:
        if irregularity_deg:
            raise ValueError("irregularity applies to the hexagon patches only; closed surfaces are meshed regularly")


class Sphere(ImplicitSurface):
    """Sphere of radius ``radius`` around the origin: ``k1 = k2 = 1/radius``."""

    name = "sphere"
    title = "Sphere"
    params = (Param("radius", 1.0, 0.1, 10.0, "radius"),)

    def implicit_derivatives(self, points):
        return 2.0 * points, np.broadcast_to(2.0 * np.eye(3), (points.shape[0], 3, 3))

    def project(self, points) -> np.ndarray:
        """(n, 3) points moved along the ray from the centre onto the sphere."""
        p = np.asarray(points, dtype=np.float64)
        return self.radius * p / np.linalg.norm(p, axis=1, keepdims=True)

    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> SampledSurface:
        """Geodesic sphere (subdivided icosahedron) with ``10 f^2 + 2`` vertices closest to ``n_vertices``.

        ``rng`` is accepted for a uniform interface and unused: the mesh is deterministic.
        """
        self._regular_only(irregularity_deg)
        f = sphere_frequency(self.default_vertices if n_vertices is None else n_vertices)
        v, faces = geodesic_sphere(f)
        return self._sampled(self.radius * v, faces, frequency=f)


class Ellipsoid(ImplicitSurface):
    """Ellipsoid ``x^2/a^2 + y^2/b^2 + z^2/c^2 = 1``; the mesh is a geodesic sphere scaled by (a, b, c)."""

    name = "ellipsoid"
    title = "Ellipsoid"
    params = (
        Param("a", 1.2, 0.1, 10.0, "semi-axis along x"),
        Param("b", 1.0, 0.1, 10.0, "semi-axis along y"),
        Param("c", 0.6, 0.1, 10.0, "semi-axis along z"),
    )

    def implicit_derivatives(self, points):
        inv2 = 1.0 / np.array([self.a, self.b, self.c]) ** 2
        return 2.0 * points * inv2, np.broadcast_to(np.diag(2.0 * inv2), (points.shape[0], 3, 3))

    def project(self, points) -> np.ndarray:
        """(n, 3) points moved along the ray from the centre onto the ellipsoid (exactly on it)."""
        p = np.asarray(points, dtype=np.float64)
        scale = np.sqrt(((p / np.array([self.a, self.b, self.c])) ** 2).sum(axis=1))
        return p / scale[:, None]

    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> SampledSurface:
        """Geodesic sphere of ``10 f^2 + 2`` vertices (closest to ``n_vertices``) scaled onto the ellipsoid.

        Vertices lie exactly on the surface; ``rng`` is unused.
        """
        self._regular_only(irregularity_deg)
        f = sphere_frequency(self.default_vertices if n_vertices is None else n_vertices)
        v, faces = geodesic_sphere(f)
        return self._sampled(v * np.array([self.a, self.b, self.c]), faces, frequency=f)


class Torus(ImplicitSurface):
    """Ring torus around the z axis: tube of radius ``minor`` around a circle of radius ``major``.

    With ``rho = sqrt(x^2 + y^2) = major + minor cos(v)``: ``k = 1/minor`` around the tube and
    ``cos(v) / rho`` along the big circle, so K > 0 on the outside and K < 0 on the inside.
    """

    name = "torus"
    title = "Torus"
    params = (
        Param("major", 1.0, 0.2, 10.0, "radius of the centre circle"),
        Param("minor", 0.4, 0.05, 5.0, "radius of the tube (< major)"),
    )

    def _check(self) -> None:
        if self.minor >= self.major:
            raise ValueError(f"a ring torus needs minor < major, got minor={self.minor:g}, major={self.major:g}")

    def implicit_derivatives(self, points):
        # F = (rho - R)^2 + z^2 - r^2, smooth away from the z axis (which is off the surface)
        x, y, z = points.T
        rho = np.hypot(x, y)
        radial = 1.0 - self.major / rho
        grad = 2.0 * np.stack([radial * x, radial * y, z], axis=1)
        c = 2.0 * self.major / rho**3
        hess = np.zeros((points.shape[0], 3, 3))
        hess[:, 0, 0] = 2.0 * radial + c * x * x
        hess[:, 1, 1] = 2.0 * radial + c * y * y
        hess[:, 0, 1] = hess[:, 1, 0] = c * x * y
        hess[:, 2, 2] = 2.0
        return grad, hess

    def project(self, points) -> np.ndarray:
        """(n, 3) nearest points of the torus (off the z axis): onto the tube around the centre circle."""
        p = np.asarray(points, dtype=np.float64)
        rho = np.hypot(p[:, 0], p[:, 1])
        centre = np.stack([self.major * p[:, 0] / rho, self.major * p[:, 1] / rho, np.zeros(len(p))], axis=1)
        off = p - centre
        return centre + self.minor * off / np.linalg.norm(off, axis=1, keepdims=True)

    def point(self, u, v) -> np.ndarray:
        """(n, 3) points at angles ``u`` (around z) and ``v`` (around the tube, 0 = outside equator)."""
        u, v = np.asarray(u, dtype=np.float64).reshape(-1), np.asarray(v, dtype=np.float64).reshape(-1)
        rho = self.major + self.minor * np.cos(v)
        return np.stack([rho * np.cos(u), rho * np.sin(u), self.minor * np.sin(v)], axis=1)

    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> SampledSurface:
        """Parameter grid closed in both directions, about ``n_vertices`` vertices.

        The grid is ``n_u x n_v`` with ``n_u / n_v ~ major / minor`` so that cells are roughly
        square on the centre circle; ``rng`` is unused.
        """
        self._regular_only(irregularity_deg)
        n = self.default_vertices if n_vertices is None else int(n_vertices)
        n_v = max(3, int(round(np.sqrt(n * self.minor / self.major))))
        n_u = max(3, int(round(n / n_v)))
        u, v, faces = parameter_grid(n_u, n_v, close_v=True)
        return self._sampled(self.point(2 * np.pi * u, 2 * np.pi * v), faces, n_u=n_u, n_v=n_v)


class Cylinder(ImplicitSurface):
    """Open tube ``x^2 + y^2 = radius^2``, ``|z| <= height/2``: ``k1 = 1/radius`` around, ``k2 = 0`` along z.

    The mesh has a border: the two end circles at ``z = ±height/2`` (no caps). The exact values
    there are those of the infinite cylinder.
    """

    name = "cylinder"
    title = "Cylinder"
    closed: ClassVar[bool] = False
    params = (
        Param("radius", 1.0, 0.1, 10.0, "radius"),
        Param("height", 2.0, 0.1, 20.0, "length along z"),
    )

    def implicit_derivatives(self, points):
        grad = 2.0 * points * np.array([1.0, 1.0, 0.0])
        return grad, np.broadcast_to(np.diag([2.0, 2.0, 0.0]), (points.shape[0], 3, 3))

    def project(self, points) -> np.ndarray:
        """(n, 3) nearest points of the tube: moved radially in x, y (z kept)."""
        p = np.array(points, dtype=np.float64)
        p[:, :2] *= self.radius / np.hypot(p[:, 0], p[:, 1])[:, None]
        return p

    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> SampledSurface:
        """Grid of ``n_theta`` vertices around by ``n_z`` rings, about ``n_vertices`` in all.

        Cells are roughly square; the two end rings are the border. ``rng`` is unused.
        """
        self._regular_only(irregularity_deg)
        n = self.default_vertices if n_vertices is None else int(n_vertices)
        n_theta = max(3, int(round(np.sqrt(n * 2 * np.pi * self.radius / self.height))))
        n_z = max(2, int(round(n / n_theta)))
        # u goes around, v along +z: X_u x X_v points outward
        u, v, faces = parameter_grid(n_theta, n_z, close_v=False)
        theta = 2 * np.pi * u
        vertices = np.stack(
            [self.radius * np.cos(theta), self.radius * np.sin(theta), self.height * (v - 0.5)], axis=1
        )
        return self._sampled(vertices, faces, n_theta=n_theta, n_z=n_z)
