"""The one owner of the range rule (paper §4.1): parsing, validation, labels and support radii.

The support of the estimate at vertex p under range Rk is every vertex connected to p through the
mesh within Euclidean distance ``k * L(p)``, where ``L(p)`` is the longest edge of p's 1-ring.
Estimators that also use their neighbours' normals (``an``, ``mru``) collect within ``(k - 1) * L(p)``:
their R2 is the classic 1-ring-plus-normals form. Any real ``k`` at least the estimator's smallest
named range is accepted; ``radius=r`` instead gives every vertex the same ball of radius ``r`` in mesh
units (the ball the estimator collects in, whatever it is). Estimators without a support (``meyer``,
``ru``: fixed 1-ring formulas) accept only their one named range.

On a point cloud (:class:`curv.PointCloud`) the unit is the point's **spacing**: the distance to
its :data:`SPACING_NEIGHBOUR`-th nearest other point. On a regular triangle mesh the 1-ring is the
six nearest vertices and its longest edge is the distance to the farthest of them, so the spacing
is the same length there and Rk means the same support on a mesh and on its vertices as points
(R1 about 6 neighbours, R2 about 20-25 on an even sample). The support is every point reachable
from p through the cloud's neighbour graph inside the ball (the graph plays the mesh edges'
part). ``an`` and ``mru`` keep their ``(k - 1)`` rule (R2: the six nearest and their normals,
like the mesh's 1-ring). ``knn=K`` (points only) gives p the ball through its K-th nearest other
point, so the support is the K nearest (more on exact ties), for every estimator alike.

Everything else (the API, the CLI, the viewer, the memory model, the study) asks this module.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import EstimatorError
from .filled import filled
from .pointcloud import PointCloud
from .support import SPACING_NEIGHBOUR, support_of

__all__ = ["describe_spacing", "Range", "parse_range", "resolve", "range_label", "support_factor", "ball_radii",
           "default_range", "takes_any_range", "canonical_k", "nearest_allowed",
           "allowed_paper_ranges", "describe_ranges", "unit_lengths", "point_spacing", "TIE_TOLERANCE",
           "PAPER_RANGES", "FORMS", "SPACING_NEIGHBOUR", "MIN_KNN"]

MIN_KNN = 3
"""The smallest ``knn=K``: the fits have three curvature unknowns."""

TIE_TOLERANCE = 1e-9
"""Relative tolerance on every ball radius, so that vertices exactly at k edge lengths (regular
meshes) are inside."""

PAPER_RANGES = (1, 2, 3, 4)
"""The paper's named ranges R1..R4."""

FORMS = "a number k >= 1 such as 2 or 2.5, a label such as 'R2', or radius=r in mesh units"
"""The allowed forms of a range, for error messages."""


@dataclass(frozen=True)
class Range:
    """A resolved range: a multiple ``k`` of each vertex's range unit, a fixed ``radius``, or ``knn``.

    Attributes
    ----------
    k : float or None
        k of Rk (None when ``radius`` is given).
    radius : float or None
        Ball radius in mesh units, the same at every vertex (None for Rk).
    """

    k: float | None = None
    radius: float | None = None
    knn: int | None = None
    """The K of ``knn=K`` (points only): the ball through the K-th nearest other point."""

    @property
    def label(self) -> str:
        """``'R2'``, ``'R2.5'``, ``'r=0.3'`` or ``'knn=20'``."""
        if self.radius is not None:
            return f"r={self.radius:g}"
        if self.knn is not None:
            return f"knn={self.knn}"
        return range_label(self.k)

    @property
    def value(self):
        """k as an int when it is whole (so ``R2`` compares equal to 2), else the float; None for a radius."""
        if self.k is None:
            return None
        return canonical_k(self.k)


def range_label(k) -> str:
    """``'R2'`` for 2 or 2.0, ``'R2.5'`` for 2.5."""
    k = float(k)
    return f"R{int(k)}" if k.is_integer() else f"R{k:g}"


def canonical_k(k):
    """k as an int when it is whole (``2.0 -> 2``, so ``R2`` and 2 compare equal), else the float."""
    k = float(k)
    return int(k) if k.is_integer() else k


def takes_any_range(spec) -> bool:
    """Whether ``spec`` takes any real k from its smallest named range on and ``radius=r``.

    False for the fixed 1-ring formulas (``meyer``, ``ru``), which take only their one named range.
    """
    return bool(spec.has_support)



def default_range(spec):
    """The range used when none is given: R2 where the estimator has it, else its first named range."""
    return canonical_k(2 if 2 in spec.ranges else spec.ranges[0])


def nearest_allowed(spec, k):
    """The range ``spec`` takes that is closest to k, for a control switching estimators.

    A support-based estimator keeps k if it is at least its smallest range, else takes that smallest
    one; a fixed 1-ring formula always has its one range.
    """
    if not takes_any_range(spec):
        return default_range(spec)
    k = parse_range(k)
    return canonical_k(max(k, min(spec.ranges)))


def allowed_paper_ranges(spec) -> tuple:
    """Which of the paper's R1..R4 ``spec`` accepts (for a list of choices)."""
    if not takes_any_range(spec):
        return tuple(k for k in PAPER_RANGES if k in spec.ranges)
    return tuple(k for k in PAPER_RANGES if k >= min(spec.ranges))


def describe_ranges(spec) -> str:
    """What ranges ``spec`` takes, in words: ``'any k >= 2, or a radius'`` or ``'R2 only (fixed 1-ring)'``."""
    if not takes_any_range(spec):
        return f"{range_label(spec.ranges[0])} only (fixed 1-ring)"
    return f"any k >= {min(spec.ranges):g}, or a radius"


def parse_range(value) -> float:
    """Read a range as a real k: ``2``, ``2.5``, ``"2"``, ``"R2"``, ``"r2.5"``.

    Raises
    ------
    EstimatorError
        Anything else (booleans, NaN, non-numbers), naming the allowed forms.
    """
    if isinstance(value, (bool, np.bool_)) or value is None:
        raise EstimatorError(f"range must be {FORMS}; got {value!r}")
    if isinstance(value, str):
        text = value.strip().upper().removeprefix("R")
        try:
            k = float(text)
        except ValueError:
            raise EstimatorError(f"range must be {FORMS}; got {value!r}") from None
    else:
        try:
            k = float(value)
        except (TypeError, ValueError):
            raise EstimatorError(f"range must be {FORMS}; got {value!r}") from None
    if not math.isfinite(k):
        raise EstimatorError(f"range must be {FORMS}; got {value!r}")
    return k


def support_factor(k: float, *, uses_normals: bool) -> float:
    """Radius of the collected support in longest-1-ring-edge units for range Rk: ``k - 1`` or ``k``."""
    return k - 1.0 if uses_normals else float(k)


def resolve(spec, range=None, radius=None, knn=None) -> Range:
    """Validate a range request for an estimator.

    Parameters
    ----------
    spec : EstimatorSpec
        The estimator (its ``ranges``, ``has_support``).
    range : int, float or str, optional
        k of Rk; default the estimator's R2 if it has one, else its first named range.
    radius : float, optional
        Absolute ball radius (mutually exclusive with ``range``).
    knn : int, optional
        The K nearest points (point clouds; mutually exclusive with the others).

    Returns
    -------
    Range

    Raises
    ------
    EstimatorError
        Both or an invalid one given; the message names the allowed forms.
    """
    if knn is not None:
        if range is not None or radius is not None:
            raise EstimatorError("give one of range=, radius= or knn=")
        if not spec.has_support:
            raise EstimatorError(f"estimator {spec.name!r} uses its fixed 1-ring and takes no knn")
        if isinstance(knn, (bool, np.bool_)) or not isinstance(knn, (int, np.integer)) or knn < MIN_KNN:
            raise EstimatorError(f"knn must be a whole number of neighbours >= {MIN_KNN}; got {knn!r}")
        return Range(knn=int(knn))
    if radius is not None:
        if range is not None:
            raise EstimatorError("give either range= or radius=, not both")
        if not spec.has_support:
            raise EstimatorError(
                f"estimator {spec.name!r} uses its fixed 1-ring ({range_label(spec.ranges[0])}) and takes no radius")
        try:
            r = float(radius)
        except (TypeError, ValueError):
            r = math.nan
        if isinstance(radius, (bool, np.bool_)) or not (math.isfinite(r) and r > 0):
            raise EstimatorError(f"radius must be a positive length in mesh units; got {radius!r}")
        return Range(radius=r)
    if range is None:
        range = default_range(spec)
    k = parse_range(range)
    if not spec.has_support:
        if k not in spec.ranges:
            raise EstimatorError(
                f"estimator {spec.name!r} has no range {range!r}; allowed: "
                f"{', '.join(range_label(r) for r in spec.ranges)} (a fixed 1-ring formula)")
        return Range(k=k)
    smallest = min(spec.ranges)
    if k < smallest:
        raise EstimatorError(
            f"estimator {spec.name!r} has no range {range!r}; allowed: any k >= {smallest:g} "
            f"({', '.join(range_label(r) for r in spec.ranges)} are the paper's), or radius=r in mesh units")
    return Range(k=k)


def point_spacing(cloud: PointCloud) -> np.ndarray:
    """(n,) float64 spacing of every point: the distance to its :data:`SPACING_NEIGHBOUR`-th nearest."""
    return cloud.kth_distance(SPACING_NEIGHBOUR)


def describe_spacing(cloud: PointCloud) -> str:
    """``spacing 0.0123 (median; 5-95 %: 0.0101 .. 0.0150)``: the range unit of a cloud, in words."""
    spacing = point_spacing(cloud)
    finite = spacing[np.isfinite(spacing)]
    if not finite.size:
        return "no spacing (a single point)"
    lo, med, hi = np.percentile(finite, [5, 50, 95])
    return f"spacing {med:.4g} (median; 5-95 %: {lo:.4g} .. {hi:.4g})"


def unit_lengths(shape) -> np.ndarray:
    """(n,) float64 range unit of every vertex: the longest 1-ring edge of a mesh, a point's spacing."""
    return support_of(shape).unit_lengths()


def ball_radii(mesh, rng: Range, *, uses_normals: bool, at: np.ndarray | None = None) -> np.ndarray:
    """(n,) float64 radius of the ball each vertex collects its support in, tolerance included.

    Parameters
    ----------
    mesh : Mesh or PointCloud
    rng : Range
    uses_normals : bool
        Whether the estimator also uses its neighbours' normals (support ``k - 1``; not for knn).
    at : (c,) int64, optional
        Only these vertices need a radius (an estimate over a region): the other rows are NaN, and
        the cost follows ``at``, not the mesh (:func:`curv.core.filled.filled`); where the input's
        search reads every radius (a cloud, :attr:`curv.core.support.Support.whole_radii`) all rows get one.

    Raises
    ------
    EstimatorError
        ``knn`` on a mesh (its supports follow the mesh edges; use a range or a radius).
    """
    support = support_of(mesh)
    if at is not None and rng.knn is None and not support.whole_radii:
        out = filled(mesh.n_vertices, np.nan)
        if rng.radius is not None:
            out[at] = rng.radius * (1.0 + TIE_TOLERANCE)
        else:
            out[at] = (support_factor(rng.k, uses_normals=uses_normals) * (1.0 + TIE_TOLERANCE)) * support.unit_lengths()[at]
        return out
    if rng.radius is not None:
        return np.full(mesh.n_vertices, rng.radius * (1.0 + TIE_TOLERANCE))
    if rng.knn is not None:
        return (1.0 + TIE_TOLERANCE) * support.knn_distances(rng.knn)
    factor = support_factor(rng.k, uses_normals=uses_normals)
    return (factor * (1.0 + TIE_TOLERANCE)) * support.unit_lengths()
