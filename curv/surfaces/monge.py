"""Monge patches ``z = f(x, y)`` over the paper's hexagon (eq. 5.1), a saddle, and their meshing.

A patch needs only ``f``, its gradient and its Hessian; :class:`MongePatch` derives the exact
curvature from the fundamental forms (paper eq. 2.1-2.3) and lifts planar hexagon meshes. Normals
point up (+z); faces are counter-clockwise seen from above.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from ..core.mesh import Mesh
from ..core.result import Curvature
from .base import Param, SampledSurface, Surface
from .geometry import exact_curvature, monge_principal
from .hexagon import PlanarMesh, hexagon_mesh

__all__ = ["MongePatch", "QuadraticPatch", "EllipsoidPatch", "TrigonometricPatch", "Saddle", "HEXAGON_CORNERS"]

HEXAGON_CORNERS = np.stack([np.cos(np.arange(6) * np.pi / 3), np.sin(np.arange(6) * np.pi / 3)], axis=1)
"""(6, 2) corners of the unit hexagon the patches are sampled on."""


class MongePatch(Surface):
    """A height field ``z = f(x, y)`` with the upward normal ``N ∝ (-fx, -fy, 1)``.

    Subclasses implement :meth:`height`, :meth:`gradient`, :meth:`hessian` and :meth:`random`.
    With our sign convention a patch that bends up (``f`` convex) has negative curvature.
    """

    closed: ClassVar[bool] = False
    default_vertices: ClassVar[int] = 817

    def height(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``f(x, y)``; arrays of one shape in, same shape out."""
        raise NotImplementedError

    def gradient(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(fx, fy)``, each shaped like ``x``."""
        raise NotImplementedError

    def hessian(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(fxx, fxy, fyy)``, each shaped like ``x``."""
        raise NotImplementedError

    @classmethod
    def random(cls, rng=None) -> "MongePatch":
        """Parameters drawn as in the paper's §5.1: here each uniform over its :class:`Param`'s
        ``low .. high``, in declaration order; a patch whose draw differs says so."""
        g = np.random.default_rng(rng)
        return cls(*(g.uniform(p.low, p.high) for p in cls.params))

    def exact(self, x, y) -> Curvature:
        """Exact curvature at ``(x, y)``.

        Parameters
        ----------
        x, y : (n,) array_like
            Points of the parameter plane.

        Returns
        -------
        Curvature
            ``k1 >= k2``, unit ``d1, d2`` tangent to the patch, upward unit ``normals``.
        """
        x = np.asarray(x, dtype=np.float64).reshape(-1)
        y = np.asarray(y, dtype=np.float64).reshape(-1)
        k1, k2, d1, d2, normals = monge_principal(self.gradient(x, y), self.hessian(x, y))
        return exact_curvature(k1, k2, d1, d2, normals, surface=self.describe())

    def exact_at(self, points) -> Curvature:
        """Exact curvature below/above ``points`` (n, 2 or 3): only ``x, y`` are used."""
        p = np.asarray(points, dtype=np.float64)
        return self.exact(p[:, 0], p[:, 1])

    def project(self, points) -> np.ndarray:
        """(n, 3) points of the patch above/below ``points`` (n, 2 or 3): ``(x, y, f(x, y))``."""
        p = np.asarray(points, dtype=np.float64)
        return np.column_stack([p[:, 0], p[:, 1], self.height(p[:, 0], p[:, 1])])

    def sample(self, planar: PlanarMesh | Mesh) -> SampledSurface:
        """Lift a planar mesh onto the patch.

        Parameters
        ----------
        planar : PlanarMesh or Mesh
            Triangles counter-clockwise seen from +z; a :class:`Mesh` contributes its ``x, y``
            (its ``z`` is replaced).

        Returns
        -------
        SampledSurface
            Same connectivity, ``z = f(x, y)``, exact values at the vertices.
        """
        if isinstance(planar, PlanarMesh):
            xy, faces = planar.xy, planar.triangles
            irregularity = planar.irregularity_deg
            info = {
                "subdivisions": planar.subdivisions, "target_deg": planar.target_deg,
                "amplitude": planar.amplitude, **planar.info,
            }
        else:
            xy, faces = planar.vertices[:, :2], planar.faces
            irregularity, info = None, {}
        x, y = xy[:, 0], xy[:, 1]
        mesh = Mesh(np.column_stack([x, y, self.height(x, y)]), faces)
        return SampledSurface(mesh=mesh, truth=self.exact(x, y), surface=self, irregularity_deg=irregularity, info=info)

    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> SampledSurface:
        """Sample the patch on the paper's hexagon.

        Parameters
        ----------
        n_vertices : int, optional
            ``3 s (s + 1) + 1`` (217, 817, 3169, 12481 in the paper); default 817.
        irregularity_deg : float
            Target RMS angle deviation from 60° of the planar mesh (see :func:`hexagon_mesh`).
        rng : numpy.random.Generator, int or None
            Random source of the irregularity.

        Returns
        -------
        SampledSurface
        """
        n = self.default_vertices if n_vertices is None else n_vertices
        return self.sample(hexagon_mesh(n, irregularity_deg=irregularity_deg, rng=rng))


class QuadraticPatch(MongePatch):
    """``f = A x^2 + B x + C x y + D y + E y^2`` (paper eq. 5.1)."""

    name = "quadratic"
    title = "Quadratic patch"
    # the paper draws all five coefficients uniformly in [-2, 2] (§5.1, :meth:`MongePatch.random`)
    params = tuple(Param(name, default, -2.0, 2.0, doc) for name, default, doc in (
        ("A", 1.0, "x^2 coefficient"), ("B", 0.0, "x coefficient (slope)"), ("C", 0.5, "xy coefficient"),
        ("D", 0.0, "y coefficient (slope)"), ("E", -0.5, "y^2 coefficient")))

    def height(self, x, y):
        return self.A * x * x + self.B * x + self.C * x * y + self.D * y + self.E * y * y

    def gradient(self, x, y):
        return 2 * self.A * x + self.B + self.C * y, self.C * x + self.D + 2 * self.E * y

    def hessian(self, x, y):
        one = np.ones_like(x)
        return 2 * self.A * one, self.C * one, 2 * self.E * one


class EllipsoidPatch(MongePatch):
    """``f = C sqrt(1 - A^2 x^2 - B^2 y^2)`` (paper eq. 5.1): an ellipsoid cap, C > 0 bulging up.

    The radicand must stay positive on the whole hexagon; since it is concave, checking the six
    corners suffices and the constructor does so.
    """

    name = "ellipsoid_patch"
    title = "Ellipsoid patch"
    params = (
        Param("A", 0.6, -0.99, 0.99, "x semi-axis is 1/|A|"),
        Param("B", 0.4, -0.99, 0.99, "y semi-axis is 1/|B|"),
        Param("C", 2.0, -10.0, 10.0, "height (negative: hanging down)"),
    )

    def _check(self) -> None:
        reach = float(np.max((self.A * HEXAGON_CORNERS[:, 0]) ** 2 + (self.B * HEXAGON_CORNERS[:, 1]) ** 2))
        if reach >= 1.0:
            raise ValueError(
                f"EllipsoidPatch(A={self.A:g}, B={self.B:g}) is undefined on the unit hexagon: 1 - A²x² - B²y² reaches "
                f"{1 - reach:.3g} at a corner; it must stay > 0 (e.g. A² + B² < 1 with max(A², B²) < 1)"
            )

    @classmethod
    def random(cls, rng=None) -> "EllipsoidPatch":
        """A, B, C uniform in [-10, 10], then A and B divided by ``10 sqrt(2)``.

        The paper scales A and B so that ``A^2 + B^2 <= 1``. Dividing the box by ``10 sqrt(2)``
        maps it onto the largest square inside the unit disc, which keeps the uniform distribution
        and gives ``A^2, B^2 <= 1/2``: on the hexagon (inside the unit disc) the radicand is then
        ``>= 1 - max(A^2, B^2) (x^2 + y^2) >= 1/2``, so ``f`` and its curvature stay finite. (Scaling
        (A, B) onto the unit circle instead would make the radicand 0 at hexagon corners.)
        """
        a, b, c = np.random.default_rng(rng).uniform(-10.0, 10.0, 3)
        s = 1.0 / (10.0 * np.sqrt(2.0))
        return cls(a * s, b * s, c)

    def _root(self, x, y):
        return np.sqrt(1.0 - (self.A * x) ** 2 - (self.B * y) ** 2)

    def height(self, x, y):
        return self.C * self._root(x, y)

    def gradient(self, x, y):
        r = self._root(x, y)
        return -self.C * self.A**2 * x / r, -self.C * self.B**2 * y / r

    def hessian(self, x, y):
        a2, b2 = self.A**2, self.B**2
        r = self._root(x, y)
        r3 = r**3
        fxx = -self.C * a2 * (1.0 - b2 * y * y) / r3
        fyy = -self.C * b2 * (1.0 - a2 * x * x) / r3
        fxy = -self.C * a2 * b2 * x * y / r3
        return fxx, fxy, fyy


class TrigonometricPatch(MongePatch):
    """``f = sin(u^A) + cos(B y)`` with ``u = 1 + x/2`` (paper eq. 5.1, made real on the hexagon).

    The paper writes ``sin(x^A)`` with A in [1, 2], which is not real for ``x < 0`` unless A is an
    integer. ``|x|^A`` would be real but has an infinite second derivative at ``x = 0`` for
    ``1 < A < 2``; any plain shift ``u = x + c`` must have ``c > 1`` and then reaches ``u^A`` up to
    ``(1 + c)^2 > 4``, where ``sin(u^A)`` curves ~5x more than the quadratic and ellipsoid patches.
    We therefore map the hexagon's x-range [-1, 1] onto ``u`` in [1/2, 3/2]: ``u`` stays 1/2 away from
    the singular point, ``u = 1`` at the centre (where ``u^A = 1`` for every A), and the x-part's
    ``|f_xx|`` stays below 2.1, within the range of ``sin(x^2)`` on [-1, 1]; ``cos(B y)`` with B in
    [-2, 2] adds up to 4, as in the paper. Over random draws the mean of ``|k1| + |k2|`` on the
    hexagon is then ~1.0, against ~1.3 (quadratic) and ~0.9 (ellipsoid); with ``u = x + 2`` it is ~1.8.
    """

    name = "trigonometric"
    title = "Trigonometric patch"
    params = (
        # drawn over these ranges: A in [1, 2], B in [-2, 2] (paper §5.1, :meth:`MongePatch.random`)
        Param("A", 1.5, 1.0, 2.0, "exponent of sin(u^A), u = 1 + x/2"),
        Param("B", 1.0, -2.0, 2.0, "frequency of cos(B y)"),
    )
    shift: ClassVar[float] = 1.0
    scale: ClassVar[float] = 0.5

    def _u(self, x):
        return self.shift + self.scale * x

    def height(self, x, y):
        return np.sin(self._u(x) ** self.A) + np.cos(self.B * y)

    def gradient(self, x, y):
        u, a = self._u(x), self.A
        fx = self.scale * a * u ** (a - 1) * np.cos(u**a)
        return fx, -self.B * np.sin(self.B * y)

    def hessian(self, x, y):
        u, a = self._u(x), self.A
        ua = u**a
        du = a * u ** (a - 1)  # d(u^A)/du
        ddu = a * (a - 1) * u ** (a - 2)
        fxx = self.scale**2 * (ddu * np.cos(ua) - du * du * np.sin(ua))
        return fxx, np.zeros_like(fxx), -self.B**2 * np.cos(self.B * y)


class Saddle(MongePatch):
    """``f = (a x^2 - b y^2) / 2``: a saddle over the hexagon.

    At the origin (normal +z) ``k2 = -a`` along x (the patch bends up, towards the normal) and
    ``k1 = +b`` along y, for ``a, b > 0``.
    """

    name = "saddle"
    title = "Saddle"
    params = (
        Param("a", 1.0, -4.0, 4.0, "curvature -a along x at the origin"),
        Param("b", 1.0, -4.0, 4.0, "curvature +b along y at the origin"),
    )

    @classmethod
    def random(cls, rng=None) -> "Saddle":
        """a and b uniform in [0.5, 2]."""
        return cls(*np.random.default_rng(rng).uniform(0.5, 2.0, 2))

    def height(self, x, y):
        return 0.5 * (self.a * x * x - self.b * y * y)

    def gradient(self, x, y):
        return self.a * x, -self.b * y

    def hessian(self, x, y):
        one = np.ones_like(x)
        return self.a * one, 0.0 * one, -self.b * one
