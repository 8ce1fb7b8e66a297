"""Colour mapping of per-vertex values, shared by the PLY export and the viewer.

Signed quantities get a diverging map centred on zero; unsigned ones a sequential map. Limits are
robust percentiles by default, so a few outliers do not wash out the picture. Invalid vertices are
drawn in a neutral grey.
"""

from __future__ import annotations

import numpy as np

__all__ = ["INVALID_RGBA", "SIGNED", "default_cmap", "auto_limits", "widen", "colour_table", "apply_table", "map_colors"]

INVALID_RGBA = (150, 150, 150, 255)
"""Neutral grey for vertices without a trustworthy value."""

SIGNED = {"mean": True, "gaussian": True, "k1": True, "k2": True, "shape_index": True,
          "curvedness": False, "error_rel": False, "error": True, "exact": True}
"""Whether a quantity has a meaningful zero (diverging map, symmetric limits)."""


def default_cmap(quantity: str) -> str:
    """``"coolwarm"`` for signed quantities, ``"viridis"`` otherwise."""
    return "coolwarm" if SIGNED.get(quantity, True) else "viridis"


def auto_limits(values: np.ndarray, *, signed: bool, percentiles: tuple[float, float] = (2.0, 98.0),
                minmax: bool = False) -> tuple[float, float]:
    """Colour limits from the finite values.

    Parameters
    ----------
    values : (n,) float64
        NaN entries are ignored.
    signed : bool
        Symmetric limits ``(-a, a)`` with ``a`` the larger absolute bound.
    percentiles : (lo, hi)
        Percentiles in [0, 100].
    minmax : bool
        Use the minimum and maximum instead of the percentiles.

    Returns
    -------
    (lo, hi) : tuple of float
        ``lo < hi`` always (a constant field gets a small window around its value).
    """
    v = np.asarray(values, dtype=np.float64)
    finite = v[np.isfinite(v)]
    if finite.size == 0:
        return (-1.0, 1.0) if signed else (0.0, 1.0)
    if minmax:
        lo, hi = float(finite.min()), float(finite.max())
    else:
        lo, hi = (float(x) for x in np.percentile(finite, percentiles))
    if signed:
        a = max(abs(lo), abs(hi))
        lo, hi = -a, a
    return widen(lo, hi)


def widen(lo: float, hi: float) -> tuple[float, float]:
    """``(lo, hi)`` unchanged when ``hi > lo``, else a small window around the value."""
    if hi > lo:
        return lo, hi
    pad = max(abs(lo) * 1e-3, 1e-12)
    return lo - pad, hi + pad


def colour_table(cmap: str, size: int = 256) -> np.ndarray:
    """(size, 3) uint8 RGB table of a matplotlib colour map."""
    from matplotlib import colormaps  # colour tables only; no plotting backend is imported

    return (colormaps[cmap].resampled(size)(np.linspace(0, 1, size))[:, :3] * 255).round().astype(np.uint8)


def apply_table(values: np.ndarray, clim: tuple[float, float], table: np.ndarray, *,
                valid: np.ndarray | None = None, out: np.ndarray | None = None) -> np.ndarray:
    """RGBA colours of ``values`` through an RGB ``table`` between ``clim``.

    Parameters
    ----------
    values : (n,) float
    clim : (lo, hi)
        Values at or below ``lo`` get the first entry, at or above ``hi`` the last; linear between,
        rounded to the nearest entry.
    table : (k, 3) uint8
    valid : (n,) bool, optional
        Vertices to colour; the others, and non-finite values, get :data:`INVALID_RGBA`.
    out : (n, 4) uint8, optional
        Written in place (e.g. a viewport's colour array).

    Returns
    -------
    (n, 4) uint8
    """
    v = np.asarray(values, dtype=np.float64)
    lo, hi = clim
    k = table.shape[0]
    bad = ~np.isfinite(v)
    if valid is not None:
        bad |= ~np.asarray(valid, bool)
    t = np.where(bad, 0.0, (v - lo) * ((k - 1) / (hi - lo)))
    idx = np.clip(np.rint(t), 0, k - 1).astype(np.intp)
    if out is None:
        out = np.empty((v.shape[0], 4), dtype=np.uint8)
    out[:, :3] = table[idx]
    out[:, 3] = 255
    out[bad] = INVALID_RGBA
    return out


def map_colors(values: np.ndarray, *, cmap: str = "coolwarm", clim: tuple[float, float] | None = None,
               signed: bool = True, valid: np.ndarray | None = None) -> np.ndarray:
    """Map values to RGBA bytes with a matplotlib colour map.

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
    lim = clim if clim is not None else auto_limits(values, signed=signed)
    return apply_table(values, lim, colour_table(cmap), valid=valid)
