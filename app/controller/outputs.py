"""What the viewer writes and overlays, through the library's public functions: exports of a pane and
the edges drawn over a mesh. Plain functions, run by the controller in worker threads."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from curv import feature_edges, save_ply, save_vtu

from app.model.export import scene_payload
from app.model.inputs import is_points

__all__ = ["write_export", "overlay_edges", "EXPORT_SUFFIXES"]

EXPORT_SUFFIXES = (".ply", ".vtu")
"""The result files a pane exports to (the PNG screenshot is the window's)."""


def write_export(path, mesh, scene, pane, colours: np.ndarray) -> Path:
    """Write the active pane of ``scene`` (:func:`app.model.picture.scene_of`; ``pane`` its
    :class:`~app.model.Pane`) on ``mesh`` to ``path`` as shown, ``colours`` (n, 4) uint8 its colours
    on screen: a coloured PLY with the curvature properties, the shown field and, for an analytic
    source, its errors (:func:`app.model.export.scene_payload`), or the same as a VTK ``.vtu``; safe
    in a worker thread.

    Raises
    ------
    RuntimeError
        The pane has no result yet.
    ValueError
        ``path`` ends in neither ``.ply`` nor ``.vtu``.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise ValueError(f"cannot export to {path.name}: choose a {' or '.join(EXPORT_SUFFIXES)} file")
    payload = scene_payload(scene, pane, scene.active)
    colours = np.asarray(colours, dtype=np.uint8)
    if suffix == ".ply":
        return save_ply(path, mesh, payload.result, quantity=scene.state.quantity.value, colors=colours,
                        extra=payload.extra, comment=payload.comment)
    return save_vtu(path, mesh, payload.result, colors=colours, extra=payload.extra)


def overlay_edges(mesh, key) -> np.ndarray:
    """(k, 2) vertex pairs of ``mesh`` to draw for overlay ``key``: ``"borders"`` (edges of one face)
    or a feature angle in degrees (:func:`curv.feature_edges`); none for a point cloud."""
    if is_points(mesh):
        return np.zeros((0, 2), np.int64)
    mask = mesh.border_edges if key == "borders" else feature_edges(mesh, float(key))
    return np.asarray(mesh.edges)[np.asarray(mask, bool)]
