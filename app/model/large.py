"""Files too large to draw whole: the preview the viewer shows, and a region read at full resolution.

A file whose header counts more points (vertices) than :data:`PREVIEW_LIMIT` opens as a
:class:`PreviewSource`: a decimated preview (:func:`curv.tiles.preview.read_preview`) that says what it
shows (``1,000,000 of 100,000,000 points shown (every 100th)``). Its estimates are the preview's;
the full resolution is read around a picked point (:class:`FullResolutionSource`, a piece of the file
with the halo its estimates read, every pane estimated at the points within the radius) or for
the whole file into an output file (:func:`curv.tiles.estimate_file`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from curv.tiles.preview import PREVIEW_POINTS

from .sources import FileSource

__all__ = ["PREVIEW_LIMIT", "PreviewSource", "FullResolutionSource", "whole_file_suffixes", "pane_job"]

PREVIEW_LIMIT = PREVIEW_POINTS
"""Points (vertices) above which a file opens as a preview."""


@dataclass(frozen=True)
class PreviewSource(FileSource):
    """A large file shown as a decimated preview.

    Attributes
    ----------
    total : int
        Points (vertices) in the file.
    words : str
        What the preview shows, e.g. ``1,000,000 of 100,000,000 points shown (every 100th)``.
    """

    total: int = 0
    words: str = ""

    @property
    def label(self) -> str:
        return f"{Path(self.path).name} (preview)"


@dataclass(frozen=True)
class FullResolutionSource(FileSource):
    """The points of a large file within ``radius`` of ``centre`` at full resolution, with the halo the
    panes' estimates read (``jobs``: ``(method, range, options)`` per pane).

    ``ball`` (the rows within the radius) is known once the piece is read: the loader returns the
    source with it.
    """

    centre: tuple = (0.0, 0.0, 0.0)
    radius: float = 1.0
    jobs: tuple = ()
    ball: object = field(default=None, compare=False, hash=False, repr=False)

    @property
    def label(self) -> str:
        x, y, z = self.centre
        return f"{Path(self.path).name}: {self.radius:g} around ({x:.6g}, {y:.6g}, {z:.6g}), full resolution"

    @property
    def region_label(self) -> str:
        return f"{self.radius:g} at full resolution"


def whole_file_suffixes(path) -> list[str]:
    """The outputs a whole-file run of ``path`` can write, its own kind first (curv's rule:
    :func:`curv.tiles.output_suffixes`)."""
    from curv.tiles import output_suffixes

    return output_suffixes(path)


def pane_job(pane) -> tuple:
    """``(method, range, keywords)`` of a pane's estimate, for a tiled run (no region)."""
    kwargs = pane.estimate_kwargs()
    kwargs.pop("vertices", None)
    rng = kwargs.pop("range", None)
    return pane.method, rng, kwargs
