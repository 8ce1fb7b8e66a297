"""Turning per-vertex values into colours: colour maps, colour limits, RGBA mapping.

Pure numpy; the same RGBA array is drawn by the viewport and written to the exported files, so a
file holds exactly the colours on screen. The rules (symmetric limits only for signed values that
straddle zero, natural ranges, visible clipping, the invalid colour) are :mod:`curv.colors`'.
"""

from __future__ import annotations

import enum
import json
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from curv.colors import CLIP_SHADE, apply_table, auto_limits, diverges, widen
from curv.colors import INVALID_RGBA as _CURV_INVALID

from app.packaged import resource

__all__ = [
    "Colormap", "LimitMode", "colormap", "colormap_names", "compute_limits", "map_colours", "diverges",
    "format_limit", "LABEL_FORMAT", "INVALID_RGBA", "contrasting_colours",
]

INVALID_RGBA = np.array(_CURV_INVALID, dtype=np.uint8)
"""Drawn where a value is NaN (invalid vertex): a colour no map has near its middle."""

LABEL_FORMAT = "%.4g"
"""printf form of :func:`format_limit`, for the VTK colour bar."""


def format_limit(value: float) -> str:
    """A colour limit as every widget writes it (4 significant digits: ``1629``, ``-0.0123``)."""
    return LABEL_FORMAT % value


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
    text = resource("colormaps.json").read_text(encoding="utf-8")
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
                   manual: tuple[float, float] = (-1.0, 1.0),
                   natural: tuple[float, float] | None = None) -> tuple[float, float]:
    """Colour limits for ``values`` (NaN ignored), as :func:`curv.colors.auto_limits` computes them.

    ``MANUAL`` returns ``manual`` sorted (widened if empty); ``MINMAX`` and ``PERCENTILE`` follow
    the data, symmetric about 0 when ``signed`` and the values straddle 0, or give the quantity's
    ``natural`` range when it has one. Always ``lo < hi``.
    """
    if mode is LimitMode.MANUAL:
        lo, hi = sorted(float(x) for x in manual)
        return widen(lo, hi)
    return auto_limits(values, signed=signed, percentiles=percentiles, minmax=mode is LimitMode.MINMAX,
                       natural=natural)


def map_colours(values: np.ndarray, clim: tuple[float, float], cmap: Colormap, *,
                out: np.ndarray | None = None) -> np.ndarray:
    """RGBA colours of ``values`` under ``cmap`` between ``clim``; NaN gets :data:`INVALID_RGBA`.

    Values beyond the limits get the map's end colours darkened (:data:`curv.colors.CLIP_SHADE`),
    so clipping shows on the mesh.
    """
    return apply_table(values, clim, cmap.table, out=out, clip_shade=CLIP_SHADE)


_OVERLAY_CANDIDATES = {
    "black": (20, 20, 20), "white": (255, 255, 255), "cyan": (0, 229, 255), "green": (0, 190, 0),
    "orange": (255, 140, 0), "blue": (0, 70, 255), "red": (230, 0, 0),
}


def contrasting_colours(cmap: Colormap, count: int = 2, *, avoid=()) -> list[tuple[int, int, int]]:
    """``count`` overlay colours (glyphs, markers) that stand out against every entry of ``cmap``.

    Picks, from a small palette, the colours whose nearest table entry is farthest away (and not
    the invalid colour or any of ``avoid``), so that d1/d2 lines stay visible on dark viridis as
    well as on coolwarm's light middle.
    """
    table = cmap.table.astype(float)
    taken = [np.asarray(INVALID_RGBA[:3], float)] + [np.asarray(a, float) for a in avoid]
    out = []
    for _ in range(count):
        def score(rgb):
            rgb = np.asarray(rgb, float)
            near_map = np.min(np.linalg.norm(table - rgb, axis=1))
            near_taken = min(np.linalg.norm(rgb - t) for t in taken)
            return min(near_map, near_taken)
        best = max(_OVERLAY_CANDIDATES.values(), key=score)
        out.append(best)
        taken.append(np.asarray(best, float))
    return out
