"""Estimating in a region: which vertices, and how a region's result is shown over the rest of the mesh.

A pane with a :class:`Region` computes its estimator only at the region's vertices
(``curv.estimate(..., vertices=idx)``). On screen the region's values lie over the rest of the
mesh: where the same estimator, range and feature angle has been computed on the whole mesh, the
rest keeps those values and colours; otherwise the rest is drawn neutral grey (not the magenta of
invalid vertices) and reads "outside the region".
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field, replace

import numpy as np
from curv.geometry.region import vertices_in_ball
from curv.core.validity import Reason

from .text import count_text

__all__ = ["Region", "ball_region", "index_region", "show_region", "shown_region", "over_rest", "outside_region",
           "RestComposer", "REST_NOTE", "REST_COLOUR"]

REST_NOTE = ("Outside the region the pane keeps the whole-mesh result of the same estimator, range and "
             "feature angle when it has been computed; otherwise the rest is mid grey.")

REST_COLOUR = np.array([150, 150, 150, 255], dtype=np.uint8)
"""RGBA of the vertices outside a region that have no whole-mesh result to show: a mid grey, darker than
the centre colour of the diverging maps and than the grey of a pane without results."""

_serials = itertools.count(1)


@dataclass(frozen=True)
class Region:
    """The vertices a pane is estimated at.

    Two regions are the same when their label and serial are (the index array is not compared:
    a new region always gets a new serial).

    Attributes
    ----------
    label : str
        What the region is, for pane titles: ``0.5 around vertex 12`` or ``in view of pane A``.
    vertices : (c,) int64
        Vertex indices, sorted.
    serial : int
        Distinguishes regions of equal labels (a new view, a new pick).
    centre : int or None
        The vertex a ball region is centred on (None for other regions).
    """

    label: str
    vertices: np.ndarray = field(compare=False, hash=False, repr=False)
    serial: int = 0
    centre: int | None = field(default=None, compare=False)

    @property
    def size(self) -> int:
        return int(self.vertices.size)

    @property
    def title(self) -> str:
        """``region 0.5 around vertex 12 (1,234 vertices)``."""
        return f"region {self.label} ({count_text(self.size, 'vertex', 'vertices')})"


def index_region(label: str, vertices, *, centre: int | None = None) -> Region:
    """A new :class:`Region` of the given vertex indices (sorted, duplicates dropped)."""
    return Region(label, np.unique(np.asarray(vertices, dtype=np.int64)), next(_serials), centre)


def ball_region(mesh, centre: int, radius: float) -> Region:
    """The vertices within ``radius`` (mesh units) of vertex ``centre``, as :func:`curv.geometry.region.vertices_in_ball`
    finds them (``EstimatorError`` for a radius that is not a positive length)."""
    idx = vertices_in_ball(mesh, mesh.vertices[int(centre)], radius)
    return index_region(f"{radius:g} around vertex {int(centre)}", idx, centre=int(centre))


def show_region(doc, region: Region | None) -> None:
    """Estimate every pane of ``doc`` (a :class:`~app.model.Document`) in ``region`` (None: the whole
    mesh again); an earlier failure or cancel of the same setting is tried again."""
    for i, pane in enumerate(doc.panes):
        doc.retry(replace(pane, region=region).key)
        doc.set_pane(i, region=region)


def shown_region(doc) -> Region | None:
    """The region of the active pane, or None."""
    return doc.panes[doc.active].region


def over_rest(part, rest, region: Region):
    """The region's result ``part`` shown over ``rest``, the whole-mesh result of the same setting.

    Parameters
    ----------
    part : curv.Curvature
        Full-length result of ``estimate(..., vertices=region.vertices)`` (NaN and ``NOT_COMPUTED``
        outside the region).
    rest : curv.Curvature or None
        The whole-mesh result, or None (then ``part`` is returned as it is).
    region : Region

    Returns
    -------
    curv.Curvature
        ``part``'s values at the region's vertices and ``rest``'s elsewhere; ``info`` is ``part``'s.
    """
    if rest is None:
        return part
    idx = region.vertices
    merged = {}
    for name in ("k1", "k2", "d1", "d2", "valid", "reason", "k1_se", "k2_se"):
        arr = getattr(rest, name).copy()
        arr[idx] = getattr(part, name)[idx]
        merged[name] = arr
    return replace(part, **merged)


def outside_region(result, region: Region | None) -> np.ndarray | None:
    """(n,) bool: vertices the region's result leaves uncomputed (drawn neutral), or None for a whole-mesh pane."""
    if region is None or result is None:
        return None
    outside = result.reason == Reason.NOT_COMPUTED
    outside[region.vertices] = False
    return outside


class RestComposer:
    """Remembers the last :func:`over_rest` of each pane key, so that drawing, the readout and the
    histogram of a large mesh do not merge the arrays again on every call."""

    KEEP = 4

    def __init__(self) -> None:
        self._memo: dict = {}

    def get(self, key, part, rest, region: Region):
        """``over_rest(part, rest, region)``, reused while ``part`` and ``rest`` are the same objects."""
        hit = self._memo.get(key)
        if hit is not None and hit[0] is part and hit[1] is rest:
            return hit[2]
        out = over_rest(part, rest, region)
        self._memo.pop(key, None)
        self._memo[key] = (part, rest, out)
        while len(self._memo) > self.KEEP:  # a merged 10M-vertex result is large: keep the newest few
            self._memo.pop(next(iter(self._memo)))
        return out

    def clear(self) -> None:
        self._memo.clear()
