"""Where the document's mesh comes from: a file, or an analytic surface with its parameters."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from curv.surfaces.hexagon import PAPER_VERTEX_COUNTS as HEXAGON_SIZES

from .inputs import SAMPLING_WORDS

__all__ = ["FileSource", "SurfaceSource", "HEXAGON_SIZES", "snap_hexagon_count"]


def snap_hexagon_count(n: int) -> int:
    """The hexagon vertex count ``3 s (s + 1) + 1`` nearest ``n`` (s >= 1)."""
    s = max(1, round((-3 + math.sqrt(max(9 + 12 * (n - 1), 0))) / 6))
    return min((3 * t * (t + 1) + 1 for t in (max(s - 1, 1), s, s + 1)), key=lambda c: (abs(c - n), c))


@dataclass(frozen=True)
class FileSource:
    """A mesh read from ``path``."""

    path: str
    repairs: tuple = ()
    """Opt-in repairs to apply when loading (``merge_vertices``, ``remove_degenerate``, ``orient``,
    ``remove_unreferenced``)."""

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
    sampling : str or None
        Sample the surface as a point cloud of ``n_vertices`` points this way (one of
        :data:`SAMPLINGS`, e.g. ``"uniform"``) instead of meshing it; ``noise`` is then a fraction of
        the points' spacing.
    """

    name: str = "ellipsoid_patch"
    params: dict = field(default_factory=dict)
    n_vertices: int = 3169
    irregularity: float = 0.0
    noise: float = 0.0
    seed: int | None = 0
    random_params: bool = False
    sampling: str | None = None

    @property
    def label(self) -> str:
        if self.sampling is not None:
            return f"{self.name} ({self.n_vertices} points, {SAMPLING_WORDS.get(self.sampling, self.sampling)})"
        return f"{self.name} ({self.n_vertices} vertices)"

    @property
    def analytic(self) -> bool:
        return True

    def __hash__(self) -> int:  # params is a dict: hash on its items
        return hash((self.name, tuple(sorted(self.params.items())), self.n_vertices,
                     self.irregularity, self.noise, self.seed, self.random_params, self.sampling))
