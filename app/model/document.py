"""The document: one mesh, its source, the results computed on it, and the panes that show them."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from psygnal import Signal
from curv.core import ranges
from curv.estimators import DEFAULT_ESTIMATOR, DEFAULT_ESTIMATORS, ESTIMATORS, polygon_estimators, refusal
from curv.core.errors import EstimatorError
from curv.core.features import check_angle
from curv.variants import Variant

from .advice import AdviceRecord
from .colors import LimitMode, colormap, map_colours
from .display import Display, Layer
from .inputs import is_points
from .picture import scene_of, view_fields, view_values
from .region import Region, RestComposer
from .scalars import at_vertex, field_values

__all__ = ["Pane", "Document", "MeshChange", "MAX_PANES", "pane_letter", "default_panes"]

MAX_PANES = 4


def pane_letter(i: int) -> str:
    """``A`` for pane 0, ``B`` for pane 1, ..."""
    return chr(65 + i)


@dataclass(frozen=True)
class Pane:
    """One estimate view: an estimator and its range (k of Rk, real allowed), a fixed radius or, on a
    point cloud, the K nearest points.

    Attributes
    ----------
    method : str
        Registry name of the estimator.
    range : int or float
        k of Rk (an int when whole, so ``Pane("mru", 2)`` and the label ``R2`` agree).
    radius : float or None
        Ball radius in mesh units; replaces Rk when given.
    knn : int or None
        The support is the K nearest points (point clouds); replaces Rk and the radius when given.
    features : float or None
        Feature angle in degrees (``curv.estimate(..., features=)``), None for no features.
    region : Region or None
        Estimate only at these vertices (``vertices=``), None for the whole mesh.
    options : tuple of (str, value)
        More keyword arguments of ``curv.estimate``, sorted by name: an estimator option
        (``("degree", 4)``) or fitted normals (``("fit_range", 4), ("normals", "fit")``); what the
        advisor's Apply sets besides method and range. Empty: the defaults.
    """

    method: str
    range: float = 2
    radius: float | None = None
    features: float | None = None
    region: Region | None = None
    knn: int | None = None
    options: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "options", tuple(sorted(dict(self.options).items())))

    @classmethod
    def default(cls, method: str = DEFAULT_ESTIMATOR) -> "Pane":
        """``method`` (default the registry's default estimator) at its default range."""
        return cls(method, ranges.default_range(ESTIMATORS[method]))

    @property
    def label(self) -> str:
        """``R2``, ``R2.5``, ``r=0.3`` or the K nearest points: the range as :mod:`curv.core.ranges` writes it."""
        if self.knn is not None:
            return ranges.Range(knn=self.knn).label
        return ranges.Range(radius=self.radius).label if self.radius is not None else ranges.range_label(self.range)

    @property
    def options_label(self) -> str:
        """``degree 4``, ``normals fit R4`` or empty (:attr:`curv.variants.Variant.options_label`)."""
        return Variant(self.method, 2, options=self.options).options_label if self.options else ""

    @property
    def setting(self) -> str:
        """``R2``, ``R4 degree 4``, ``R2 features 30°``, ``R2 features 30° region 0.5 around vertex 12
        (...)``: the range and whatever else changes the result."""
        text = self.label + (f" {self.options_label}" if self.options else "")
        text += "" if self.features is None else f" features {self.features:g}°"
        return text + ("" if self.region is None else f" {self.region.title}")

    @property
    def key(self) -> tuple[str, str]:
        """``(method, setting)``: what results are cached by (the feature angle and region included)."""
        return (self.method, self.setting)

    @property
    def whole(self) -> "Pane":
        """This pane on the whole mesh (its region dropped)."""
        return replace(self, region=None)

    @property
    def title(self) -> str:
        """``mru R2`` (``mru R2 features 30°`` ...)."""
        return f"{self.method} {self.setting}"

    def estimate_kwargs(self) -> dict:
        """Keyword arguments for ``curv.iter_estimate``: ``range=k``, ``radius=r`` or ``knn=K``, and
        ``features=``, ``vertices=`` when set; ``standard_errors=True`` for the fits that give them (the
        Uncertainty layer, the readout's ± 2σ and the exports show them)."""
        if self.knn is not None:
            kwargs = {"knn": self.knn}
        else:
            kwargs = {"radius": self.radius} if self.radius is not None else {"range": self.range}
        if self.features is not None:
            kwargs["features"] = self.features
        if self.region is not None:
            kwargs["vertices"] = self.region.vertices
        if ESTIMATORS[self.method].skips_errors:
            kwargs["standard_errors"] = True
        return {**kwargs, **dict(self.options)}

    def validated(self) -> "Pane":
        """This pane checked by :func:`curv.core.ranges.resolve` and :func:`curv.core.features.check_angle`
        (``EstimatorError`` naming the allowed forms)."""
        spec = ESTIMATORS[self.method]
        features = None if self.features is None else check_angle(self.features)
        opts = dict(self.options)
        if opts.pop("normals", "fit") not in ("fit", "pca"):
            raise EstimatorError("the normals options of a pane are 'fit' and 'pca' (a point cloud's)")
        if "fit_range" in opts:
            opts.pop("fit_range")
            ranges.resolve(ESTIMATORS["jet"], range=dict(self.options)["fit_range"])
        spec.check_options(opts)
        if self.knn is not None:
            return replace(self, knn=ranges.resolve(spec, knn=self.knn).knn, radius=None, features=features)
        if self.radius is not None:
            return replace(self, radius=ranges.resolve(spec, radius=self.radius).radius, features=features)
        return replace(self, range=ranges.resolve(spec, range=self.range).value, radius=None, features=features)


def default_panes() -> tuple[Pane, ...]:
    """The panes compare mode adds, in order: the default estimator, then those that run on any mesh
    (polygons too), then the rest, each in registry order and at its default range."""
    names = list(dict.fromkeys([DEFAULT_ESTIMATOR, *polygon_estimators(), *ESTIMATORS]))
    return tuple(Pane.default(n) for n in names)


@dataclass(frozen=True)
class MeshChange:
    """What ``mesh_changed`` carries: the new source and mesh and what was built for it off the GUI thread.

    Attributes
    ----------
    source : FileSource or SurfaceSource
    mesh : curv.Mesh
    truth : curv.Curvature or None
    report : tuple of str or None
        ``mesh.report().lines()``; None while it is computed (after the new mesh's estimates).
    repairs : tuple of str
        Repairs applied while loading.
    geometry : object
        Render geometry built by the controller's ``prepare`` hook (opaque to the model).
    """

    source: object
    mesh: object
    truth: object = None
    report: tuple | None = ()
    repairs: tuple = ()
    geometry: object = None


class Document:
    """The viewer's state, free of Qt and VTK.

    Results are cached by ``Pane.key``: switching a pane to a pair already computed costs
    nothing, and changing one pane never touches the others. View index ``i`` is an estimate pane
    for ``i < len(panes)``; when ``difference`` is on, index ``len(panes)`` is the A - B pane.

    Events
    ------
    mesh_changed(MeshChange)
        New source and mesh (results cleared).
    panes_changed()
        Pane count, difference pane or the active pane changed.
    pane_changed(i)
        Pane ``i`` switched estimator or range.
    result_changed(key)
        A result arrived or failed for ``key``.
    picked_changed(index)
        The picked vertex (or None).
    advice_changed(AdviceRecord or None)
        The advisor's answer (or failure) arrived; whether it is for the current mesh is
        :attr:`advice_current` (a new mesh makes the advice stale without this event).
    report_changed()
        The mesh's report arrived (:attr:`report`, None until then when set later).
    edges_changed(key)
        The edges of an overlay arrived (:attr:`edges`: ``"borders"`` or a feature angle).

    The events are psygnal signals: ``connect`` holds a bound method weakly (a closed view does not
    stay alive through the model) and ``disconnect`` drops a callback.
    """

    mesh_changed = Signal(object)
    panes_changed = Signal()
    pane_changed = Signal(int)
    result_changed = Signal(object)
    picked_changed = Signal(object)
    advice_changed = Signal(object)
    report_changed = Signal()
    edges_changed = Signal(object)

    def __init__(self, *, default_panes: tuple[Pane, ...] | None = None) -> None:
        default_panes = default_panes or (Pane.default(),)
        self.source = None
        self.mesh = None
        self.truth = None
        self.report: tuple | None = ()
        self.repairs: tuple = ()
        self.results: dict[tuple, object] = {}
        self.failures: dict[tuple, str] = {}
        self.panes: list[Pane] = [default_panes[0]]
        self.default_panes = tuple(default_panes)
        self.panes_asked = False
        """Panes named on the command line: kept as they are on every input (else a pane left at the
        default estimator of one input kind follows the default of the next input's kind)."""
        self.difference = False
        self.active = 0
        self.picked: int | None = None
        self.mesh_serial = 0
        """Counts the meshes set so far: what an :class:`AdviceRecord` names its mesh by."""
        self.advice: AdviceRecord | None = None
        self._rest = RestComposer()
        self._last_good: dict[int, Pane] = {}
        self.display = Display()
        self.edges: dict = {}
        """Overlay edges of the mesh shown, (k, 2) vertex pairs by key: ``"borders"`` (one face) or a
        feature angle in degrees (:func:`curv.feature_edges`); computed off the GUI thread on request."""

    # -- source ---------------------------------------------------------------------------------
    def set_mesh(self, source, mesh, truth=None, *, report=(), repairs=(), geometry=None) -> None:
        """Replace the mesh; every cached result and the pick are dropped.

        ``report=None``: the report follows (:meth:`set_report`). Manual colour limits go back to
        percentiles unless ``display.lock_limits`` is set.
        """
        previous = self.mesh
        self.source, self.mesh, self.truth = source, mesh, truth
        self.mesh_serial += 1  # the advice, if any, now belongs to an earlier mesh
        self.report, self.repairs = None if report is None else tuple(report), tuple(repairs)
        self.results.clear()
        self.failures.clear()
        self.edges = {}
        self._last_good.clear()
        self._rest.clear()
        self.panes = self._panes_for(mesh, previous)
        self.picked = None
        changes = {}
        if truth is None and self.display.layer.needs_truth:
            changes["layer"] = Layer.ESTIMATE
        if self.display.limit_mode is LimitMode.MANUAL and not self.display.lock_limits:
            changes["limit_mode"] = LimitMode.PERCENTILE
        if changes:
            self.display.update(**changes)
        self.mesh_changed.emit(MeshChange(source, mesh, truth, self.report, self.repairs, geometry))

    def set_edges(self, key, edges) -> None:
        """Keep the overlay edges ``key`` of the mesh shown (:attr:`edges`)."""
        self.edges[key] = edges
        self.edges_changed.emit(key)

    def set_report(self, lines) -> None:
        """The report of the current mesh (``mesh.report().lines()``), computed after it was set."""
        self.report = tuple(lines)
        self.report_changed.emit()

    def _panes_for(self, mesh, previous=None) -> list[Pane]:
        """The panes on a new input: regions dropped (they name the old input's vertices), knn dropped
        on a mesh, a pane left at the default of the ``previous`` input's kind (a mesh before any
        input) moved to the default of this one's (:data:`curv.estimators.DEFAULT_ESTIMATORS`) unless
        :attr:`panes_asked`, and an estimator the input rules out (:func:`curv.estimators.refusal`: a
        face-based one on a point cloud) replaced by the first default pane that runs on it and is not
        shown yet."""
        panes = [replace(p.whole, knn=p.knn if is_points(mesh) else None) for p in self.panes]
        if not self.panes_asked and mesh is not None and is_points(previous) != is_points(mesh):
            before = Pane.default(DEFAULT_ESTIMATORS["points" if is_points(previous) else "mesh"])
            now = Pane.default(DEFAULT_ESTIMATORS["points" if is_points(mesh) else "mesh"])
            panes = [now if p == before and now not in panes else p for p in panes]
        runs = self._runnable_defaults(mesh)
        for i, p in enumerate(panes):
            if refusal(ESTIMATORS[p.method], mesh) is not None:
                shown = {q.method for q in panes}
                spare = [q for q in runs if q.method not in shown] or runs
                if spare:
                    panes[i] = spare[0]
        return panes

    def _runnable_defaults(self, mesh) -> list[Pane]:
        """The default panes whose estimator runs on ``mesh`` (all of them before any input)."""
        if mesh is None:
            return list(self.default_panes)
        return [p for p in self.default_panes if refusal(ESTIMATORS[p.method], mesh) is None]

    @property
    def is_points(self) -> bool:
        """Whether the input shown is a point cloud (no faces)."""
        return is_points(self.mesh)

    @property
    def has_truth(self) -> bool:
        return self.truth is not None

    # -- advice ---------------------------------------------------------------------------------
    def set_advice(self, record: AdviceRecord | None) -> None:
        """Keep the advisor's answer (or failure) for the mesh ``record.mesh_serial`` names."""
        self.advice = record
        self.advice_changed.emit(record)

    @property
    def advice_current(self) -> bool:
        """Whether :attr:`advice` holds advice computed for the mesh shown now."""
        return (self.advice is not None and self.advice.advice is not None
                and self.advice.mesh_serial == self.mesh_serial)

    # -- panes ----------------------------------------------------------------------------------
    @property
    def view_count(self) -> int:
        """Number of drawn views: the panes plus the difference pane if shown."""
        return len(self.panes) + (1 if self.difference and len(self.panes) >= 2 else 0)

    def is_difference(self, i: int) -> bool:
        return i == len(self.panes)

    def set_pane(self, i: int, **changes) -> None:
        """Change pane ``i``'s ``method``, ``range``, ``radius`` and/or ``knn`` (``radius=None``,
        ``knn=None``: back to Rk)."""
        old = self.panes[i]
        new = replace(old, **changes)
        if new != old:
            self.panes[i] = new
            self.pane_changed.emit(i)

    def pane_for(self, key) -> Pane:
        """A pane showing ``key`` (``KeyError`` if none does)."""
        for p in self.panes:
            if p.key == key:
                return p
        raise KeyError(key)

    def set_pane_count(self, n: int) -> None:
        """Show ``n`` panes (1 to :data:`MAX_PANES`); new panes take the next default estimator that runs
        on the input."""
        n = int(min(max(n, 1), MAX_PANES))
        if n == len(self.panes):
            return
        runs = self._runnable_defaults(self.mesh) or list(self.default_panes)
        while len(self.panes) < n:
            self.panes.append(runs[len(self.panes) % len(runs)])
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

    def missing_keys(self) -> list[tuple]:
        """Keys some pane shows that have neither a result nor a failure, in pane order."""
        out = []
        for p in self.panes:
            if p.key not in self.results and p.key not in self.failures and p.key not in out:
                out.append(p.key)
        return out

    def view_title(self, i: int) -> str:
        """``A: mru R2`` or ``A − B: mru R2 − nc R2``."""
        if self.is_difference(i):
            return f"A − B: {self.panes[0].title} − {self.panes[1].title}"
        return f"{pane_letter(i)}: {self.panes[i].title}"

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
        self.set_failures({key: message})

    def set_failures(self, messages: dict) -> None:
        """Record that every key of ``messages`` failed or was cancelled (``key -> one-line message``).

        Every pane showing one of them goes back to its last good estimator and range when that
        result is still there, so that its header, the selector and its colours describe the same
        estimate; a pane with nothing to go back to keeps the key and shows no colours. All keys
        are recorded before any pane moves, so that no listener restarts a key cancelled with it.
        """
        for key, message in messages.items():
            self.results.pop(key, None)
            self.failures[key] = message
        for i, p in enumerate(self.panes):
            good = self._last_good.get(i)
            if p.key in messages and good is not None and good.key in self.results:
                self.panes[i] = good
                self.pane_changed.emit(i)
        for key in messages:
            self.result_changed.emit(key)

    def retry(self, key) -> None:
        """Forget a failure or cancel of ``key``, so that the next request computes it again."""
        self.failures.pop(key, None)

    def result(self, i: int):
        """Result of estimate pane ``i``, or None; a region's result lies over the whole-mesh one
        (:func:`~app.model.region.over_rest`)."""
        pane = self.panes[i]
        res = self.results.get(pane.key)
        if res is None or pane.region is None:
            return res
        return self._rest.get(pane.key, res, self.results.get(pane.whole.key), pane.region)

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
        return view_values(scene_of(self), i)

    def value_at(self, i: int, index: int) -> float | None:
        """The shown field of view ``i`` at vertex ``index`` (constant time), or None without a result."""
        state = self.display.state
        if self.mesh is None or (state.layer.needs_truth and self.truth is None):
            return None
        if self.is_difference(i):
            a, b = self.value_at(0, index), self.value_at(1, index)
            return None if a is None or b is None else a - b
        res = self.result(i)
        if res is None and state.layer is not Layer.EXACT:
            return None
        return float(field_values(at_vertex(res, index), at_vertex(self.truth, index), state)[0])

    def signed(self, i: int) -> bool:
        return True if self.is_difference(i) else self.display.state.signed

    def fields(self) -> list:
        """The shown field of every view (:func:`app.model.picture.view_fields`).

        Returns
        -------
        list of (values, (lo, hi), Colormap) or None
            One entry per view (:attr:`view_count`); None where the result is not there yet.
        """
        return view_fields(scene_of(self))

    def field(self, i: int):
        """``(values, (lo, hi), Colormap)`` of view ``i`` as :meth:`fields` gives it, or None."""
        fields = self.fields()
        return fields[i] if i < len(fields) else None

    def colours(self, i: int, *, out: np.ndarray | None = None):
        """``(values, (lo, hi), rgba)`` for view ``i``, or None if nothing to draw yet."""
        f = self.field(i)
        if f is None:
            return None
        values, clim, cmap = f
        return values, clim, map_colours(values, clim, cmap, out=out)

    def cmap(self, i: int):
        """The colour map view ``i`` is drawn with (the diverging one until its field is there)."""
        f = self.field(i)
        if f is not None:
            return f[2]
        return colormap(self.display.state.diverging_cmap if self.signed(i) else self.display.state.sequential_cmap)
