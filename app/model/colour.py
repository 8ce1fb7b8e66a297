"""Turning per-vertex values into colours: colour maps, colour limits, RGBA mapping.

Pure numpy; the same RGBA array is drawn by the viewport and written to the exported PLY, so the
file holds exactly the colours on screen.
"""

from __future__ import annotations

import enum
import json
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np

__all__ = [
    "Colormap", "LimitMode", "colormap", "colormap_names", "compute_limits", "map_colours",
    "INVALID_RGBA",
]

INVALID_RGBA = np.array([150, 150, 150, 255], dtype=np.uint8)
"""Neutral grey drawn where a value is NaN (invalid vertex)."""


class LimitMode(enum.Enum):
    """How the colour limits follow the data."""

    PERCENTILE = "percentile"
    MINMAX = "minmax"
    MANUAL = "manual"

    @property
    def title(self) -> str:
        return {"percentile": "Percentile", "minmax": "Min / max", "manual": "Manual"}[self.value]

    def __str__(self) -> str:
        return self.title


@dataclass(frozen=True)
class Colormap:
    """A 256-entry colour table.

    Attributes
    ----------
    name : str
    kind : str
        ``"diverging"`` or ``"sequential"``.
    table : (256, 3) uint8
    """

    name: str
    kind: str
    table: np.ndarray


@lru_cache(maxsize=1)
def _load() -> dict[str, Colormap]:
    text = resources.files("app.resources").joinpath("colormaps.json").read_text(encoding="utf-8")
    out = {}
    for name, spec in json.loads(text).items():
        table = np.frombuffer(bytes.fromhex(spec["colors"]), dtype=np.uint8).reshape(-1, 3)
        table.flags.writeable = False
        out[name] = Colormap(name, spec["kind"], table)
    return out


def colormap_names(kind: str | None = None) -> list[str]:
    """Names of the packaged colour maps, optionally only ``"diverging"`` or ``"sequential"`` ones."""
    return [n for n, c in _load().items() if kind is None or c.kind == kind]


def colormap(name: str) -> Colormap:
    """The packaged colour map ``name`` (``KeyError`` listing the known ones otherwise)."""
    maps = _load()
    if name not in maps:
        raise KeyError(f"unknown colour map {name!r}; known: {', '.join(maps)}")
    return maps[name]


def compute_limits(values: np.ndarray, *, mode: LimitMode, signed: bool,
                   percentiles: tuple[float, float] = (2.0, 98.0),
                   manual: tuple[float, float] = (-1.0, 1.0)) -> tuple[float, float]:
    """Colour limits for ``values`` (NaN ignored).

    Parameters
    ----------
    values : (n,) float
    mode : LimitMode
        ``PERCENTILE``: the ``percentiles`` of the finite values, made symmetric about 0 when
        ``signed`` (±max(|lo|, |hi|)); ``MINMAX``: min and max (symmetric when ``signed``);
        ``MANUAL``: ``manual`` as given.
    signed : bool
        Centre the limits on 0.

    Returns
    -------
    (lo, hi) : tuple of float
        ``lo < hi`` always (a constant field gets a small span around its value).
    """
    if mode is LimitMode.MANUAL:
        lo, hi = sorted(float(x) for x in manual)
        return _widen(lo, hi)
    finite = np.asarray(values, dtype=np.float64)
    finite = finite[np.isfinite(finite)]
    if finite.size == 0:
        return (-1.0, 1.0) if signed else (0.0, 1.0)
    if mode is LimitMode.MINMAX:
        lo, hi = float(finite.min()), float(finite.max())
    else:
        lo, hi = (float(x) for x in np.percentile(finite, percentiles))
    if signed:
        m = max(abs(lo), abs(hi))
        lo, hi = -m, m
    return _widen(lo, hi)


def _widen(lo: float, hi: float) -> tuple[float, float]:
    if hi > lo:
        return lo, hi
    pad = max(abs(lo) * 1e-3, 1e-12)
    return lo - pad, hi + pad


def map_colours(values: np.ndarray, clim: tuple[float, float], cmap: Colormap, *,
                out: np.ndarray | None = None) -> np.ndarray:
    """RGBA colours of ``values`` under ``cmap`` between ``clim``; NaN gets :data:`INVALID_RGBA`.

    Parameters
    ----------
    values : (n,) float
    clim : (lo, hi)
        Values at or below ``lo`` get the first table entry, at or above ``hi`` the last.
    cmap : Colormap
    out : (n, 4) uint8, optional
        Array written in place (e.g. the viewport's colour array).

    Returns
    -------
    (n, 4) uint8
    """
    v = np.asarray(values, dtype=np.float64)
    lo, hi = clim
    n_col = cmap.table.shape[0]
    nan = np.isnan(v)
    t = (v - lo) * ((n_col - 1) / (hi - lo))
    t[nan] = 0.0
    idx = np.clip(np.rint(t), 0, n_col - 1).astype(np.intp)
    if out is None:
        out = np.empty((v.shape[0], 4), dtype=np.uint8)
    out[:, :3] = cmap.table[idx]
    out[:, 3] = 255
    out[nan] = INVALID_RGBA
    return out
