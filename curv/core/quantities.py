"""The one owner of the per-vertex scalar quantities derived from k1 and k2.

Every consumer (``Curvature.quantity``, the CLI's ``--quantity`` choices, the PLY and VTK
exports, the viewer's quantity menu and colour rules, the help text) reads this registry, so a
new quantity is one entry here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["QuantitySpec", "QUANTITIES", "EXPORTED", "STANDARD_ERRORS", "get_quantity", "compute", "describe", "anisotropy"]


@dataclass(frozen=True)
class QuantitySpec:
    """A scalar of the principal curvatures.

    Attributes
    ----------
    name : str
        Registry key (``Curvature.quantity(name)``, ``--quantity name``, export property name).
    title : str
        Label for menus and colour bars.
    signed : bool
        True when the value takes both signs with a meaningful zero (diverging map centred on 0).
    natural : (lo, hi) or None
        The quantity's own range when it has one (shape index: [-1, 1]); colour limits use it.
    formula : str
        How it is computed, for help text.
    fn : callable
        ``fn(k1, k2) -> (n,) float64`` on (n,) arrays; NaN in, NaN out.
    """

    name: str
    title: str
    signed: bool
    natural: tuple[float, float] | None
    formula: str
    fn: Callable[[np.ndarray, np.ndarray], np.ndarray]


def _shape_index(k1, k2):
    return (2.0 / np.pi) * np.arctan2(k1 + k2, k1 - k2)


_SPECS = (
    QuantitySpec("mean", "Mean H", True, None, "H = (k1 + k2) / 2", lambda k1, k2: 0.5 * (k1 + k2)),
    QuantitySpec("gaussian", "Gaussian K", True, None, "K = k1 k2", lambda k1, k2: k1 * k2),
    QuantitySpec("k1", "k1", True, None, "larger principal curvature", lambda k1, k2: np.asarray(k1, float)),
    QuantitySpec("k2", "k2", True, None, "smaller principal curvature", lambda k1, k2: np.asarray(k2, float)),
    QuantitySpec("shape_index", "Shape index", True, (-1.0, 1.0),
                 "Koenderink: 2/pi arctan((k1 + k2) / (k1 - k2)), in [-1, 1]", _shape_index),
    QuantitySpec("curvedness", "Curvedness", False, None, "Koenderink: sqrt((k1² + k2²) / 2)",
                 lambda k1, k2: np.sqrt(0.5 * (k1 * k1 + k2 * k2))),
    QuantitySpec("absolute", "Absolute curvature", False, None, "|k1| + |k2| (MeshLab's absolute curvature)",
                 lambda k1, k2: np.abs(k1) + np.abs(k2)),
    QuantitySpec("rms", "RMS curvature", False, None, "sqrt(4H² - 2K) = sqrt(k1² + k2²) (MeshLab's RMS curvature)",
                 lambda k1, k2: np.sqrt(k1 * k1 + k2 * k2)),
)

QUANTITIES: dict[str, QuantitySpec] = {q.name: q for q in _SPECS}
"""Registry: name -> :class:`QuantitySpec`, in display order."""


EXPORTED = ("k1", "k2", "mean", "gaussian")
"""The quantities every export writes as float fields and the CLI summarises (the rest derive from k1, k2)."""

STANDARD_ERRORS = ("k1_se", "k2_se")
"""The :class:`~curv.core.result.Curvature` fields of the standard errors of k1 and k2 (docs/UNCERTAINTY.md),
which every export writes as float fields after :data:`EXPORTED` (NaN where undefined)."""


def anisotropy(k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """(n,) ``|k1 - k2| / (|k1| + |k2|)`` in [0, 1]: 0 at an umbilic (no principal direction), 1 where one
    curvature vanishes or they have opposite signs; NaN where both are 0 or a value is NaN."""
    k1 = np.asarray(k1, dtype=np.float64)
    k2 = np.asarray(k2, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.abs(k1 - k2) / (np.abs(k1) + np.abs(k2))


def get_quantity(name: str) -> QuantitySpec:
    """The spec of ``name``; ``ValueError`` naming the known quantities otherwise."""
    try:
        return QUANTITIES[name]
    except KeyError:
        raise ValueError(f"unknown quantity {name!r}; choose one of {', '.join(QUANTITIES)}") from None


def compute(name: str, k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """(n,) float64 values of quantity ``name`` from (n,) principal curvatures."""
    k1 = np.asarray(k1, dtype=np.float64)
    k2 = np.asarray(k2, dtype=np.float64)
    return np.asarray(get_quantity(name).fn(k1, k2), dtype=np.float64)


def describe() -> list[str]:
    """One help line per quantity: ``name: title, formula``."""
    return [f"{q.name}: {q.title}, {q.formula}" for q in QUANTITIES.values()]
