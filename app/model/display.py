"""Display settings shared by every pane: what to colour by and how."""

from __future__ import annotations

import enum
from dataclasses import dataclass, fields, replace

from psygnal import Signal

from .colors import LimitMode
from .inputs import DEFAULT_POINT_SIZE
from .quantities import Quantity

__all__ = ["Layer", "DisplayState", "Display"]


class Layer(enum.Enum):
    """Which field of the chosen quantity is shown."""

    ESTIMATE = "estimate"
    EXACT = "exact"
    ERROR = "error"
    E_REL = "e_rel"
    UNCERTAINTY = "uncertainty"
    """Twice the standard error of the estimate's k2 when k2 is the quantity, else of its k1
    (``Curvature.k1_se``, ``k2_se``: least-squares estimators only)."""

    @property
    def title(self) -> str:
        return {"estimate": "Estimate", "exact": "Exact value", "error": "Signed error (est - exact)",
                "e_rel": "Relative error e_rel", "uncertainty": "Uncertainty (2 sigma)"}[self.value]

    @property
    def needs_truth(self) -> bool:
        return self not in (Layer.ESTIMATE, Layer.UNCERTAINTY)

    def __str__(self) -> str:
        return self.title


@dataclass(frozen=True)
class DisplayState:
    """An immutable snapshot of the display settings.

    Attributes
    ----------
    quantity : Quantity
    layer : Layer
    diverging_cmap, sequential_cmap : str
        Colour maps for signed and unsigned fields.
    limit_mode : LimitMode
    percentiles : (lo, hi)
        Percentiles of the ``PERCENTILE`` mode, default 2-98 %.
    manual : (lo, hi)
        Limits of the ``MANUAL`` mode.
    shared_scale : bool
        One colour scale over every estimate pane (compare mode).
    lock_limits : bool
        Keep manual limits when a new mesh opens (otherwise they go back to percentiles).
    show_directions : bool
        Draw d1/d2 glyph lines.
    show_edges, show_borders, show_points : bool
        Wireframe overlay, border edges highlighted, vertices as points.
    point_size : float
        Width in pixels of a point cloud's points.
    """

    quantity: Quantity = Quantity.MEAN
    layer: Layer = Layer.ESTIMATE
    diverging_cmap: str = "coolwarm"
    sequential_cmap: str = "viridis"
    limit_mode: LimitMode = LimitMode.PERCENTILE
    percentiles: tuple = (2.0, 98.0)
    manual: tuple = (-1.0, 1.0)
    shared_scale: bool = True
    lock_limits: bool = False
    show_directions: bool = False
    show_edges: bool = False
    show_borders: bool = False
    show_points: bool = False
    point_size: float = DEFAULT_POINT_SIZE

    @property
    def signed(self) -> bool:
        """Whether the shown field is signed (diverging map, limits centred on 0)."""
        if self.layer is Layer.ERROR:
            return True
        if self.layer in (Layer.E_REL, Layer.UNCERTAINTY):
            return False
        return self.quantity.signed

    @property
    def natural(self) -> tuple[float, float] | None:
        """The natural range of the shown field (the quantity's, for estimate and exact values)."""
        return self.quantity.natural if self.layer in (Layer.ESTIMATE, Layer.EXACT) else None

    @property
    def uncertain_of(self) -> str:
        """The principal curvature whose uncertainty :attr:`Layer.UNCERTAINTY` shows: k2 when the
        quantity is k2, else k1 (a standard error of H or K would need the two's covariance)."""
        return "k2" if self.quantity.value == "k2" else "k1"

    def field_name(self, *, difference: bool = False) -> str:
        """What the colours show, for colour bars and export comments (``Mean H error (est - exact)``)."""
        if self.layer is Layer.E_REL:
            name = "e_rel (relative error of k1, k2)"
        elif self.layer is Layer.UNCERTAINTY:
            name = f"2 standard errors of {self.uncertain_of}"
        elif self.layer is Layer.ERROR:
            name = f"{self.quantity.title} error (estimate - exact)"
        elif self.layer is Layer.EXACT:
            name = f"{self.quantity.title} (exact)"
        else:
            name = self.quantity.title
        return f"A − B of {name}" if difference else name

    def field_title(self, *, difference: bool = False) -> str:
        """Short colour-bar title."""
        name = "e_rel" if self.layer is Layer.E_REL else self.quantity.title
        if self.layer is Layer.UNCERTAINTY:
            name = f"2σ of {self.uncertain_of}"
        if self.layer is Layer.ERROR:
            name += " error"
        elif self.layer is Layer.EXACT:
            name += " (exact)"
        return ("A − B " if difference else "") + name


class Display:
    """Mutable holder of a :class:`DisplayState` with a ``changed`` event.

    ``changed`` (a psygnal signal) is emitted with the set of field names that changed.
    """

    changed = Signal(set)

    def __init__(self, state: DisplayState | None = None) -> None:
        self.state = state or DisplayState()

    def update(self, **changes) -> None:
        """Set fields by name; emits ``changed`` only if something differs."""
        known = {f.name for f in fields(DisplayState)}
        unknown = set(changes) - known
        if unknown:
            raise TypeError(f"unknown display settings: {', '.join(sorted(unknown))}")
        new = replace(self.state, **changes)
        diff = {k for k in changes if getattr(new, k) != getattr(self.state, k)}
        if diff:
            self.state = new
            self.changed.emit(diff)

    def __getattr__(self, name):
        if name == "state":
            raise AttributeError(name)
        return getattr(self.state, name)
