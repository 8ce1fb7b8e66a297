"""Errors of an estimate against exact curvature (paper §5.1, eq. 5.2), per vertex."""

from __future__ import annotations

import numpy as np

from .core.result import Curvature

__all__ = ["absolute_error", "relative_error", "curvature_error"]


def absolute_error(k1, k2, k1_hat, k2_hat) -> np.ndarray:
    """``e_abs = |k1 - k̂1| + |k2 - k̂2|``.

    Parameters
    ----------
    k1, k2 : (n,) float
        Exact principal curvatures, ``k1 >= k2``.
    k1_hat, k2_hat : (n,) float
        Estimates, ``k1_hat >= k2_hat``; NaN where the estimate is invalid.

    Returns
    -------
    (n,) float64
        NaN where an estimate is NaN.
    """
    return np.abs(np.asarray(k1, float) - k1_hat) + np.abs(np.asarray(k2, float) - k2_hat)


def relative_error(k1, k2, k1_hat, k2_hat) -> np.ndarray:
    """``e_rel = e_abs / (|k1| + |k2|)`` (paper eq. 5.2).

    Parameters as in :func:`absolute_error`.

    Returns
    -------
    (n,) float64
        ``inf`` where the exact curvature is zero and the estimate is not; ``0`` where both are
        zero; NaN where the estimate is NaN.
    """
    num = absolute_error(k1, k2, k1_hat, k2_hat)
    den = np.abs(np.asarray(k1, float)) + np.abs(np.asarray(k2, float))
    with np.errstate(divide="ignore", invalid="ignore"):
        out = num / den
    flat = den == 0
    out[flat & (num == 0)] = 0.0
    out[flat & (num > 0)] = np.inf
    return out


def curvature_error(estimate: Curvature, truth: Curvature, *, relative: bool = True) -> np.ndarray:
    """Per-vertex error of ``estimate`` against ``truth`` on the same mesh.

    Returns
    -------
    (n,) float64
        e_rel (or e_abs with ``relative=False``); NaN where the estimate is invalid.
    """
    fn = relative_error if relative else absolute_error
    return fn(truth.k1, truth.k2, estimate.k1, estimate.k2)
