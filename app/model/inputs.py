"""The two input kinds the viewer shows, a mesh or a point cloud, and the words and lengths that
differ between them (every fact comes from the library)."""

from __future__ import annotations

import numpy as np
from curv import PointCloud
from curv.core.ranges import describe_spacing, point_spacing
from curv.surfaces import SAMPLINGS

__all__ = ["is_points", "unit_length", "item_word", "items_word", "samplings", "can_sample_points", "cloud_report",
           "result_report", "SAMPLING_WORDS", "POINT_SIZES", "DEFAULT_POINT_SIZE", "DEFAULT_KNN"]

POINT_SIZES = (1, 40)
"""The point-size control's range, in pixels."""

DEFAULT_POINT_SIZE = 6
"""Pixels per point when a cloud first shows."""

DEFAULT_KNN = 20
"""The K the Nearest control offers first (about the support of R2 on an even sampling)."""


def is_points(obj) -> bool:
    """Whether ``obj`` (the document's input) is a :class:`curv.PointCloud` (no faces)."""
    return isinstance(obj, PointCloud)


def unit_length(obj) -> float:
    """The input's own length unit, for default radii and glyph lengths: a mesh's mean edge length, a
    point cloud's median spacing (the unit of its range, :func:`curv.core.ranges.point_spacing`; the cloud
    keeps its neighbour search, so the source worker's first question makes later ones cheap)."""
    if not is_points(obj):
        return float(obj.mean_edge_length)
    spacing = point_spacing(obj)
    finite = spacing[np.isfinite(spacing)]
    return float(np.median(finite)) if finite.size else 1.0


SAMPLING_WORDS = {"uniform": "uniform random", "blue": "blue noise", "rows": "scan rows"}
"""How the Source panel names the library's samplings (a new one shows under its own name)."""


def samplings() -> dict[str, str]:
    """How the library samples a surface as points (``curv.surfaces.SAMPLINGS``): ``{name: words}``."""
    return {name: SAMPLING_WORDS.get(name, name) for name in SAMPLINGS}


def can_sample_points(surface_class) -> bool:
    """Whether :func:`curv.surfaces.sample_points` takes this surface (it needs a smooth projection;
    the creased solids have none)."""
    return hasattr(surface_class, "project")


def cloud_report(cloud) -> list[str]:
    """The point-cloud report's lines before any estimate: points, spacing, normals, coincident points
    (the facts are the library's: :func:`curv.core.ranges.describe_spacing`, ``PointCloud.coincident_points``)."""
    lines = [f"{cloud.n_points:,} points, no faces", describe_spacing(cloud)]
    lines.append("normals from the file" if cloud.normals is not None else
                 "no normals in the file: each estimate fits and orients its own")
    lines.append(f"coincident points {int(cloud.coincident_points.sum()):,}")
    return lines


def result_report(result) -> list[str]:
    """What an estimate on a point cloud found out about it (``Curvature.info``): the normals it used,
    border points, ambiguous normal orientations."""
    info = result.info
    if not info.get("points"):
        return []
    normals = info.get("normals")
    said = None if not normals else "normals from the file" if normals == "file" else f"normals estimated ({normals})"
    lines = [said, f"border points {info.get('border_points', 0):,} (on the rim of an open scan)"]
    if info.get("ambiguous_normals"):
        lines.append(f"ambiguous normals {info['ambiguous_normals']:,} (orientation undecided: no estimate there)")
    if info.get("one_sided_normals"):
        lines.append(f"one-sided normals {info['one_sided_normals']:,} (fitted across an empty side: no estimate there)")
    return [line for line in lines if line]


def item_word(obj) -> str:
    """``point`` or ``vertex``: what one element of the input is called."""
    return "point" if is_points(obj) else "vertex"


def items_word(obj) -> str:
    """``points`` or ``vertices``."""
    return "points" if is_points(obj) else "vertices"
