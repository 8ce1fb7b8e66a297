"""The study protocol of the paper's §5: the grid of settings, the estimator variants and the tasks.

A *task* is one test mesh: (function, density, irregularity, noise, sample). Every estimator
variant is evaluated on it, so meshing and normal estimation happen once per mesh. Each task draws
its random numbers from streams derived from ``(seed, part of the key)`` only, never from a shared
generator, so results do not depend on the order or the machine tasks run on.

The streams are chosen for *paired* comparisons (common random numbers):

- the surface parameters depend on ``(seed, function, sample)``: the same random surface is
  meshed at every density, irregularity and noise level;
- the planar mesh depends on ``(seed, density, irregularity, sample)``;
- the noise field depends on ``(seed, function, density, irregularity, sample)`` and is scaled by
  the noise level, so the 33/66/100 % meshes of a sample differ only in amplitude.

Differences between settings are then not drowned by surface-to-surface variation, which matters
when a setting is averaged over tens rather than the paper's 1000 surfaces.
"""

from __future__ import annotations

import enum
import zlib
from dataclasses import dataclass, field, replace
from typing import Iterator, Sequence

import numpy as np

from ..api import Smoothing
from ..variants import NOISE_FRACTION, SMOOTHING_SUFFIX, Variant, short_name
from ..surfaces import PAPER_SURFACES
from ..surfaces.hexagon import PAPER_VERTEX_COUNTS, hexagon_subdivisions

__all__ = [
    "DENSITIES", "NOISE_LEVELS", "NOISE_FRACTION", "IRREGULARITIES", "FUNCTIONS", "EXCLUSION_RANGE",
    "SMOOTH_RANGE", "FIG10_DENSITY", "Smoothing", "SMOOTHING_SUFFIX", "Variant", "study_variants", "parse_variants",
    "StudySettings", "Task", "Preset", "preset_settings", "short_name",
]

DENSITIES: tuple[int, ...] = PAPER_VERTEX_COUNTS
"""Vertex counts of the subdivided hexagon (3 s^2 + 3 s + 1 for s = 8, 16, 32, 64 segments per side)."""

NOISE_LEVELS: tuple[float, ...] = (0.0, 0.33, 0.66, 1.0)
"""Noise levels as fractions of :data:`NOISE_FRACTION` of the mean edge length."""

IRREGULARITIES: tuple[float, ...] = (0.0, 14.0, 25.0)
"""Targets of the RMS deviation of all triangle angles from 60 degrees."""

FUNCTIONS: tuple[str, ...] = PAPER_SURFACES
"""The Monge patches of eq. 5.1 (registry names of :mod:`curv.surfaces`)."""

EXCLUSION_RANGE = 4
"""Vertices with a border vertex within this range are not evaluated (§5.1)."""

SMOOTH_RANGE = 2
"""The range of the smoothing variants R2SM and R2SV (Fig. 10)."""

FIG10_DENSITY = 3169
"""The density of Fig. 10 (the paper's text; its caption says 'highest sampling density')."""


def _registry():
    from ..estimators import ESTIMATORS

    return ESTIMATORS


def study_variants(*, smoothing: bool = True) -> tuple[Variant, ...]:
    """Every variant of the registry: each estimator at each of its ranges, in registry order.

    With ``smoothing``, each estimator that has range :data:`SMOOTH_RANGE` also gets its R2SM and
    R2SV variants (they come after the plain ranges of that estimator).
    """
    out = []
    for name, spec in _registry().items():
        out += [Variant(name, k) for k in spec.ranges]
        if smoothing and SMOOTH_RANGE in spec.ranges:
            out += [Variant(name, SMOOTH_RANGE, s) for s in (Smoothing.MESH, Smoothing.VALUES)]
    return tuple(out)


def parse_variants(selectors: Sequence[str] | None, *, smoothing: bool = True) -> tuple[Variant, ...]:
    """Resolve estimator selectors against the registry.

    Parameters
    ----------
    selectors : sequence of str or None
        ``None`` or empty: every variant. Otherwise tokens ``name`` (all its variants),
        ``name:R2`` or ``name:2`` (one range), ``name:R2,R3`` (several), ``name:R2SM``.
    smoothing : bool
        Whether a bare ``name`` includes its smoothing variants.

    Returns
    -------
    tuple of Variant
        In registry order, without duplicates.

    Raises
    ------
    ValueError
        For an unknown estimator or a range it does not have, naming the allowed ones.
    """
    every = study_variants(smoothing=True)
    if not selectors:
        return tuple(v for v in every if smoothing or v.smooth is Smoothing.NONE)
    registry = _registry()
    wanted: set[Variant] = set()
    for token in selectors:
        name, _, ranges = token.strip().partition(":")
        if name not in registry:
            raise ValueError(f"unknown estimator {name!r}; choose from {', '.join(registry)}")
        own = [v for v in every if v.method == name]
        if not ranges:
            wanted.update(v for v in own if smoothing or v.smooth is Smoothing.NONE)
            continue
        for part in ranges.split(","):
            part = part.strip().upper()
            part = part if part.startswith("R") else "R" + part
            match = [v for v in own if v.range_label == part]
            if not match:
                allowed = ", ".join(v.range_label for v in own)
                raise ValueError(f"estimator {name!r} has no variant {part}; allowed: {allowed}")
            wanted.update(match)
    return tuple(v for v in every if v in wanted)


def _crc(text: str) -> int:
    return zlib.crc32(text.encode())


@dataclass(frozen=True, order=True)
class Task:
    """One test mesh of the grid; every variant of the study is evaluated on it.

    ``noise`` is the level as a fraction of the 100 % level (:data:`NOISE_FRACTION` of the mean
    edge length); ``irregularity`` is the target RMS angle deviation in degrees.
    """

    seed: int
    function: str
    density: int
    irregularity: float
    noise: float
    sample: int

    @property
    def key(self) -> tuple:
        """``(seed, function, density, irregularity, noise, sample)``: identifies the task in a results file."""
        return (self.seed, self.function, self.density, float(self.irregularity), float(self.noise), self.sample)

    def _ss(self, *parts: int) -> np.random.SeedSequence:
        return np.random.SeedSequence([self.seed, *parts])

    def surface_rng(self) -> np.random.Generator:
        """Random parameters of the surface: depends on (seed, function, sample) only."""
        return np.random.default_rng(self._ss(1, _crc(self.function), self.sample))

    def mesh_rng(self) -> np.random.Generator:
        """Vertex shifts of the planar mesh: depends on (seed, density, irregularity, sample)."""
        return np.random.default_rng(self._ss(2, self.density, round(self.irregularity * 1000), self.sample))

    def noise_rng(self) -> np.random.Generator:
        """Noise directions: the same for every noise level of one (function, mesh, sample)."""
        return np.random.default_rng(
            self._ss(3, _crc(self.function), self.density, round(self.irregularity * 1000), self.sample)
        )


@dataclass(frozen=True)
class StudySettings:
    """The grid of a study run.

    Attributes
    ----------
    samples : int
        Random surfaces per setting (the paper uses 1000).
    densities : tuple of int
        Vertex counts of the subdivided hexagon, ``3 s (s + 1) + 1`` for some ``s >= 1``: the
        paper's :data:`DENSITIES` or any other subdivision (e.g. 1801 for s = 24, 7057 for s = 48).
    noise : tuple of float
        Noise levels as fractions of the 100 % level (10 % of the mean edge length).
    irregularity : tuple of float
        Target RMS angle deviations in degrees.
    functions : tuple of str
        Monge patches of eq. 5.1.
    estimators : tuple of str
        Selectors for :func:`parse_variants`; empty means the whole registry.
    smoothing_density : int or None
        Density at which the R2SM/R2SV variants are computed (Fig. 10); ``None`` picks
        :data:`FIG10_DENSITY` if it is in the grid, else the largest density of the grid.
    seed : int
        Root of every random stream.
    """

    samples: int = 1
    densities: tuple[int, ...] = DENSITIES
    noise: tuple[float, ...] = NOISE_LEVELS
    irregularity: tuple[float, ...] = IRREGULARITIES
    functions: tuple[str, ...] = FUNCTIONS
    estimators: tuple[str, ...] = ()
    smoothing_density: int | None = None
    seed: int = 0

    def __post_init__(self):
        if self.samples < 1:
            raise ValueError(f"samples must be at least 1, got {self.samples}")
        for d in self.densities:
            try:
                hexagon_subdivisions(d)
            except ValueError as exc:
                raise ValueError(f"density {d} is not a hexagon subdivision: {exc}") from None
        bad = [f for f in self.functions if f not in FUNCTIONS]
        if bad:
            raise ValueError(f"unknown function {bad[0]!r}; choose from {', '.join(FUNCTIONS)}")
        if any(x < 0 for x in self.noise) or any(x < 0 for x in self.irregularity):
            raise ValueError("noise levels and irregularities must be non-negative")
        for name in ("densities", "noise", "irregularity", "functions", "estimators"):
            object.__setattr__(self, name, tuple(getattr(self, name)))

    def with_(self, **changes) -> "StudySettings":
        """A copy with some fields changed (``None`` values are ignored)."""
        return replace(self, **{k: v for k, v in changes.items() if v is not None})

    @property
    def fig10_density(self) -> int:
        """The density that gets the smoothing variants."""
        if self.smoothing_density is not None:
            return self.smoothing_density
        return FIG10_DENSITY if FIG10_DENSITY in self.densities else max(self.densities)

    def variants(self) -> tuple[Variant, ...]:
        """All variants of this study, smoothing ones included."""
        return parse_variants(self.estimators, smoothing=True)

    def variants_for(self, task: Task) -> tuple[Variant, ...]:
        """The variants evaluated on ``task``: smoothing variants only at :attr:`fig10_density`."""
        every = self.variants()
        if task.density == self.fig10_density:
            return every
        return tuple(v for v in every if v.smooth is Smoothing.NONE)

    def tasks(self) -> Iterator[Task]:
        """Every task, sample by sample (so an interrupted run holds complete samples first);
        within a sample the densest meshes come first (better load balance in a pool)."""
        for s in range(self.samples):
            for d in sorted(self.densities, reverse=True):
                for irr in self.irregularity:
                    for f in self.functions:
                        for nz in self.noise:
                            yield Task(self.seed, f, d, float(irr), float(nz), s)

    @property
    def n_tasks(self) -> int:
        return self.samples * len(self.densities) * len(self.irregularity) * len(self.functions) * len(self.noise)

    def as_dict(self) -> dict:
        return {
            "samples": self.samples, "densities": list(self.densities), "noise": list(self.noise),
            "irregularity": list(self.irregularity), "functions": list(self.functions),
            "estimators": list(self.estimators), "smoothing_density": self.fig10_density, "seed": self.seed,
        }


class Preset(str, enum.Enum):
    """Named grids: ``quick`` for CI (36 meshes of 217/817 vertices, ~30 s on 2 cores), ``medium``
    for the docs (the full grid with N=2, 288 meshes: ~20 CPU-minutes, 24 min wall measured on a
    busy 2-core machine), ``paper`` the full grid of §5 with N=1000 (for a cluster)."""

    QUICK = "quick"
    MEDIUM = "medium"
    PAPER = "paper"


_PRESETS: dict[Preset, StudySettings] = {
    Preset.QUICK: StudySettings(
        samples=1, densities=(217, 817), noise=(0.0, 1.0), irregularity=(0.0, 14.0, 25.0),
    ),
    Preset.MEDIUM: StudySettings(samples=2),
    Preset.PAPER: StudySettings(samples=1000),
}


def preset_settings(preset: Preset | str) -> StudySettings:
    """The :class:`StudySettings` of a preset."""
    return _PRESETS[Preset(preset)]
