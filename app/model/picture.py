"""What the panes show, computed from a snapshot of the document so that it can run off the GUI thread.

:func:`scene_of` captures, on the GUI thread and in constant time, everything the colours depend on
(the panes' results by reference, the truth, the display state). :func:`paint` turns a
:class:`Scene` into a :class:`Picture`: per view its field, colour limits and a fresh RGBA array, the
active view's histogram and invalid count. On a large input :func:`paint` runs in a worker (seconds
at 5M points) and the GUI thread only hands the finished arrays to VTK.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from curv.colors import diverges

from .colors import Colormap, colormap, compute_limits, map_colours
from .display import DisplayState, Layer
from .region import REST_COLOUR, outside_region
from .scalars import field_values

__all__ = ["Scene", "ViewPicture", "Picture", "scene_of", "view_values", "view_fields", "paint",
           "histogram_counts", "HISTOGRAM_BINS"]

HISTOGRAM_BINS = 64


@dataclass(frozen=True, eq=False)
class Scene:
    """What the views' colours depend on, captured from a :class:`~app.model.Document`.

    Attributes
    ----------
    n : int
        Vertices (points) of the input.
    results : tuple of curv.Curvature or None
        Per estimate pane, its result as shown (a region's over the whole-mesh one).
    regions : tuple of Region or None
        Per estimate pane.
    truth : curv.Curvature or None
    state : DisplayState
    difference : bool
        Whether the A - B view follows the panes.
    active : int
    """

    n: int
    results: tuple
    regions: tuple
    truth: object
    state: DisplayState
    difference: bool
    active: int

    @property
    def view_count(self) -> int:
        return len(self.results) + (1 if self.difference else 0)

    def is_difference(self, i: int) -> bool:
        return i == len(self.results)

    def signed(self, i: int) -> bool:
        return True if self.is_difference(i) else self.state.signed

    @property
    def key(self) -> tuple:
        """Equal for scenes that draw the same colours (results compared by identity; of the display
        state only what the colours depend on: an overlay or the point size needs no new colours)."""
        st = self.state
        colours = (st.quantity, st.layer, st.diverging_cmap, st.sequential_cmap, st.limit_mode, st.percentiles,
                   st.manual, st.shared_scale)
        return (self.n, tuple(map(id, self.results)), self.regions, id(self.truth), colours, self.difference,
                self.active)


@dataclass(frozen=True, eq=False)
class ViewPicture:
    """One view's colours: ``values`` (n,) float64 (NaN where invalid), ``clim``, ``cmap`` and ``rgba``
    (n, 4) uint8, a new array owned by the picture."""

    values: np.ndarray
    clim: tuple
    cmap: Colormap
    rgba: np.ndarray


@dataclass(frozen=True, eq=False)
class Picture:
    """Everything :func:`paint` made of a :class:`Scene`.

    Attributes
    ----------
    scene : Scene
    views : tuple of ViewPicture or None
        Per view (:attr:`Scene.view_count`); None where its result is not there yet.
    histogram : (counts, edges, n_nan) or None
        The active view's :func:`histogram_counts`.
    n_invalid : int or None
        Invalid vertices of the active pane inside its region (None without a result).
    """

    scene: Scene
    views: tuple
    histogram: tuple | None
    n_invalid: int | None


def scene_of(doc) -> Scene:
    """The :class:`Scene` of ``doc`` now (constant time but for a region shown over the whole-mesh
    result the first time, which :class:`~app.model.region.RestComposer` then keeps)."""
    n = 0 if doc.mesh is None else int(doc.mesh.n_vertices)
    return Scene(n, tuple(doc.result(i) for i in range(len(doc.panes))), tuple(p.region for p in doc.panes),
                 doc.truth, doc.display.state, doc.view_count > len(doc.panes), doc.active)


def view_values(scene: Scene, i: int) -> np.ndarray | None:
    """The shown field of view ``i``, or None if its result is not there yet."""
    state = scene.state
    if scene.n == 0 or (state.layer.needs_truth and scene.truth is None):
        return None
    if scene.is_difference(i):
        a, b = view_values(scene, 0), view_values(scene, 1)
        return None if a is None or b is None else a - b
    res = scene.results[i]
    if res is None and state.layer is not Layer.EXACT:
        return None
    return field_values(res, scene.truth, state)


def _cmap_for(scene: Scene, i: int, clim) -> Colormap:
    """Diverging map when the field is signed and its limits straddle 0, else the sequential one."""
    state = scene.state
    return colormap(state.diverging_cmap if diverges(clim, signed=scene.signed(i)) else state.sequential_cmap)


def view_fields(scene: Scene) -> list:
    """The shown field of every view, computing each pane's values and the limits once.

    Returns
    -------
    list of (values, (lo, hi), Colormap) or None
        One entry per view; None where the result is not there yet.
    """
    state = scene.state
    kw = dict(mode=state.limit_mode, percentiles=state.percentiles, manual=state.manual)
    panes = len(scene.results)
    values = [view_values(scene, i) for i in range(panes)]
    if scene.difference:
        a, b = values[0], values[1]
        values.append(None if a is None or b is None else a - b)
    shared = None
    present = [v for v in values[:panes] if v is not None]
    if state.shared_scale and panes > 1 and present:
        shared = compute_limits(np.concatenate(present), signed=state.signed, natural=state.natural, **kw)
    out = []
    for i, v in enumerate(values):
        if v is None:
            out.append(None)
            continue
        diff = scene.is_difference(i)
        if shared is not None and not diff:
            clim = shared
        else:
            clim = compute_limits(v, signed=scene.signed(i), natural=None if diff else state.natural, **kw)
        out.append((v, clim, _cmap_for(scene, i, clim)))
    return out


def paint(scene: Scene) -> Picture:
    """The colours of every view of ``scene``; safe in a worker thread (it only reads the scene).

    Vertices a region leaves uncomputed get :data:`~app.model.region.REST_COLOUR`.
    """
    views = []
    for i, field in enumerate(view_fields(scene)):
        if field is None:
            views.append(None)
            continue
        values, clim, cmap = field
        rgba = map_colours(values, clim, cmap)
        if i < len(scene.results):
            outside = outside_region(scene.results[i], scene.regions[i])
            if outside is not None:
                rgba[outside] = REST_COLOUR
        views.append(ViewPicture(values, clim, cmap, rgba))
    active = views[scene.active] if scene.active < len(views) else None
    histogram = None if active is None else histogram_counts(active.values, active.clim)
    res = scene.results[scene.active] if scene.results else None
    n_invalid = None
    if res is not None:
        outside = outside_region(res, scene.regions[scene.active])
        invalid = ~res.valid if outside is None else ~res.valid & ~outside
        n_invalid = int(np.count_nonzero(invalid))
    return Picture(scene, tuple(views), histogram, n_invalid)


def histogram_counts(values: np.ndarray, clim: tuple[float, float], *, bins: int = HISTOGRAM_BINS):
    """Counts of the finite ``values`` over a span covering the bulk of the data and ``clim``.

    Returns
    -------
    counts : (bins,) int
    edges : (bins + 1,) float
    n_nan : int
        Values that are NaN (invalid vertices).
    """
    finite = values[np.isfinite(values)]
    n_nan = int(values.size - finite.size)
    lo, hi = clim
    if finite.size:
        p_lo, p_hi = np.percentile(finite, (0.5, 99.5))
        span = hi - lo
        lo = min(lo - 0.1 * span, p_lo)
        hi = max(hi + 0.1 * span, p_hi)
    if not hi - lo > 1e-9 * max(abs(lo), abs(hi), 1e-300):  # a constant field: a small window around it
        pad = max(abs(lo), abs(hi), 1e-12) * 1e-3
        lo, hi = lo - pad, hi + pad
    counts, edges = np.histogram(finite, bins=bins, range=(lo, hi))
    return counts, edges, n_nan
