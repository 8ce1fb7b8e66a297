"""The Feature angle control's defaults and words, and the feature edges a pane's angle marks
(the rule is :func:`curv.features.feature_edges`'s)."""

from __future__ import annotations

import numpy as np
from curv.features import feature_edges

__all__ = ["feature_edge_pairs", "DEFAULT_FEATURE_ANGLE", "FEATURE_TIP"]

DEFAULT_FEATURE_ANGLE = 30.0
"""The angle the Feature angle control offers when first switched on."""

FEATURE_TIP = ("<b>Feature angle</b>: edges whose faces meet at more than this dihedral angle are creases. "
               "Supports do not cross them, so each side is estimated from its own side only; vertices on a "
               "crease have no smooth curvature (magenta, as invalid) and read 'on a crease (feature edge)'. "
               "Off by default. 'Borders and features' draws the creases in black.")


def feature_edge_pairs(mesh, angle: float) -> np.ndarray:
    """(k, 2) int64 vertex pairs of the edges of ``mesh`` sharper than ``angle`` degrees."""
    return np.asarray(mesh.edges)[feature_edges(mesh, angle)]
