"""Closed surfaces with sharp creases: a capped cylinder, a box, a hemisphere on a disc, a cone.

Each solid is convex and the intersection of the inner sides of its smooth parts (planes, a
cylinder side, a sphere, a cone side), so a point of its surface lies on the part(s) whose signed
distance is zero: on one part it has that part's exact curvature; on two or more (a crease or a
corner), or at the cone's apex, the curvature is undefined and the truth holds NaN with
``Reason.FEATURE`` (``valid`` False).

Where ``k1 = k2`` (flat parts, the sphere) every tangent direction is principal and ``d1, d2`` are an
arbitrary orthonormal tangent pair with ``d2 = N x d1``.

The meshes are closed, watertight and outward: the vertices on a crease are shared by the faces of
both sides (:mod:`.ring_mesh`), at the spacing of the smooth parts' near-regular triangles.
``info["part"]`` names each vertex's part (an index into ``info["parts"]``, -1 on a feature), and
:func:`crease_distance_rings` counts the edge rings from the nearest feature vertex.
"""

from __future__ import annotations

from abc import abstractmethod
from typing import ClassVar

import numpy as np
from scipy.sparse.csgraph import dijkstra

from ..core.mesh import Mesh
from ..core.result import Curvature
from ..core.validity import Reason
from .base import Param, SampledSurface, Surface
from .geometry import tangent_frame
from .ring_mesh import box_lattice_mesh, revolution_mesh

__all__ = [
    "CreasedSurface", "CappedCylinder", "Box", "HemisphereOnDisc", "Cone", "crease_distance_rings",
]

ON_SURFACE_TOLERANCE = 1e-9
"""A point is on a part when its distance to it is below this fraction of the solid's size."""

_EQUILATERAL_HEIGHT = np.sqrt(3.0) / 2.0


# ---------------------------------------------------------------------------------- smooth parts
class _Part:
    """One smooth piece of a solid's boundary: its signed distance (< 0 inside) and exact curvature."""

    name: str

    def signed_distance(self, p: np.ndarray) -> np.ndarray:
        """(n,) distance to the part's (extended) surface, negative on the solid's side."""
        raise NotImplementedError

    def principal(self, p: np.ndarray):
        """``k1, k2`` (n,) and ``d1, d2, normals`` (n, 3) at points of the part."""
        raise NotImplementedError

    def singular(self, p: np.ndarray, tol: float) -> np.ndarray:
        """(n,) True where the part has no curvature (the apex of a cone)."""
        return np.zeros(p.shape[0], bool)


def _arbitrary_frame(normals: np.ndarray):
    frame = tangent_frame(normals)
    return frame[:, :, 0], frame[:, :, 1]


class _Plane(_Part):
    def __init__(self, name: str, normal, offset: float):
        self.name, self.normal, self.offset = name, np.asarray(normal, dtype=np.float64), float(offset)

    def signed_distance(self, p):
        return p @ self.normal - self.offset

    def principal(self, p):
        normals = np.broadcast_to(self.normal, p.shape).copy()
        zero = np.zeros(p.shape[0])
        return (zero, zero.copy(), *_arbitrary_frame(normals), normals)


def _around_z(p: np.ndarray):
    """Distance to the z axis (n,), radial and angular unit vectors (n, 3)."""
    rho = np.hypot(p[:, 0], p[:, 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        radial = np.stack([p[:, 0] / rho, p[:, 1] / rho, np.zeros_like(rho)], axis=1)
    angular = np.stack([-radial[:, 1], radial[:, 0], np.zeros_like(rho)], axis=1)
    return rho, radial, angular


class _CylinderSide(_Part):
    """``rho = radius``: ``k1 = 1/radius`` around (``d1``), ``k2 = 0`` along +z (``d2``)."""

    name = "side"

    def __init__(self, radius: float):
        self.radius = radius

    def signed_distance(self, p):
        return np.hypot(p[:, 0], p[:, 1]) - self.radius

    def principal(self, p):
        _, radial, angular = _around_z(p)
        n = p.shape[0]
        return np.full(n, 1.0 / self.radius), np.zeros(n), angular, np.cross(radial, angular), radial


class _SphereCap(_Part):
    """The sphere of radius ``radius`` around the origin: ``k1 = k2 = 1/radius``."""

    name = "sphere"

    def __init__(self, radius: float):
        self.radius = radius

    def signed_distance(self, p):
        return np.linalg.norm(p, axis=1) - self.radius

    def principal(self, p):
        normals = p / np.linalg.norm(p, axis=1, keepdims=True)
        k = np.full(p.shape[0], 1.0 / self.radius)
        return (k, k.copy(), *_arbitrary_frame(normals), normals)


class _ConeSide(_Part):
    """Cone with apex ``(0, 0, height)`` over the circle ``rho = radius`` at ``z = 0``.

    With the half-angle ``alpha = atan(radius / height)``, the outward normal is
    ``cos(alpha) e_rho + sin(alpha) e_z``; along a generator (a straight line) the normal curvature
    is 0, and around, the parallel circle of radius ``rho`` has curvature ``1/rho`` towards the axis,
    of which the normal takes ``cos(alpha)``: ``k1 = cos(alpha) / rho`` with ``d1 = e_theta``.
    """

    name = "side"

    def __init__(self, radius: float, height: float):
        self.height = height
        self.alpha = np.arctan2(radius, height)

    def signed_distance(self, p):
        # distance to the generator line in the (rho, z) half-plane
        return np.hypot(p[:, 0], p[:, 1]) * np.cos(self.alpha) + (p[:, 2] - self.height) * np.sin(self.alpha)

    def principal(self, p):
        rho, radial, angular = _around_z(p)
        normals = np.cos(self.alpha) * radial + np.sin(self.alpha) * np.array([0.0, 0.0, 1.0])
        return np.cos(self.alpha) / rho, np.zeros_like(rho), angular, np.cross(normals, angular), normals

    def singular(self, p, tol):
        return np.hypot(p[:, 0], p[:, 1]) <= tol


# ---------------------------------------------------------------------------------- surfaces
class CreasedSurface(Surface):
    """A convex solid bounded by smooth parts that meet at sharp creases; subclasses add the meshing."""

    closed: ClassVar[bool] = True
    default_vertices: ClassVar[int] = 2562
    positive: ClassVar[bool] = True

    @property
    @abstractmethod
    def parts(self) -> tuple[_Part, ...]:
        """The smooth parts of the boundary, in the order of ``info["parts"]``."""

    @property
    @abstractmethod
    def size(self) -> float:
        """The solid's largest dimension (the scale of the on-surface tolerance)."""

    @property
    @abstractmethod
    def area(self) -> float:
        """Surface area (to turn a vertex count into an edge length)."""

    def part_membership(self, points) -> np.ndarray:
        """Which smooth parts each point lies on (two or more on a crease, three at a box corner).

        Parameters
        ----------
        points : (n, 3) array_like
            Points of the solid's boundary.

        Returns
        -------
        (n, len(parts)) bool

        Raises
        ------
        ValueError
            A point is not on the surface.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        tol = ON_SURFACE_TOLERANCE * self.size
        distance = np.stack([part.signed_distance(p) for part in self.parts], axis=1)
        outside = np.abs(distance.max(axis=1, initial=-np.inf))
        if np.any(outside > tol):
            raise ValueError(
                f"points must lie on the {self.title.lower()}; {int((outside > tol).sum())} are off it "
                f"(farthest {outside.max():.3g} away)")
        return np.abs(distance) <= tol

    def part_of(self, points) -> np.ndarray:
        """(n,) int64: the index into :attr:`parts` of each point's part; -1 on a crease, a corner or an apex.

        ``points`` and the ``ValueError`` as in :meth:`part_membership`.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        on = self.part_membership(p)
        part = np.argmax(on, axis=1)
        singular = np.zeros(p.shape[0], bool)
        tol = ON_SURFACE_TOLERANCE * self.size
        for index, smooth in enumerate(self.parts):
            singular |= (part == index) & smooth.singular(p, tol)
        return np.where((on.sum(axis=1) > 1) | singular, -1, part)

    def crease_edges(self, mesh: Mesh) -> np.ndarray:
        """(e,) bool: edges of a mesh of this surface that run along a crease (both ends on the same two parts)."""
        on = self.part_membership(mesh.vertices)
        return (on[mesh.edges[:, 0]] & on[mesh.edges[:, 1]]).sum(axis=1) >= 2

    def exact_at(self, points) -> Curvature:
        """Exact curvature at points of the surface; NaN and ``Reason.FEATURE`` on creases, corners, apex.

        Parameters
        ----------
        points : (n, 3) array_like
            Points on the surface (``ValueError`` otherwise).

        Returns
        -------
        Curvature
            ``method="exact"``; ``k1 >= k2``, unit ``d1, d2`` and outward ``normals`` on the smooth
            parts, NaN with ``valid`` False on the features.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        part = self.part_of(p)
        n = p.shape[0]
        k1, k2 = np.full(n, np.nan), np.full(n, np.nan)
        d1, d2, normals = (np.full((n, 3), np.nan) for _ in range(3))
        for index, smooth in enumerate(self.parts):
            at = part == index
            k1[at], k2[at], d1[at], d2[at], normals[at] = smooth.principal(p[at])
        valid = part >= 0
        return Curvature(
            k1=k1, k2=k2, d1=d1, d2=d2, normals=normals, valid=valid,
            reason=np.where(valid, Reason.OK, Reason.FEATURE).astype(np.uint8),
            method="exact", range=None, info={"surface": self.describe()},
        )

    def edge_length(self, n_vertices: int | None) -> float:
        """The edge length of near-regular triangles that cover the surface with about ``n_vertices``."""
        n = self.default_vertices if n_vertices is None else int(n_vertices)
        if n < 8:
            raise ValueError(f"n_vertices must be >= 8, got {n_vertices}")
        return float(np.sqrt(self.area / (_EQUILATERAL_HEIGHT * n)))

    def _sampled(self, vertices: np.ndarray, faces: np.ndarray, irregularity_deg: float, **info) -> SampledSurface:
        if irregularity_deg:
            raise ValueError("irregularity applies to the hexagon patches only; creased surfaces are meshed regularly")
        truth = self.exact_at(vertices)
        part = self.part_of(vertices)
        info = {**info, "part": part, "parts": tuple(p.name for p in self.parts)}
        return SampledSurface(mesh=Mesh(vertices, faces), truth=truth, surface=self, info=info)


class _RevolutionSolid(CreasedSurface):
    """A creased solid of revolution around z, meshed ring by ring along its profile."""

    def _ring_counts(self, rho: np.ndarray, rim_count: int) -> np.ndarray:
        """Vertices per ring: the rim's count scaled by radius, a pole on the axis."""
        counts = np.maximum(3, np.rint(rim_count * rho / self.radius)).astype(np.int64)
        return np.where(rho <= ON_SURFACE_TOLERANCE * self.size, 1, counts)

    @staticmethod
    def _spacing(length: float, h: float) -> np.ndarray:
        """Fractions 0..1 of a profile segment of ``length``, rings a triangle height apart."""
        steps = max(1, int(round(length / (_EQUILATERAL_HEIGHT * h))))
        return np.linspace(0.0, 1.0, steps + 1)

    def _disc(self, z: float, h: float, outward: bool):
        """Rings of the flat disc ``rho <= radius`` at height ``z``, from the centre (or to it)."""
        t = self._spacing(self.radius, h)
        t = t if outward else t[::-1]
        return self.radius * t, np.full(t.size, z)

    def _mesh_profile(self, segments, h: float, irregularity_deg: float) -> SampledSurface:
        """Join profile segments ``(rho, z)`` that share their end rings, and mesh them."""
        rho = np.concatenate([segments[0][0]] + [s[0][1:] for s in segments[1:]])
        z = np.concatenate([segments[0][1]] + [s[1][1:] for s in segments[1:]])
        rim = max(3, int(round(2 * np.pi * self.radius / h)))
        vertices, faces = revolution_mesh(rho, z, self._ring_counts(rho, rim))
        return self._sampled(vertices, faces, irregularity_deg, rim_vertices=rim, rings=rho.size)


class CappedCylinder(_RevolutionSolid):
    """Cylinder ``rho <= radius``, ``|z| <= height/2``, closed by two flat discs (90° rims).

    Side: ``k1 = 1/radius`` around (``d1``), ``k2 = 0`` along z (``d2``); caps: 0, 0.
    """

    name = "capped_cylinder"
    title = "Capped cylinder"
    params = (
        Param("radius", 1.0, 0.1, 10.0, "radius"),
        Param("height", 2.0, 0.1, 20.0, "length along z"),
    )

    @property
    def parts(self):
        half = 0.5 * self.height
        return (_Plane("bottom", (0, 0, -1), half), _CylinderSide(self.radius), _Plane("top", (0, 0, 1), half))

    @property
    def size(self):
        return max(2 * self.radius, self.height)

    @property
    def area(self):
        return 2 * np.pi * self.radius * (self.radius + self.height)

    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> SampledSurface:
        """Rings from the bottom centre over the rim, up the side and over the top; about ``n_vertices``.

        ``rng`` is unused: the mesh is deterministic.
        """
        h = self.edge_length(n_vertices)
        half = 0.5 * self.height
        t = self._spacing(self.height, h)
        side = (np.full(t.size, self.radius), -half + self.height * t)
        segments = [self._disc(-half, h, outward=True), side, self._disc(half, h, outward=False)]
        return self._mesh_profile(segments, h, irregularity_deg)


class HemisphereOnDisc(_RevolutionSolid):
    """Upper half of the ball of radius ``radius`` around the origin: a dome on the flat disc ``z = 0``.

    Dome: ``k1 = k2 = 1/radius``; disc: 0, 0; the rim meets at 90°.
    """

    name = "hemisphere"
    title = "Hemisphere on a disc"
    params = (Param("radius", 1.0, 0.1, 10.0, "radius"),)


    @property
    def parts(self):
        return (_Plane("disc", (0, 0, -1), 0.0), _SphereCap(self.radius))

    @property
    def size(self):
        return 2 * self.radius

    @property
    def area(self):
        return 3 * np.pi * self.radius**2

    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> SampledSurface:
        """Rings from the disc's centre out to the rim, then up the dome to its pole; about ``n_vertices``.

        ``rng`` is unused.
        """
        h = self.edge_length(n_vertices)
        elevation = 0.5 * np.pi * self._spacing(0.5 * np.pi * self.radius, h)
        dome = (self.radius * np.cos(elevation), self.radius * np.sin(elevation))
        dome[0][-1] = 0.0  # the pole, exactly on the axis
        return self._mesh_profile([self._disc(0.0, h, outward=True), dome], h, irregularity_deg)


class Cone(_RevolutionSolid):
    """Solid cone: apex ``(0, 0, height)`` over the disc ``rho <= radius`` at ``z = 0``.

    With the half-angle ``alpha = atan(radius / height)``, the side has ``k1 = cos(alpha) / rho``
    around (``d1``) at distance ``rho`` from the axis and ``k2 = 0`` along the generator; the base
    has 0, 0. The base rim (a crease of ``90° + alpha`` between the normals) and the apex are features.
    """

    name = "cone"
    title = "Cone"
    params = (Param("radius", 1.0, 0.1, 10.0, "radius of the base"),
              Param("height", 1.5, 0.1, 20.0, "height of the apex over the base"))

    @property
    def half_angle(self) -> float:
        """``alpha = atan(radius / height)`` in radians: between the axis and a generator."""
        return float(np.arctan2(self.radius, self.height))

    @property
    def parts(self):
        return (_Plane("base", (0, 0, -1), 0.0), _ConeSide(self.radius, self.height))

    @property
    def size(self):
        return max(2 * self.radius, self.height)

    @property
    def area(self):
        return np.pi * self.radius * (self.radius + np.hypot(self.radius, self.height))

    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> SampledSurface:
        """Rings from the base's centre out to the rim, then up the side to the apex; about ``n_vertices``.

        ``rng`` is unused.
        """
        h = self.edge_length(n_vertices)
        t = self._spacing(np.hypot(self.radius, self.height), h)
        side = (self.radius * (1.0 - t), self.height * t)
        return self._mesh_profile([self._disc(0.0, h, outward=True), side], h, irregularity_deg)


class Box(CreasedSurface):
    """Box ``|x| <= size_x/2``, ``|y| <= size_y/2``, ``|z| <= size_z/2``: six flat faces, 0, 0 on each.

    Its 12 edges (90° creases) and 8 corners are features.
    """

    name = "box"
    title = "Box"
    params = tuple(Param(f"size_{axis}", side, 0.1, 10.0, f"length along {axis}")
                   for axis, side in zip("xyz", (2.0, 1.5, 1.0)))

    @property
    def sizes(self) -> np.ndarray:
        return np.array([self.size_x, self.size_y, self.size_z])

    @property
    def parts(self):
        return tuple(
            _Plane(f"{'-+'[side]}{'xyz'[axis]}", np.eye(3)[axis] * (2 * side - 1), 0.5 * self.sizes[axis])
            for axis in range(3) for side in (0, 1)
        )

    @property
    def size(self):
        return float(self.sizes.max())

    @property
    def area(self):
        x, y, z = self.sizes
        return 2 * (x * y + y * z + z * x)

    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> SampledSurface:
        """A square grid on each face (each square in two right triangles), about ``n_vertices`` in all.

        The squares' side is the one that gives about ``n_vertices`` (``area / side^2``), rounded per
        axis so that the edges are cut evenly. ``rng`` is unused.
        """
        n = self.default_vertices if n_vertices is None else int(n_vertices)
        side = _EQUILATERAL_HEIGHT ** 0.5 * self.edge_length(n)  # area / side^2 = n
        cells = np.maximum(1, np.rint(self.sizes / side)).astype(np.int64)
        lattice, faces = box_lattice_mesh(cells)
        vertices = self.sizes * (lattice / cells - 0.5)
        return self._sampled(vertices, faces, irregularity_deg, cells=tuple(int(c) for c in cells))


def crease_distance_rings(mesh: Mesh, feature_vertices) -> np.ndarray:
    """Edge rings from each vertex to the nearest feature vertex (breadth-first over the mesh's edges).

    Parameters
    ----------
    mesh : Mesh
    feature_vertices : (n,) bool
        The vertices on creases, corners or apices (e.g. ``~sampled.truth.valid``).

    Returns
    -------
    (n,) int64
        0 on a feature vertex, 1 on its neighbours, ...; -1 where no feature vertex is reachable.
    """
    features = np.flatnonzero(np.asarray(feature_vertices, dtype=bool))
    if features.size == 0:
        return np.full(mesh.n_vertices, -1, dtype=np.int64)
    rings = dijkstra(mesh.adjacency, directed=False, indices=features, unweighted=True, min_only=True)
    return np.where(np.isfinite(rings), rings, -1).astype(np.int64)
