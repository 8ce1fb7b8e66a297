"""What every analytic surface shares: its parameters, the sampled result, and noise."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..core.mesh import Mesh
from ..core.result import Curvature

__all__ = ["Param", "Surface", "SampledSurface", "add_noise"]


@dataclass(frozen=True)
class Param:
    """One parameter of a surface, for pickers and the CLI.

    Attributes
    ----------
    name : str
        Keyword of the surface's constructor.
    default : float
        Value used when the caller gives none.
    low, high : float
        A sensible range to offer in a user interface (not enforced; the constructor validates);
        a Monge patch's random draw, unless it says otherwise, is uniform over it.
    doc : str
        One line saying what the parameter does.
    """

    name: str
    default: float
    low: float
    high: float
    doc: str = ""


class Surface(ABC):
    """An analytic surface with exact curvature at any of its points.

    Subclasses declare ``name`` (registry key), ``title`` (human name) and ``params`` (one
    :class:`Param` per constructor keyword, in order) and implement :meth:`exact_at` and
    :meth:`mesh`; the constructor stores the parameters as attributes of the same names, and a
    subclass whose parameters must satisfy more than ``positive`` checks them in :meth:`_check`.
    """

    name: ClassVar[str]
    title: ClassVar[str]
    params: ClassVar[tuple[Param, ...]]
    closed: ClassVar[bool] = False
    """True for surfaces meshed without border (sphere, ellipsoid, torus)."""
    default_vertices: ClassVar[int] = 817
    positive: ClassVar[bool] = False
    """True where every parameter is a length: the constructor refuses values that are not finite and > 0."""

    def __init__(self, *values, **named):
        """Parameters in the order of :attr:`params` (or by name), as floats; defaults otherwise.

        Raises
        ------
        TypeError
            More values than parameters, or a name that is not one.
        ValueError
            A value the surface does not take (:attr:`positive`, :meth:`_check`).
        """
        names = [p.name for p in self.params]
        if len(values) > len(names):
            raise TypeError(f"{type(self).__name__} takes at most {len(names)} parameters ({', '.join(names)})")
        unknown = sorted(set(named) - set(names))
        if unknown:
            raise TypeError(f"{type(self).__name__} has no parameter {', '.join(unknown)}")
        given = {**dict(zip(names, values)), **named}
        for p in self.params:
            setattr(self, p.name, float(given.get(p.name, p.default)))
        if self.positive:
            for name, value in self.parameters.items():
                if not (np.isfinite(value) and value > 0):
                    raise ValueError(f"{name} must be a finite value > 0, got {value}")
        self._check()

    def _check(self) -> None:
        """Raise ``ValueError`` for parameter values the surface cannot take (beyond :attr:`positive`)."""

    @property
    def parameters(self) -> dict[str, float]:
        """``{name: value}`` of the parameters, in declaration order."""
        return {p.name: float(getattr(self, p.name)) for p in self.params}

    def describe(self) -> str:
        """One line: the surface and its parameter values, e.g. ``"Torus (major=1, minor=0.4)"``."""
        values = ", ".join(f"{k}={v:.4g}" for k, v in self.parameters.items())
        return f"{self.title} ({values})"

    def __repr__(self) -> str:
        values = ", ".join(f"{k}={v!r}" for k, v in self.parameters.items())
        return f"{type(self).__name__}({values})"

    def __eq__(self, other) -> bool:
        return type(self) is type(other) and self.parameters == other.parameters

    def __hash__(self) -> int:
        return hash((type(self), tuple(self.parameters.items())))

    @abstractmethod
    def exact_at(self, points: np.ndarray) -> Curvature:
        """Exact curvature at points of the surface.

        Parameters
        ----------
        points : (n, 3) float64
            Points on the surface (a Monge patch uses only their ``x, y``).

        Returns
        -------
        Curvature
            ``method="exact"``, every vertex valid.
        """

    @abstractmethod
    def mesh(self, n_vertices: int | None = None, *, irregularity_deg: float = 0.0, rng=None) -> "SampledSurface":
        """Mesh the surface with about ``n_vertices`` vertices and attach the exact curvature."""


@dataclass(frozen=True, eq=False)
class SampledSurface:
    """A mesh of an analytic surface with its exact curvature at every vertex.

    Attributes
    ----------
    mesh : Mesh
        The triangle mesh, faces counter-clockwise seen from the normal side.
    truth : Curvature
        Exact ``k1, k2, d1, d2, normals`` at the vertices (``method="exact"``, all valid). With noise,
        the values are those of the noise-free vertex each noisy one came from.
    surface : Surface
        The analytic surface that was sampled.
    irregularity_deg : float or None
        Measured RMS deviation of all triangle angles from 60 degrees, for hexagon patches.
    noise : float
        Standard deviation of the 3D Gaussian vertex noise, in mean edge lengths.
    info : dict
        Meshing details: ``subdivisions``, the irregularity ``target_deg`` and displacement
        ``amplitude``, ``seed``, ...
    """

    mesh: Mesh
    truth: Curvature
    surface: Surface
    irregularity_deg: float | None = None
    noise: float = 0.0
    info: dict = field(default_factory=dict)

    def describe(self) -> str:
        """One line for a viewer's title or a log, e.g. surface, vertex count, irregularity, noise."""
        parts = [self.surface.describe(), f"{self.mesh.n_vertices} vertices"]
        if self.irregularity_deg is not None:
            parts.append(f"irregularity {self.irregularity_deg:.1f}°")
        if self.noise:
            parts.append(f"noise {self.noise:g} × mean edge")
        if self.info.get("seed") is not None:
            parts.append(f"seed {self.info['seed']}")
        return ", ".join(parts)


def add_noise(sampled: SampledSurface, noise: float, rng) -> SampledSurface:
    """Perturb every vertex with 3D Gaussian noise; the truth stays that of the clean surface.

    Parameters
    ----------
    sampled : SampledSurface
        Noise-free sample.
    noise : float
        Standard deviation as a multiple of the mesh's mean edge length (paper §5.1). 0 returns
        ``sampled`` unchanged.
    rng : numpy.random.Generator, int or None
        Random source.

    Returns
    -------
    SampledSurface
    """
    if noise < 0:
        raise ValueError(f"noise must be >= 0, got {noise}")
    if noise == 0:
        return sampled
    rng = np.random.default_rng(rng)
    sigma = noise * sampled.mesh.mean_edge_length
    v = sampled.mesh.vertices + rng.normal(scale=sigma, size=sampled.mesh.vertices.shape)
    info = {**sampled.info, "noise_sigma": sigma}
    return SampledSurface(
        mesh=sampled.mesh.with_vertices(v), truth=sampled.truth, surface=sampled.surface,
        irregularity_deg=sampled.irregularity_deg, noise=float(noise), info=info,
    )
