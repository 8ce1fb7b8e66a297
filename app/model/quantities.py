"""The per-vertex scalar quantities the viewer can colour by: an enum over :mod:`curv.core.quantities`.

Adding a quantity to the curv registry adds it here, to the menus and to the help text.
"""

from __future__ import annotations

import enum

from curv.core.quantities import QUANTITIES, QuantitySpec

__all__ = ["Quantity"]


class _QuantityEnum(enum.Enum):
    """A scalar of :class:`curv.Curvature`; the value is its registry name."""

    @property
    def spec(self) -> QuantitySpec:
        return QUANTITIES[self.value]

    @property
    def title(self) -> str:
        """Label for menus and colour bars."""
        return self.spec.title

    @property
    def signed(self) -> bool:
        """True when the quantity takes both signs with a meaningful zero."""
        return self.spec.signed

    @property
    def natural(self) -> tuple[float, float] | None:
        """The quantity's own range (shape index: (-1, 1)), or None."""
        return self.spec.natural

    def __str__(self) -> str:
        return self.title


Quantity = _QuantityEnum("Quantity", [(name.upper(), name) for name in QUANTITIES], module=__name__)
"""Enum of the registry's quantities: ``Quantity.MEAN``, ``Quantity("rms")``, ..."""
