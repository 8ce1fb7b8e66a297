"""Colour mapping of per-vertex values, shared by the PLY export and the viewer.

Signed quantities whose values straddle zero get a diverging map centred on zero; everything else
(unsigned quantities, and signed ones of one sign, such as H on a torus) a sequential map over the
values' own span, so that the whole map is used. A quantity with a natural range (shape index)
is drawn over that range. Limits are robust percentiles by default, so a few outliers do not wash
out the picture. Invalid vertices are drawn in a colour none of the maps uses near its middle.
"""

from __future__ import annotations

import numpy as np

from .core.jit import jit
from .core.quantities import QUANTITIES

__all__ = ["INVALID_RGBA", "SIGNED", "CLIP_SHADE", "CLIP_MARGIN", "auto_limits", "diverges", "widen", "check_cmap",
           "check_limits", "colour_choice", "colour_table", "apply_table", "map_colors", "DIVERGING", "SEQUENTIAL"]

DIVERGING = "coolwarm"
"""The default map of signed values that straddle zero."""

SEQUENTIAL = "viridis"
"""The default map of everything else."""

INVALID_RGBA = (214, 0, 214, 255)
"""Magenta for vertices without a trustworthy value: no packaged map has it near its middle
(a neutral grey would read as coolwarm's zero)."""

CLIP_SHADE = 0.6
"""Values beyond the colour limits are drawn in the map's end colours darkened by this factor."""

CLIP_MARGIN = 0.05
"""Values beyond a limit by less than this share of the limits' span are not shaded as clipped: the
robust percentile limits cut into the surface's own extremes (a torus's inner equator, 1.6 % of
its vertices), and shading that ring drew a dark zig-zag line that looked like a seam."""

SIGNED = {**{q.name: q.signed for q in QUANTITIES.values()}, "error_rel": False, "error": True, "exact": True}
"""Whether a quantity has a meaningful zero (diverging map, symmetric limits when it straddles 0)."""


def check_cmap(name: str) -> str:
    """``name`` if matplotlib knows the colour map; ``ValueError`` in one line naming a few otherwise."""
    from matplotlib import colormaps

    if name not in colormaps:
        import difflib

        close = difflib.get_close_matches(str(name), list(colormaps), n=3)
        hint = f"did you mean {', '.join(close)}? " if close else ""
        raise ValueError(f"unknown colour map {name!r}; {hint}any matplotlib map works, e.g. {DIVERGING}, "
                         f"{SEQUENTIAL}, RdBu, plasma")
    return name


def check_limits(lo: float, hi: float) -> tuple[float, float]:
    """``(lo, hi)`` if both are finite and ``lo < hi``; ``ValueError`` in one line otherwise."""
    lo, hi = float(lo), float(hi)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise ValueError(f"colour limits must be finite numbers; got {lo:g} .. {hi:g}")
    if not lo < hi:
        raise ValueError(f"colour limits must have LO < HI; got {lo:g} .. {hi:g}")
    return lo, hi


def colour_choice(values: np.ndarray, valid: np.ndarray, quantity: str, *, cmap: str | None = None,
                  clim: tuple[float, float] | None = None) -> tuple[str, tuple[float, float]]:
    """The colour map and limits an export draws ``values`` of ``quantity`` with: the one colouring rule.

    Parameters
    ----------
    values : (n,) float
    valid : (n,) bool
        Vertices whose values count for the automatic limits.
    quantity : str
        A :data:`curv.core.quantities.QUANTITIES` name (or ``error_rel``...), for its sign and natural range.
    cmap, clim : optional
        The caller's choice; checked (:func:`check_cmap`, :func:`check_limits`) and kept.

    Returns
    -------
    (cmap, (lo, hi))
        Default limits: robust percentiles (:func:`auto_limits`); default map: :data:`DIVERGING`
        for signed values straddling zero, else :data:`SEQUENTIAL`.
    """
    signed = SIGNED.get(quantity, True)
    spec = QUANTITIES.get(quantity)
    if clim is not None:
        lim = check_limits(*clim)
    else:
        lim = auto_limits(values[valid], signed=signed, natural=spec.natural if spec else None)
    if cmap is not None:
        return check_cmap(cmap), lim
    return (DIVERGING if diverges(lim, signed=signed) else SEQUENTIAL), lim


def diverges(clim: tuple[float, float], *, signed: bool) -> bool:
    """True when a field is drawn with a diverging map: signed and its limits straddle zero."""
    return bool(signed and clim[0] < 0.0 < clim[1])


def auto_limits(values: np.ndarray, *, signed: bool, percentiles: tuple[float, float] = (2.0, 98.0),
                minmax: bool = False, natural: tuple[float, float] | None = None) -> tuple[float, float]:
    """Colour limits from the finite values.

    Parameters
    ----------
    values : (n,) float64
        NaN entries are ignored.
    signed : bool
        Symmetric limits ``(-a, a)`` with ``a`` the larger absolute bound, when the values
        straddle zero (values of one sign keep their own span).
    percentiles : (lo, hi)
        Percentiles in [0, 100].
    minmax : bool
        Use the minimum and maximum instead of the percentiles.
    natural : (lo, hi), optional
        The quantity's own range (shape index: (-1, 1)); returned as it is.

    Returns
    -------
    (lo, hi) : tuple of float
        ``lo < hi`` always (a constant field gets a small window around its value).
    """
    if natural is not None:
        return float(natural[0]), float(natural[1])
    v = np.asarray(values, dtype=np.float64)
    finite = v[np.isfinite(v)]
    if finite.size == 0:
        return (-1.0, 1.0) if signed else (0.0, 1.0)
    if minmax:
        lo, hi = float(finite.min()), float(finite.max())
    else:
        lo, hi = (float(x) for x in np.percentile(finite, percentiles))
    if signed and lo < 0.0 < hi:
        a = max(abs(lo), abs(hi))
        lo, hi = -a, a
    return widen(lo, hi)


def widen(lo: float, hi: float) -> tuple[float, float]:
    """``(lo, hi)`` unchanged when ``hi > lo`` by more than rounding, else a small window around the value."""
    if hi - lo > 1e-9 * max(abs(lo), abs(hi)):
        return lo, hi
    pad = max(abs(lo) * 1e-3, 1e-12)
    return lo - pad, hi + pad


def colour_table(cmap: str, size: int = 256) -> np.ndarray:
    """(size, 3) uint8 RGB table of a matplotlib colour map."""
    from matplotlib import colormaps  # colour tables only; no plotting backend is imported

    return (colormaps[cmap].resampled(size)(np.linspace(0, 1, size))[:, :3] * 255).round().astype(np.uint8)


def apply_table(values: np.ndarray, clim: tuple[float, float], table: np.ndarray, *,
                valid: np.ndarray | None = None, out: np.ndarray | None = None,
                clip_shade: float | None = None) -> np.ndarray:
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
    clip_shade : float, optional
        Values beyond the limits by more than :data:`CLIP_MARGIN` of their span get the end
        colours times this factor (see :data:`CLIP_SHADE`), so that clipping is visible; default:
        plain end colours.

    Returns
    -------
    (n, 4) uint8
    """
    v = np.ascontiguousarray(values, dtype=np.float64)
    lo, hi = float(clim[0]), float(clim[1])
    if out is None:
        out = np.empty((v.shape[0], 4), dtype=np.uint8)
    mask = np.ones(0, np.bool_) if valid is None else np.ascontiguousarray(valid, dtype=np.bool_)
    shade = -1.0 if clip_shade is None else float(clip_shade)
    _apply_table_kernel(v, mask, lo, hi, np.ascontiguousarray(table, dtype=np.uint8), shade, CLIP_MARGIN * (hi - lo),
                        np.asarray(INVALID_RGBA, np.uint8), out)
    return out


@jit
def _apply_table_kernel(v, valid, lo, hi, table, shade, margin, invalid, out):
    """Per vertex: the nearest table entry of its value (ends beyond the limits, shaded when
    ``shade >= 0`` and beyond by more than ``margin``), or ``invalid`` (empty ``valid``: all valid).

    Serial on purpose: the viewer colours on its GUI thread while a worker runs the estimators'
    parallel kernels, and numba's thread pool takes one parallel launch at a time
    (:func:`curv.core.jit.launch`); a serial loop neither waits for that nor disturbs it.
    """
    k = table.shape[0]
    scale = (k - 1) / (hi - lo)
    check = valid.shape[0] > 0
    for i in range(v.shape[0]):
        value = v[i]
        if not np.isfinite(value) or (check and not valid[i]):
            for c in range(4):
                out[i, c] = invalid[c]
            continue
        t = (value - lo) * scale
        j = 0 if t <= 0.0 else (k - 1 if t >= k - 1 else int(np.rint(t)))
        factor = shade if shade >= 0.0 and (value < lo - margin or value > hi + margin) else 1.0
        for c in range(3):
            out[i, c] = table[j, c] if factor == 1.0 else np.uint8(int(table[j, c] * factor))
        out[i, 3] = 255


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
