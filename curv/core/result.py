"""Result containers: the raw output of an estimator and the public :class:`Curvature`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .quantities import QUANTITIES
from .quantities import compute as _compute
from .validity import Reason

__all__ = ["Principal", "Curvature"]


@dataclass
class Principal:
    """What an estimator returns before the validity rules are applied.

    Attributes
    ----------
    k1, k2 : (n,) float64
        Principal curvatures, in any order.
    d1, d2 : (n, 3) float64
        Directions belonging to ``k1`` and ``k2``.
    reason : (n,) uint8
        :class:`Reason` codes; ``Reason.OK`` where the estimate is usable.
    normals : (n, 3) float64 or None
        The normals the estimator computed itself (only when it was asked to: see
        ``EstimatorSpec.computes_normals``).
    k1_se, k2_se : (n,) float64 or None
        Standard errors of ``k1`` and ``k2`` from the fit's residuals (least-squares estimators
        only; None for the others).
    """

    k1: np.ndarray
    k2: np.ndarray
    d1: np.ndarray
    d2: np.ndarray
    reason: np.ndarray
    normals: np.ndarray | None = None
    k1_se: np.ndarray | None = None
    k2_se: np.ndarray | None = None


def _quantity_property(name: str) -> property:
    """A read-only ``Curvature`` attribute computing quantity ``name`` by :mod:`curv.core.quantities`."""
    spec = QUANTITIES[name]
    return property(lambda self: self.quantity(name), doc=f"(n,) {spec.title}: {spec.formula}.")


@dataclass
class Curvature:
    """Principal curvatures and directions at every vertex, with a validity mask.

    Attributes
    ----------
    k1, k2 : (n,) float64
        Principal curvatures, ``k1 >= k2``; NaN where ``valid`` is False. Positive where the
        surface bends away from its normal (outward sphere of radius r: ``+1/r``).
    d1, d2 : (n, 3) float64
        Unit principal directions, tangent to ``normals``; NaN where ``valid`` is False.
    normals : (n, 3) float64
        The unit vertex normals the estimate used.
    valid : (n,) bool
        False where the estimate is not trustworthy (border-affected, degenerate, singular).
    reason : (n,) uint8
        Why a vertex is invalid (:class:`curv.Reason`), ``0`` where valid.
    method : str
        Registry name of the estimator (``"exact"`` for analytic truth).
    k1_se, k2_se : (n,) float64
        Standard errors of ``k1`` and ``k2`` from the least-squares fit's residuals (``nc``, ``qs``,
        ``an``, ``mru``, ``jet``, when asked: ``curv.estimate(..., standard_errors=True)``;
        docs/UNCERTAINTY.md): they cover noise in the positions and normals, not model bias. NaN
        where ``valid`` is False, where the fit has no spare equations, for the estimators without a
        fit, for the smoothing variants, and everywhere when not asked (:attr:`has_standard_errors`).
    range : int, float or None
        The range k of Rk (an int when whole, e.g. 2 for R2; 2.5 for R2.5); None when a fixed
        ``radius`` was given (``info["radius"]``; ``info["range_label"]`` reads ``R2`` or ``r=0.3``).
    info : dict
        Free-form details: elapsed seconds, smoothing options, ...
    """

    k1: np.ndarray
    k2: np.ndarray
    d1: np.ndarray
    d2: np.ndarray
    normals: np.ndarray
    valid: np.ndarray
    reason: np.ndarray = None
    method: str = ""
    range: int | float | None = None
    info: dict = field(default_factory=dict)
    k1_se: np.ndarray = None
    k2_se: np.ndarray = None

    def __post_init__(self):
        if self.reason is None:
            self.reason = np.where(self.valid, Reason.OK, Reason.NOT_COMPUTED).astype(np.uint8)
        if self.k1_se is None:
            self.k1_se = np.full(self.k1.shape, np.nan)
        if self.k2_se is None:
            self.k2_se = np.full(self.k2.shape, np.nan)

    @property
    def n(self) -> int:
        return self.k1.shape[0]

    @property
    def has_standard_errors(self) -> bool:
        """Whether ``k1_se`` and ``k2_se`` were computed (``info["standard_errors"]``): asked for, of
        a least-squares fit, without smoothing. The exports write them only then."""
        return bool(self.info.get("standard_errors", False))

    mean = _quantity_property("mean")
    gaussian = _quantity_property("gaussian")
    shape_index = _quantity_property("shape_index")
    curvedness = _quantity_property("curvedness")

    @property
    def valid_fraction(self) -> float:
        return float(self.valid.mean()) if self.valid.size else 0.0

    def quantity(self, name: str) -> np.ndarray:
        """A per-vertex scalar by name, one of :data:`curv.core.quantities.QUANTITIES` (``ValueError`` otherwise)."""
        return _compute(name, self.k1, self.k2)

