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
from curv.colors import INVALID_RGBA as _CURV_INVALID
from curv.colors import apply_table, auto_limits, widen

__all__ = [
    "Colormap", "LimitMode", "colormap", "colormap_names", "compute_limits", "map_colours",
    "INVALID_RGBA",
]

INVALID_RGBA = np.array(_CURV_INVALID, dtype=np.uint8)
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
    """Colour limits for ``values`` (NaN ignored), as :func:`curv.colors.auto_limits` computes them.

    ``MANUAL`` returns ``manual`` sorted (widened if empty); ``MINMAX`` and ``PERCENTILE`` follow
    the data, symmetric about 0 when ``signed``. Always ``lo < hi``.
    """
    if mode is LimitMode.MANUAL:
        lo, hi = sorted(float(x) for x in manual)
        return widen(lo, hi)
    return auto_limits(values, signed=signed, percentiles=percentiles, minmax=mode is LimitMode.MINMAX)


def map_colours(values: np.ndarray, clim: tuple[float, float], cmap: Colormap, *,
                out: np.ndarray | None = None) -> np.ndarray:
    """RGBA colours of ``values`` under ``cmap`` between ``clim``; NaN gets :data:`INVALID_RGBA`.

    The same mapping as :func:`curv.colors.apply_table`, with the packaged table of ``cmap``.
    """
    return apply_table(values, clim, cmap.table, out=out)
