"""The per-vertex scalar quantities the viewer can colour by."""

from __future__ import annotations

import enum

__all__ = ["Quantity"]


class Quantity(enum.Enum):
    """A scalar of :class:`curv.Curvature`; the value is the name :meth:`Curvature.quantity` takes."""

    MEAN = "mean"
    GAUSSIAN = "gaussian"
    K1 = "k1"
    K2 = "k2"
    SHAPE_INDEX = "shape_index"
    CURVEDNESS = "curvedness"

    @property
    def title(self) -> str:
        """Label for menus and colour bars."""
        return _TITLES[self]

    @property
    def signed(self) -> bool:
        """True when the quantity takes both signs (drawn with a diverging map centred on 0)."""
        return self is not Quantity.CURVEDNESS

    def __str__(self) -> str:
        return self.title


_TITLES = {
    Quantity.MEAN: "Mean H",
    Quantity.GAUSSIAN: "Gaussian K",
    Quantity.K1: "k1",
    Quantity.K2: "k2",
    Quantity.SHAPE_INDEX: "Shape index",
    Quantity.CURVEDNESS: "Curvedness",
}
