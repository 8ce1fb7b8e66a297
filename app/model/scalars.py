"""The scalar field of a pane under the display settings (estimate, exact value or error)."""

from __future__ import annotations

import numpy as np
from curv.core.quantities import compute
from curv.metrics import curvature_error

from .display import DisplayState, Layer

__all__ = ["field_values", "relative_error", "at_vertex", "OneVertex"]


def relative_error(estimate, truth) -> np.ndarray:
    """Per-vertex e_rel (paper eq. 5.2) with NaN where it has no finite value.

    Parameters
    ----------
    estimate, truth : curv.Curvature
        Same mesh; ``truth`` holds the exact values.

    Returns
    -------
    (n,) float64
        NaN where the estimate is invalid or the exact curvature is zero (flat point): such
        vertices are drawn as invalid rather than saturated.
    """
    e = curvature_error(estimate, truth)
    e[~np.isfinite(e)] = np.nan
    return e


def field_values(result, truth, state: DisplayState) -> np.ndarray:
    """Per-vertex values of the shown field.

    Parameters
    ----------
    result : curv.Curvature or None
        The pane's estimate (None only for ``Layer.EXACT``).
    truth : curv.Curvature or None
        Exact curvature of an analytic source.
    state : DisplayState

    Returns
    -------
    (n,) float64
        NaN where the estimate is invalid.

    Raises
    ------
    ValueError
        The layer needs the truth and the source has none.
    """
    layer, name = state.layer, state.quantity.value
    if layer.needs_truth and truth is None:
        raise ValueError(f"{layer.title} needs an analytic source with known curvature")
    if layer is Layer.EXACT:
        return np.asarray(truth.quantity(name), dtype=np.float64)
    if layer is Layer.E_REL:
        return relative_error(result, truth)
    if layer is Layer.UNCERTAINTY:
        return 2.0 * np.asarray(getattr(result, f"{state.uncertain_of}_se"), dtype=np.float64)
    est = np.asarray(result.quantity(name), dtype=np.float64)
    if layer is Layer.ERROR:
        return est - truth.quantity(name)
    return est


class OneVertex:
    """One vertex of a result (or of the truth) shaped like a one-vertex ``curv.Curvature``: what
    :func:`field_values` reads (``k1``, ``k2``, their standard errors, ``quantity``), so that the
    picked vertex's field costs nothing on a large input."""

    def __init__(self, result, index: int) -> None:
        sl = slice(int(index), int(index) + 1)
        self.k1, self.k2 = result.k1[sl], result.k2[sl]
        for name in ("k1_se", "k2_se"):
            se = getattr(result, name, None)
            setattr(self, name, None if se is None else se[sl])

    def quantity(self, name: str) -> np.ndarray:
        """As :meth:`curv.Curvature.quantity`."""
        return compute(name, self.k1, self.k2)


def at_vertex(result, index: int):
    """``result`` (a ``curv.Curvature`` or None) at vertex ``index`` only (:class:`OneVertex`)."""
    return None if result is None else OneVertex(result, index)
