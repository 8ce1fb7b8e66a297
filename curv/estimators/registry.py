"""The estimator registry: every estimator family registers its spec here.

The CLI, the viewer and the study list estimators from :data:`ESTIMATORS`; adding an estimator is
one module with one ``register(EstimatorSpec(...))`` call.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Generator

import numpy as np

from ..errors import EstimatorError
from ..mesh import Mesh
from ..result import Principal

__all__ = ["EstimatorSpec", "ESTIMATORS", "register", "get_spec", "EstimatorFunction"]

EstimatorFunction = Callable[..., Generator[float, None, Principal]]
"""``fn(mesh, normals, radii, *, chunk) -> Generator[fraction done, None, Principal]``.

``normals`` (n, 3) is None only for a spec with ``computes_normals``; ``radii`` (n,) float64 is the
ball radius every vertex collects its support in (:func:`curv.ranges.ball_radii`), None for an
estimator without a support (``has_support=False``); ``chunk`` fixes the vertices per kernel call
(default adaptive, :func:`curv.jit.iter_chunks`)."""


@dataclass(frozen=True)
class EstimatorSpec:
    """Description of one estimator family.

    Attributes
    ----------
    name : str
        Registry key, e.g. ``"mru"``.
    title : str
        Human-readable name.
    ranges : tuple of int
        The ranges k of Rk it supports.
    function : EstimatorFunction
        The generator computing it.
    triangles_only : bool
        Needs a triangle mesh.
    uses_normals : bool
        Uses the neighbours' vertex normals, so its support at Rk is collected within
        ``(k - 1)`` times the longest 1-ring edge.
    closed_ring : bool
        Assumes a closed 1-ring: border-affected vertices are invalid.
    reference : str
        Where the method comes from.
    summary : str
        One line on what it does.
    has_support : bool
        Collects a range support (any real range >= its smallest named one, or a radius). False for
        the fixed 1-ring formulas (``meyer``, ``ru``), which take only their one named range.
    kernels : tuple
        The numba dispatchers the estimator calls, so that a caller can announce a first-run
        compilation (:func:`curv.jit.compile_pending`).
    computes_normals : bool
        Can compute the default (Max-weighted) vertex normals in its own pass over the mesh: called
        with ``normals=None`` it returns them in :attr:`Principal.normals`, already NaN at
        :func:`curv.normals.unusable_normal_vertices`, saving a separate pass.
    """

    name: str
    title: str
    ranges: tuple[int, ...]
    function: EstimatorFunction = field(repr=False, compare=False)
    triangles_only: bool
    uses_normals: bool
    closed_ring: bool
    reference: str
    summary: str = ""
    computes_normals: bool = False
    has_support: bool = True
    kernels: tuple = field(default=(), repr=False, compare=False)

    def support_factor(self, k: int) -> int:
        """Radius of the collected support in longest-1-ring-edge units for range Rk."""
        return k - 1 if self.uses_normals else k

    def check_range(self, k) -> int:
        """Validate a range and return it as int; :class:`EstimatorError` names the allowed ones."""
        try:
            ki = int(k)
        except (TypeError, ValueError):
            ki = None
        if ki is None or ki != k or ki not in self.ranges:
            allowed = ", ".join(f"R{r}" for r in self.ranges)
            raise EstimatorError(f"estimator {self.name!r} has no range {k!r}; allowed: {allowed}")
        return ki

    def variants(self) -> list[tuple[str, int]]:
        """``[(name, k), ...]`` for every supported range."""
        return [(self.name, k) for k in self.ranges]


ESTIMATORS: dict[str, EstimatorSpec] = {}
"""Registry: name -> :class:`EstimatorSpec`, in registration (paper) order."""


def register(spec: EstimatorSpec) -> EstimatorSpec:
    """Add ``spec`` to :data:`ESTIMATORS` (the name must be new)."""
    if spec.name in ESTIMATORS:
        raise ValueError(f"estimator {spec.name!r} is registered twice")
    ESTIMATORS[spec.name] = spec
    return spec


def get_spec(name: str) -> EstimatorSpec:
    """Look up an estimator; :class:`EstimatorError` lists the known names."""
    try:
        return ESTIMATORS[name]
    except (KeyError, TypeError):
        raise EstimatorError(f"unknown estimator {name!r}; choose one of {', '.join(ESTIMATORS)}") from None


def all_variants() -> list[tuple[str, int]]:
    """Every (name, range) pair of the registry, in registry order."""
    return [v for spec in ESTIMATORS.values() for v in spec.variants()]


def iter_blockwise(mesh: Mesh, factor: float, block_fn, *, block_size: int | None = None
                   ) -> Generator[float, None, Principal]:
    """Run a per-block estimator over all range supports (threaded) and assemble the result.

    Parameters
    ----------
    mesh : Mesh
    factor : float
        Support radius in longest-1-ring-edge units.
    block_fn : callable
        ``block_fn(neighbourhood) -> (k1, k2, d1, d2, reason)`` for the block's centre vertices:
        (c,), (c,), (c, 3), (c, 3), (c,) uint8.
    block_size : int, optional
        Vertices per block.

    Yields
    ------
    float
        Fraction of vertices done (the points where a caller may cancel).

    Returns
    -------
    Principal
    """
    from .._legacy_neighbourhood import map_neighbourhoods

    n = mesh.n_vertices
    out = empty_principal(n)
    done = 0
    for nb, (k1, k2, d1, d2, reason) in map_neighbourhoods(mesh, factor, block_fn, block_size=block_size):
        ids = nb.vertices
        out.k1[ids], out.k2[ids], out.d1[ids], out.d2[ids] = k1, k2, d1, d2
        out.reason[ids] = reason
        done += ids.size
        yield done / n
    return out


def empty_principal(n: int) -> Principal:
    """A :class:`Principal` of NaNs with every reason ``OK`` (to be filled by an estimator)."""
    return Principal(
        k1=np.full(n, np.nan), k2=np.full(n, np.nan),
        d1=np.full((n, 3), np.nan), d2=np.full((n, 3), np.nan),
        reason=np.zeros(n, np.uint8),
    )
