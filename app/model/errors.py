"""Error of an estimate against the analytic truth, as the viewer shows it (numbers from curv.metrics)."""

from __future__ import annotations

import numpy as np
from curv.metrics import curvature_error

__all__ = ["relative_error"]


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
        vertices are drawn grey rather than saturated.
    """
    e = curvature_error(estimate, truth)
    e[~np.isfinite(e)] = np.nan
    return e
