"""The picked-vertex readout as rows of text: one column per pane, A − B, and the exact values."""

from __future__ import annotations

import numpy as np
from curv.core.validity import Reason

from .document import Document, pane_letter
from .scalars import at_vertex, relative_error

__all__ = ["readout_columns", "readout_rows", "fmt", "fmt_se", "fmt_vec", "REASON_WORDS"]


def fmt(x) -> str:
    """A value of the readout (``—`` where there is none)."""
    return "—" if x is None or not np.isfinite(x) else f"{x:.5g}"


def fmt_se(x) -> str:
    """An uncertainty of the readout: two significant digits (``0.042``)."""
    return f"{x:.2g}"


def fmt_vec(v, *, stacked: bool = False) -> str:
    """``(+0.100, -0.200, +0.975)``, or its three components one per line when ``stacked``."""
    if not np.all(np.isfinite(v)):
        return "—"
    parts = [f"{c:+.3f}" for c in v]
    return "\n".join(parts) if stacked else "(" + ", ".join(parts) + ")"


REASON_WORDS = {
    Reason.BORDER: "on or near a border",
    Reason.TOO_FEW_NEIGHBOURS: "too few neighbours in range",
    Reason.SINGULAR: "singular fit",
    Reason.DEGENERATE: "degenerate surroundings",
    Reason.NONMANIFOLD: "non-manifold",
    Reason.NOT_COMPUTED: "not computed",
    Reason.FEATURE: "on a crease (feature edge)",
    Reason.ORIENTATION: "normal orientation undecided",
}
"""What the readout says for each :class:`curv.Reason` of an invalid vertex."""


def _reason(r, index) -> str:
    if r.valid[index]:
        return "valid"
    code = int(r.reason[index]) if r.reason is not None else 0
    if code == Reason.NOT_COMPUTED and r.info.get("region", r.n) < r.n:
        return "outside the region"
    try:
        return REASON_WORDS[Reason(code)]
    except (ValueError, KeyError):
        return f"invalid ({code})"


def readout_columns(doc: Document, *, short: bool = False) -> list[str]:
    """Column headings: ``A: mru R2`` (``A`` when ``short``), ..., ``A − B`` when the difference pane
    is on, ``exact``."""
    heads = [pane_letter(j) if short else f"{pane_letter(j)}: {pane.title}" for j, pane in enumerate(doc.panes)]
    if doc.view_count > len(doc.panes):
        heads.append("A − B")
    if doc.truth is not None:
        heads.append("exact")
    return heads


def readout_rows(doc: Document, index: int, *, stacked: bool = False) -> list[tuple[str, list[str]]]:
    """Rows ``(label, [value per column])`` for vertex ``index``, columns as :func:`readout_columns`.

    Rows: k1, k2 (``0.52 ± 0.04``: two standard errors, where the estimator gives them), H, K, d1, d2 (components one per line when ``stacked``), the status (``valid`` or
    the :class:`curv.Reason`), the shown field and, for an analytic source, e_rel.
    """
    cols = [doc.result(i) for i in range(len(doc.panes))]
    diff = doc.view_count > len(doc.panes)
    a, b = (cols[0], cols[1]) if diff else (None, None)
    truth = doc.truth
    values = [doc.value_at(i, index) for i in range(doc.view_count)]

    def scalar_row(label, get):
        row = [fmt(get(r)) if r is not None else "…" for r in cols]
        if diff:
            row.append(fmt(get(a) - get(b)) if a is not None and b is not None else "…")
        if truth is not None:
            row.append(fmt(get(truth)))
        return (label, row)

    def vector_row(label, get):
        row = [fmt_vec(get(r), stacked=stacked) if r is not None else "…" for r in cols]
        row += [""] * diff + ([fmt_vec(get(truth), stacked=stacked)] if truth is not None else [])
        return (label, row)

    def principal_row(name):
        """k1 or k2, as ``0.52 ± 0.04`` (2 standard errors) where the estimate has a standard error."""
        label, row = scalar_row(name, lambda r: getattr(r, name)[index])
        ses = [getattr(r, f"{name}_se")[index] if r is not None else np.nan for r in cols]
        for j, se in enumerate(ses):
            if np.isfinite(se) and row[j] != "—":
                row[j] = f"{row[j]} ± {fmt_se(2.0 * se)}"
        return (f"{name} ± 2σ" if np.isfinite(ses).any() else label, row)

    rows = [principal_row("k1"), principal_row("k2"),
            # H and K of the one vertex: a result's own .mean and .gaussian compute every vertex's
            scalar_row("H", lambda r: at_vertex(r, index).quantity("mean")[0]),
            scalar_row("K", lambda r: at_vertex(r, index).quantity("gaussian")[0]),
            vector_row("d1", lambda r: r.d1[index]), vector_row("d2", lambda r: r.d2[index])]
    status = [_reason(r, index) if r is not None else "…" for r in cols]
    status += [""] * diff + (["exact"] if truth is not None else [])
    rows.append(("status", status))
    shown = [fmt(v) if v is not None else "…" for v in values]
    shown += [""] if truth is not None else []
    rows.append(("shown", shown))
    if truth is not None:
        errs = [fmt(relative_error(at_vertex(r, index), at_vertex(truth, index))[0]) if r is not None else "…" for r in cols]
        rows.append(("e_rel", errs + [""] * diff + [""]))
    return rows

