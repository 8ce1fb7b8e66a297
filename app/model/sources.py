"""Where the document's mesh comes from: a file, or an analytic surface with its parameters."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["FileSource", "SurfaceSource", "HEXAGON_SIZES"]

HEXAGON_SIZES = (217, 817, 3169, 12481)
"""Vertex counts of the paper's subdivided hexagon (Monge patches)."""


@dataclass(frozen=True)
class FileSource:
    """A mesh read from ``path``."""

    path: str

    @property
    def label(self) -> str:
        return Path(self.path).name

    @property
    def analytic(self) -> bool:
        return False


@dataclass(frozen=True)
class SurfaceSource:
    """An analytic surface of ``curv.surfaces``, meshed with ``make_surface``.

    Attributes
    ----------
    name : str
        Key of ``curv.surfaces.SURFACES``.
    params : dict
        Shape parameters passed through to the surface (empty: its defaults, or random with ``seed``).
    n_vertices : int
        Target vertex count (hexagon sizes for Monge patches, a resolution for closed surfaces).
    irregularity : float
        Target RMS angle deviation from 60 degrees, 0-25.
    noise : float
        Gaussian noise as a fraction of the mean edge length.
    seed : int or None
        Seed of the random parameters, irregularity and noise.
    random_params : bool
        Draw the shape parameters at random from ``seed`` instead of ``params``.
    """

    name: str = "ellipsoid_patch"
    params: dict = field(default_factory=dict)
    n_vertices: int = 3169
    irregularity: float = 0.0
    noise: float = 0.0
    seed: int | None = 0
    random_params: bool = False

    @property
    def label(self) -> str:
        return f"{self.name} ({self.n_vertices} vertices)"

    @property
    def analytic(self) -> bool:
        return True

    def __hash__(self) -> int:  # params is a dict: hash on its items
        return hash((self.name, tuple(sorted(self.params.items())), self.n_vertices,
                     self.irregularity, self.noise, self.seed, self.random_params))
