"""Colour mapping of per-vertex values, shared by the PLY export and the viewer.

Signed quantities get a diverging map centred on zero; unsigned ones a sequential map. Limits are
robust percentiles by default, so a few outliers do not wash out the picture. Invalid vertices are
drawn in a neutral grey.
"""

from __future__ import annotations

import numpy as np

__all__ = ["INVALID_RGBA", "SIGNED", "default_cmap", "auto_limits", "map_colors"]

INVALID_RGBA = (150, 150, 150, 255)
"""Neutral grey for vertices without a trustworthy value."""

SIGNED = {"mean": True, "gaussian": True, "k1": True, "k2": True, "shape_index": True,
          "curvedness": False, "error_rel": False, "error": True, "exact": True}
"""Whether a quantity has a meaningful zero (diverging map, symmetric limits)."""


def default_cmap(quantity: str) -> str:
    """``"coolwarm"`` for signed quantities, ``"viridis"`` otherwise."""
    return "coolwarm" if SIGNED.get(quantity, True) else "viridis"


def auto_limits(values: np.ndarray, *, signed: bool, percentiles: tuple[float, float] = (2.0, 98.0)) -> tuple[float, float]:
    """Colour limits from the finite values.

    Parameters
    ----------
    values : (n,) float64
        NaN entries are ignored.
    signed : bool
        Symmetric limits ``(-a, a)`` with ``a`` the larger absolute percentile.
    percentiles : (lo, hi)
        Percentiles in [0, 100].

    Returns
    -------
    (lo, hi) : tuple of float
        ``lo < hi`` always (a constant field gets a small window around its value).
    """
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return (-1.0, 1.0) if signed else (0.0, 1.0)
    lo, hi = np.percentile(finite, percentiles)
    if signed:
        a = float(max(abs(lo), abs(hi)))
        lo, hi = -a, a
    lo, hi = float(lo), float(hi)
    if not hi > lo:
        pad = max(abs(hi), 1.0) * 1e-6
        lo, hi = lo - pad, hi + pad
    return lo, hi


def map_colors(values: np.ndarray, *, cmap: str = "coolwarm", clim: tuple[float, float] | None = None,
               signed: bool = True, valid: np.ndarray | None = None) -> np.ndarray:
    """Map values to RGBA bytes.

    Parameters
    ----------
    values : (n,) float64
    cmap : str
        A matplotlib colour-map name.
    clim : (lo, hi), optional
        Limits; default :func:`auto_limits`.
    signed : bool
        Used for the default limits.
    valid : (n,) bool, optional
        Vertices to colour; the others (and non-finite values) get :data:`INVALID_RGBA`.

    Returns
    -------
    (n, 4) uint8
    """
    from matplotlib import colormaps  # colour tables only; no plotting backend is imported

    values = np.asarray(values, dtype=np.float64)
    lo, hi = clim if clim is not None else auto_limits(values, signed=signed)
    ok = np.isfinite(values)
    if valid is not None:
        ok &= np.asarray(valid, bool)
    t = np.clip((np.where(ok, values, lo) - lo) / (hi - lo), 0.0, 1.0)
    lut = (colormaps[cmap].resampled(256)(np.linspace(0, 1, 256)) * 255).round().astype(np.uint8)
    rgba = lut[np.minimum((t * 256).astype(np.int64), 255)]
    rgba[~ok] = INVALID_RGBA
    return rgba
