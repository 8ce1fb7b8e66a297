"""What persists between sessions besides the window layout: quantity, field shown, colour maps,
limits, panes (with their feature angles) and the difference pane. Regions do not persist: they
name vertices of one mesh."""

from __future__ import annotations

import json

from PySide6.QtCore import QSettings

from app.model import Document, Layer, LimitMode, Pane, Quantity, colormap_names

__all__ = ["restore_session", "save_session"]


def restore_session(settings: QSettings, doc: Document) -> None:
    """Apply the saved quantity, field shown (Show), colour maps, limits (mode, percentiles, manual,
    lock), panes and difference pane to ``doc``.

    Unreadable or stale entries (an estimator that no longer exists, ...) are ignored. A field that
    needs an analytic truth goes back to the estimate when the mesh that opens has none.
    """
    changes = {}
    for key, kind in (("quantity", Quantity), ("layer", Layer)):
        try:
            changes[key] = kind(str(settings.value(f"display/{key}")))
        except ValueError:
            pass
    for key, kind in (("diverging_cmap", "diverging"), ("sequential_cmap", "sequential")):
        value = settings.value(f"cmap/{key}")
        if value and str(value) in colormap_names(kind):
            changes[key] = str(value)
    try:
        mode = settings.value("limits/mode")
        if mode:
            changes["limit_mode"] = LimitMode(str(mode))
        for key in ("percentiles", "manual"):
            value = settings.value(f"limits/{key}")
            if value:
                lo, hi = (float(x) for x in json.loads(str(value)))
                changes[key] = (lo, hi)
        changes["lock_limits"] = str(settings.value("limits/lock", "false")).lower() == "true"
    except (ValueError, TypeError):
        pass
    doc.display.update(**changes)
    try:
        saved = json.loads(str(settings.value("panes", "[]")))
        panes = [Pane(p["method"], p["range"], p.get("radius"), p.get("features"),
                      options=tuple(tuple(o) for o in p.get("options", ()))).validated() for p in saved]
    except (ValueError, TypeError, KeyError, LookupError):
        return
    if panes:
        doc.set_pane_count(len(panes))
        for i, pane in enumerate(panes):
            doc.set_pane(i, method=pane.method, range=pane.range, radius=pane.radius, features=pane.features,
                         options=pane.options)
    doc.set_difference(str(settings.value("panes/difference", "false")).lower() == "true")


def save_session(settings: QSettings, doc: Document) -> None:
    """Store the quantity, field shown, colour maps, limits, panes and difference pane of ``doc``."""
    st = doc.display.state
    settings.setValue("display/quantity", st.quantity.value)
    settings.setValue("display/layer", st.layer.value)
    settings.setValue("panes/difference", "true" if doc.difference else "false")
    settings.setValue("cmap/diverging_cmap", st.diverging_cmap)
    settings.setValue("cmap/sequential_cmap", st.sequential_cmap)
    settings.setValue("panes", json.dumps([{"method": p.method, "range": p.range, "radius": p.radius,
                                            "features": p.features, "options": [list(o) for o in p.options]}
                                           for p in doc.panes]))
    settings.setValue("limits/mode", st.limit_mode.value)
    settings.setValue("limits/percentiles", json.dumps(list(st.percentiles)))
    settings.setValue("limits/manual", json.dumps(list(st.manual)))
    settings.setValue("limits/lock", "true" if st.lock_limits else "false")
