"""The Feature angle control's defaults and words, and the feature edges a pane's angle marks
(the rule is :func:`curv.features.feature_edges`'s; this remembers its answers)."""

from __future__ import annotations

import numpy as np
from curv.features import feature_edges

__all__ = ["FeatureMasks", "DEFAULT_FEATURE_ANGLE", "FEATURE_TIP"]

DEFAULT_FEATURE_ANGLE = 30.0
"""The angle the Feature angle control offers when first switched on."""

FEATURE_TIP = ("<b>Feature angle</b>: edges whose faces meet at more than this dihedral angle are creases. "
               "Supports do not cross them, so each side is estimated from its own side only; vertices on a "
               "crease have no smooth curvature (magenta, as invalid) and read 'on a crease (feature edge)'. "
               "Off by default. 'Borders and features' draws the creases in black.")


class FeatureMasks:
    """The feature-edge masks of one mesh, per angle, computed once by :func:`curv.features.feature_edges`.

    The dihedral angles of a 10M-vertex mesh take seconds; a region estimate there takes a fraction
    of one. Estimates pass the remembered mask (``features=mask``) so that only the first estimate
    at an angle pays for it. Safe to call from worker threads (at worst two compute the same mask).
    """

    KEEP = 4

    def __init__(self) -> None:
        self._mesh = None
        self._masks: dict[float, np.ndarray] = {}

    def mask(self, mesh, angle: float) -> np.ndarray:
        """(e,) bool feature edges of ``mesh`` at ``angle`` degrees."""
        masks = self._masks if mesh is self._mesh else {}
        found = masks.get(float(angle))
        if found is None:
            found = feature_edges(mesh, angle)
            masks = dict(list(masks.items())[-(self.KEEP - 1):])  # the newest few angles
            masks[float(angle)] = found
            self._mesh, self._masks = mesh, masks
        return found

    def edge_pairs(self, mesh, angle: float) -> np.ndarray:
        """(k, 2) int64 vertex pairs of the edges of ``mesh`` sharper than ``angle`` degrees."""
        return np.asarray(mesh.edges)[self.mask(mesh, angle)]
