"""The scalar field of a pane under the display settings (estimate, exact value or error)."""

from __future__ import annotations

import numpy as np

from .display import DisplayState, Layer
from .errors import relative_error

__all__ = ["field_values"]


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
    est = np.asarray(result.quantity(name), dtype=np.float64)
    if layer is Layer.ERROR:
        return est - truth.quantity(name)
    return est
