"""What an export of the active pane holds: the result, the extra per-vertex fields and the comment."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .colors import format_limit
from .document import Document
from .scalars import relative_error

__all__ = ["ExportPayload", "export_payload"]


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
    """The export of estimate pane ``i`` (default the active one) as it is shown.

    Raises
    ------
    RuntimeError
        The pane has no result yet.
    """
    i = doc.active if i is None else i
    res = doc.result(i)
    if res is None:
        raise RuntimeError(f"pane {chr(65 + i)} has no result to export yet")
    state = doc.display.state
    q = state.quantity.value
    extra = {}
    field = doc.field(i)
    if field is not None:
        extra["shown"] = np.asarray(field[0], np.float64)
    if doc.truth is not None:
        extra.update({"error_rel": relative_error(res, doc.truth),
                      f"error_{q}": res.quantity(q) - doc.truth.quantity(q),
                      f"exact_{q}": doc.truth.quantity(q)})
    pane = doc.panes[i]
    if field is None:
        comment = f"curvlab: {pane.title}, colours show nothing yet"
    else:
        _, (lo, hi), cmap = field
        comment = (f"curvlab: {pane.title}, colours show {state.field_name()} "
                   f"({cmap.name}, limits {format_limit(lo)} .. {format_limit(hi)}); property 'shown' holds it")
    return ExportPayload(res, extra, comment)
