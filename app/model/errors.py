"""Error of an estimate against the analytic truth.

Interim home: this belongs in ``curv`` (the study's metrics); the viewer will import it from there
once the library exposes it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["relative_error"]


def relative_error(estimate, truth) -> np.ndarray:
    """Per-vertex e_rel = (|k1 - k̂1| + |k2 - k̂2|) / (|k1| + |k2|) (paper §5.1).

    Parameters
    ----------
    estimate, truth : curv.Curvature
        Same mesh; ``truth`` holds the exact values.

    Returns
    -------
    (n,) float64
        NaN where the estimate is invalid or the exact curvature is zero (flat point).
    """
    num = np.abs(truth.k1 - estimate.k1) + np.abs(truth.k2 - estimate.k2)
    den = np.abs(truth.k1) + np.abs(truth.k2)
    with np.errstate(invalid="ignore", divide="ignore"):
        e = num / den
    e[~np.isfinite(e)] = np.nan
    return e
