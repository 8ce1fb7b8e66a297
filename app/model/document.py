"""The document: one mesh, its source, the results computed on it, and the panes that show them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .colour import colormap, compute_limits, map_colours
from .display import Display, Layer
from .events import Event
from .scalars import field_values

__all__ = ["Pane", "Document", "MAX_PANES"]

MAX_PANES = 4


@dataclass(frozen=True)
class Pane:
    """One estimate view: an estimator and its range."""

    method: str
    range: int

    @property
    def key(self) -> tuple[str, int]:
        return (self.method, self.range)


class Document:
    """The viewer's state, free of Qt and VTK.

    Results are cached by ``(method, range)``: switching a pane to a pair already computed costs
    nothing, and changing one pane never touches the others. View index ``i`` is an estimate pane
    for ``i < len(panes)``; when ``difference`` is on, index ``len(panes)`` is the A - B pane.

    Events
    ------
    mesh_changed()
        New source and mesh (results cleared).
    panes_changed()
        Pane count, difference pane or the active pane changed.
    pane_changed(i)
        Pane ``i`` switched estimator or range.
    result_changed(key)
        A result arrived or failed for ``key``.
    picked_changed(index)
        The picked vertex (or None).
    """

    def __init__(self, *, default_panes: tuple[Pane, ...] = (Pane("mru", 2),)) -> None:
        self.source = None
        self.mesh = None
        self.truth = None
        self.results: dict[tuple[str, int], object] = {}
        self.failures: dict[tuple[str, int], str] = {}
        self.panes: list[Pane] = [default_panes[0]]
        self.default_panes = tuple(default_panes)
        self.difference = False
        self.active = 0
        self.picked: int | None = None
        self._last_good: dict[int, Pane] = {}
        self.display = Display()
        self.mesh_changed = Event()
        self.panes_changed = Event()
        self.pane_changed = Event()
        self.result_changed = Event()
        self.picked_changed = Event()

    # -- source ---------------------------------------------------------------------------------
    def set_mesh(self, source, mesh, truth=None) -> None:
        """Replace the mesh; every cached result and the pick are dropped."""
        self.source, self.mesh, self.truth = source, mesh, truth
        self.results.clear()
        self.failures.clear()
        self._last_good.clear()
        self.picked = None
        if truth is None and self.display.layer is not Layer.ESTIMATE:
            self.display.update(layer=Layer.ESTIMATE)
        self.mesh_changed.emit()

    @property
    def has_truth(self) -> bool:
        return self.truth is not None

    # -- panes ----------------------------------------------------------------------------------
    @property
    def view_count(self) -> int:
        """Number of drawn views: the panes plus the difference pane if shown."""
        return len(self.panes) + (1 if self.difference and len(self.panes) >= 2 else 0)

    def is_difference(self, i: int) -> bool:
        return i == len(self.panes)

    def set_pane(self, i: int, *, method: str | None = None, range: int | None = None) -> None:
        """Switch pane ``i``'s estimator and/or range."""
        old = self.panes[i]
        new = Pane(method if method is not None else old.method, range if range is not None else old.range)
        if new != old:
            self.panes[i] = new
            self.pane_changed.emit(i)

    def set_pane_count(self, n: int) -> None:
        """Show ``n`` panes (1 to :data:`MAX_PANES`); new panes take the next default estimator."""
        n = int(min(max(n, 1), MAX_PANES))
        if n == len(self.panes):
            return
        while len(self.panes) < n:
            self.panes.append(self.default_panes[len(self.panes) % len(self.default_panes)])
        del self.panes[n:]
        self._last_good = {i: p for i, p in self._last_good.items() if i < n}
        self.active = min(self.active, n - 1)
        self.panes_changed.emit()

    def set_difference(self, on: bool) -> None:
        if bool(on) != self.difference:
            self.difference = bool(on)
            self.panes_changed.emit()

    def set_active(self, i: int) -> None:
        i = int(min(max(i, 0), len(self.panes) - 1))
        if i != self.active:
            self.active = i
            self.panes_changed.emit()

    def missing_keys(self) -> list[tuple[str, int]]:
        """Keys some pane shows that have neither a result nor a failure, in pane order."""
        out = []
        for p in self.panes:
            if p.key not in self.results and p.key not in self.failures and p.key not in out:
                out.append(p.key)
        return out

    # -- results --------------------------------------------------------------------------------
    def set_result(self, key, result) -> None:
        """Store the result of ``key``; panes showing it remember it as their last good state."""
        self.failures.pop(key, None)
        self.results[key] = result
        for i, p in enumerate(self.panes):
            if p.key == key:
                self._last_good[i] = p
        self.result_changed.emit(key)

    def set_failure(self, key, message: str) -> None:
        """Record that ``key`` failed; panes showing it go back to their last good estimator."""
        self.results.pop(key, None)
        self.failures[key] = message
        for i, p in enumerate(self.panes):
            good = self._last_good.get(i)
            if p.key == key and good is not None and good.key in self.results:
                self.panes[i] = good
                self.pane_changed.emit(i)
        self.result_changed.emit(key)

    def result(self, i: int):
        """Result of estimate pane ``i``, or None."""
        return self.results.get(self.panes[i].key)

    def set_picked(self, index: int | None) -> None:
        if index is not None:
            index = int(index)
            if self.mesh is None or not 0 <= index < self.mesh.n_vertices:
                raise IndexError(f"vertex {index} is not in the mesh")
        if index != self.picked:
            self.picked = index
            self.picked_changed.emit(index)

    # -- what to draw -----------------------------------------------------------------------------
    def values(self, i: int) -> np.ndarray | None:
        """The shown field of view ``i``, or None if its result is not there yet."""
        state = self.display.state
        if self.mesh is None or (state.layer.needs_truth and self.truth is None):
            return None
        if self.is_difference(i):
            a, b = self.values(0), self.values(1)
            return None if a is None or b is None else a - b
        res = self.result(i)
        if res is None and state.layer is not Layer.EXACT:
            return None
        return field_values(res, self.truth, state)

    def signed(self, i: int) -> bool:
        return True if self.is_difference(i) else self.display.state.signed

    def cmap(self, i: int):
        state = self.display.state
        return colormap(state.diverging_cmap if self.signed(i) else state.sequential_cmap)

    def limits(self, i: int, values: np.ndarray | None = None) -> tuple[float, float]:
        """Colour limits of view ``i``: shared over the estimate panes unless disabled."""
        state = self.display.state
        kw = dict(mode=state.limit_mode, signed=self.signed(i), percentiles=state.percentiles,
                  manual=state.manual)
        if self.is_difference(i):
            return compute_limits(self.values(i) if values is None else values, **kw)
        if state.shared_scale and len(self.panes) > 1:
            parts = [v for v in (self.values(j) for j in range(len(self.panes))) if v is not None]
            if parts:
                return compute_limits(np.concatenate(parts), **kw)
        return compute_limits(self.values(i) if values is None else values, **kw)

    def fields(self) -> list:
        """The shown field of every view, computing each pane's values and the limits once.

        Returns
        -------
        list of (values, (lo, hi), Colormap) or None
            One entry per view (:attr:`view_count`); None where the result is not there yet.
        """
        state = self.display.state
        kw = dict(mode=state.limit_mode, percentiles=state.percentiles, manual=state.manual)
        values = [self.values(i) for i in range(len(self.panes))]
        if self.view_count > len(self.panes):
            a, b = values[0], values[1]
            values.append(None if a is None or b is None else a - b)
        shared = None
        present = [v for v in values[:len(self.panes)] if v is not None]
        if state.shared_scale and len(self.panes) > 1 and present:
            shared = compute_limits(np.concatenate(present), signed=state.signed, **kw)
        out = []
        for i, v in enumerate(values):
            if v is None:
                out.append(None)
                continue
            diff = self.is_difference(i)
            clim = shared if shared is not None and not diff else compute_limits(v, signed=self.signed(i), **kw)
            out.append((v, clim, self.cmap(i)))
        return out

    def colours(self, i: int, *, out: np.ndarray | None = None):
        """``(values, (lo, hi), rgba)`` for view ``i``, or None if nothing to draw yet."""
        values = self.values(i)
        if values is None:
            return None
        clim = self.limits(i, values)
        return values, clim, map_colours(values, clim, self.cmap(i), out=out)
