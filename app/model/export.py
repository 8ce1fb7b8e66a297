"""What an export of the active pane holds: the result, the extra per-vertex fields and the comment."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .colors import format_limit
from .document import Document, pane_letter
from .picture import Scene, scene_of, view_fields
from .scalars import relative_error

__all__ = ["ExportPayload", "export_payload", "scene_payload", "export_name", "output_name"]


@dataclass(frozen=True)
class ExportPayload:
    """Everything a PLY/VTU writer needs besides the mesh and the colours.

    Attributes
    ----------
    result : curv.Curvature
    extra : dict of str -> (n,) float64
        ``shown`` (the coloured field) and, for an analytic source, ``error_rel``,
        ``error_<q>`` and ``exact_<q>``.
    comment : str
        Names the field, the estimator, the range, the colour map and the limits.
    """

    result: object
    extra: dict
    comment: str


def export_payload(doc: Document, i: int | None = None) -> ExportPayload:
    """The export of estimate pane ``i`` (default the active one) as it is shown (:func:`scene_payload`
    of the document now).

    Raises
    ------
    RuntimeError
        The pane has no result yet.
    """
    i = doc.active if i is None else i
    return scene_payload(scene_of(doc), doc.panes[i], i)


def scene_payload(scene: Scene, pane, i: int) -> ExportPayload:
    """The export of estimate pane ``i`` (a :class:`~app.model.Pane`, for its title) of ``scene``; safe
    in a worker thread.

    Raises
    ------
    RuntimeError
        The pane has no result yet.
    """
    res = scene.results[i]
    if res is None:
        raise RuntimeError(f"pane {pane_letter(i)} has no result to export yet")
    state = scene.state
    q = state.quantity.value
    extra = {}
    field = view_fields(scene)[i]
    if field is not None:
        extra["shown"] = np.asarray(field[0], np.float64)
    truth = scene.truth
    if truth is not None:
        extra.update({"error_rel": relative_error(res, truth),
                      f"error_{q}": res.quantity(q) - truth.quantity(q),
                      f"exact_{q}": truth.quantity(q)})
    if field is None:
        comment = f"curvlab: {pane.title}, colours show nothing yet"
    else:
        _, (lo, hi), cmap = field
        comment = (f"curvlab: {pane.title}, colours show {state.field_name()} "
                   f"({cmap.name}, limits {format_limit(lo)} .. {format_limit(hi)}); property 'shown' holds it")
    return ExportPayload(res, extra, comment)


def export_name(doc: Document, suffix: str) -> str:
    """The file name an export of the active pane suggests: ``<input>-<method>-<range><suffix>``, e.g.
    ``bunny-mru-R2.ply`` or ``torus-jet-r0.05.vtu`` (the feature angle and a region added when set:
    ``part-qs-R2-features30-region.ply``); characters a file name should not hold become ``_``."""
    source = doc.source
    stem = Path(source.path).stem if hasattr(source, "path") else getattr(source, "name", "") or "curvlab"
    return output_name(stem, doc.panes[doc.active], suffix)


def output_name(stem: str, pane, suffix: str, *, region: bool = True) -> str:
    """``<stem>-<method>-<range>[-features<angle>][-region]<suffix>`` for ``pane`` (:func:`export_name`;
    ``region=False`` for a run that ignores the pane's region, such as a whole file's)."""
    parts = [stem, pane.method, pane.label.replace("=", "")]
    if pane.features is not None:
        parts.append(f"features{pane.features:g}")
    if region and pane.region is not None:
        parts.append("region")
    name = "-".join(parts)
    return re.sub(r"[^A-Za-z0-9._+-]+", "_", name) + suffix
