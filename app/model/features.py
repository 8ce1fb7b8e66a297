"""The Feature angle control's default and words (the rule is :func:`curv.core.features.feature_edges`'s)."""

from __future__ import annotations

__all__ = ["DEFAULT_FEATURE_ANGLE", "FEATURE_TIP"]

DEFAULT_FEATURE_ANGLE = 30.0
"""The angle the Feature angle control offers when first switched on."""

FEATURE_TIP = ("<b>Feature angle</b>: edges whose faces meet at more than this dihedral angle are creases. "
               "Supports do not cross them, so each side is estimated from its own side only; vertices on a "
               "crease have no smooth curvature (magenta, as invalid) and read 'on a crease (feature edge)'. "
               "Off by default. 'Borders and features' draws the creases in black.")
