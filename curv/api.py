"""The one entry point: ``curv.estimate(mesh, method, range)`` and its generator form."""

from __future__ import annotations

import builtins
import enum
import inspect
import math
import time
from dataclasses import dataclass, replace
from typing import Generator

import numpy as np

from .core.errors import EstimatorError, MeshError
from .estimators import DEFAULT_ESTIMATOR, SHARED_PASSES, get_spec, refusal
from .estimators._pooling import pool_members
from .core.jit import COMPILE_MESSAGE, Progress, compile_pending, jit_parallel, launch, prange, run_to_end
from .convert import as_mesh
from .core.mesh import Mesh
from .core.pointcloud import PointCloud
from .core.ranges import ball_radii, parse_range, resolve
from .core.features import check_angle, feature_set
from .core.filled import filled
from .geometry.neighbourhood import cached_with_mesh, latest_with_mesh
from .geometry.normals import NormalWeighting, cached_max_normals, normalize_rows, unusable_normal_vertices, vertex_normals
from .core.result import Curvature
from .geometry.smoothing import smooth_positions, smooth_values
from .core.validity import Reason

__all__ = ["estimate", "iter_estimate", "estimate_ranges", "iter_estimate_ranges", "estimate_table",
           "iter_estimate_table", "Smoothing", "parse_range"]

builtins_range = builtins.range  # the keyword ``range`` shadows it in the functions below


class Smoothing(str, enum.Enum):
    """The paper's smoothing variants (§5.3, Fig. 10), applied around an estimate."""

    NONE = "none"
    MESH = "mesh"
    """Cotan-smooth the vertex positions, then estimate (R2SM in the paper)."""
    VALUES = "values"
    """Estimate, then cotan-smooth k1 and k2 over valid neighbours (R2SV)."""


def _asks_for_fit(normals) -> bool:
    """``normals="fit"``; any other string is an error naming the choices."""
    if not isinstance(normals, str):
        return False
    if normals != "fit":
        raise EstimatorError(f"normals must be an (n, 3) array or 'fit', got {normals!r}")
    return True


def _check_normals(normals, n: int) -> np.ndarray:
    arr = np.asarray(normals, dtype=np.float64)
    if arr.shape != (n, 3):
        raise MeshError(f"normals must have shape ({n}, 3), got {arr.shape}")
    return normalize_rows(arr)


def iter_estimate(
    mesh: Mesh,
    method: str = DEFAULT_ESTIMATOR,
    range=None,
    *,
    radius: float | None = None,
    normals: np.ndarray | None = None,
    normal_weighting: NormalWeighting | str = NormalWeighting.MAX,
    smooth: Smoothing | str | None = None,
    smooth_iterations: int = 1,
    smooth_strength: float = 0.5,
    fit_range=2,
    block_size: int | None = None,
    features=None,
    vertices=None,
    knn: int | None = None,
    orient=None,
    standard_errors: bool = True,
    **options,
) -> Generator[float, None, Curvature]:
    """Estimate curvature step by step: yields the fraction done, returns the :class:`Curvature`.

    Every ``yield`` is a point where a caller may stop (cancel); the yielded values are
    :class:`curv.core.jit.Progress` floats, whose ``message`` says when kernels are being compiled.
    Parameters as in :func:`estimate`.
    """
    results = yield from _iter_estimates(
        mesh, (method,), (range,), radius=radius, normals=normals, normal_weighting=normal_weighting, smooth=smooth,
        smooth_iterations=smooth_iterations, smooth_strength=smooth_strength, fit_range=fit_range,
        block_size=block_size, features=features, vertices=vertices, knn=knn, orient=orient,
        standard_errors=standard_errors, **options)
    return results[method][0]


def iter_estimate_ranges(mesh: Mesh, method: str = DEFAULT_ESTIMATOR, ranges=(1, 2, 3, 4), **keywords
                         ) -> Generator[float, None, list]:
    """:func:`estimate_ranges` step by step: yields the fraction done, returns the list of
    :class:`Curvature` (as :func:`iter_estimate` does for one range)."""
    results = yield from iter_estimate_table(mesh, (method,), ranges, **keywords)
    return results[method]


def estimate_ranges(mesh: Mesh, method: str = DEFAULT_ESTIMATOR, ranges=(1, 2, 3, 4), **keywords) -> list:
    """Estimate at several ranges of one estimator on the same mesh: one :class:`Curvature` per range.

    The result for each range equals ``estimate(mesh, method, range, **keywords)``: bit for bit for
    the estimators that run each range on its own, to rounding for those that share one pass
    over the ranges (below). What every range shares is done once: the mesh's checks and
    connectivity, the normals, a region's rows. ``csm`` and ``icc`` share more: one walk per
    vertex at the widest range serves every range (each range's support is exactly its own
    search's, :func:`curv.geometry.neighbourhood.widen_ball_support`), the star sums of a range are
    the narrower one's plus the vertices it adds, and only the faces crossing each sphere are
    clipped per range; their sums are added in another order than a call with one range, so the
    values agree to a few units in the last place (and a value at a threshold, e.g. a tiny negative
    discriminant, may land on the other side). So do the fits ``nc``, ``qs``, ``an`` and ``mru`` with
    ``standard_errors=False`` on a mesh: one walk, and each range's normal equations are the
    narrower range's plus the rows of the vertices it adds
    (:func:`curv.estimators._local_fit.run_fit_levels`); with standard errors, or on a point cloud,
    they run each range on its own. The ``jet`` walks once on a mesh and fits each range anew (its
    frame follows the support): to rounding too, its standard errors included.

    Parameters
    ----------
    mesh, method :
        As in :func:`estimate`.
    ranges : sequence of (int, float or str)
        The ranges k of Rk (:mod:`curv.core.ranges`), in any order; the results follow it.
    **keywords
        As in :func:`estimate`, but not ``radius`` or ``knn``.

    Returns
    -------
    list of Curvature
        One per range, in the order of ``ranges``; each one's ``info["seconds"]`` counts from the
        start of the call.
    """
    return run_to_end(iter_estimate_ranges(mesh, method, ranges, **keywords))


def _range_tuple(ranges) -> tuple:
    """``ranges`` as a non-empty tuple (one range alone is a tuple of it)."""
    ranges = (ranges,) if isinstance(ranges, (str, int, float, np.number)) else tuple(ranges)
    if not ranges:
        raise EstimatorError("ranges must name at least one range")
    return ranges


def iter_estimate_table(mesh: Mesh, methods, ranges=(1, 2, 3, 4), **keywords) -> Generator[float, None, dict]:
    """:func:`estimate_table` step by step: yields the fraction done, returns the dict of lists of
    :class:`Curvature`."""
    methods = (methods,) if isinstance(methods, str) else tuple(methods)
    if not methods or len(set(methods)) != len(methods):
        raise EstimatorError(f"methods must name each estimator once; got {list(methods)}")
    wanted = {m: _range_tuple(ranges[m] if isinstance(ranges, dict) else ranges) for m in methods}
    for name in ("radius", "knn"):
        if keywords.get(name) is not None:
            raise EstimatorError(f"estimate_ranges and estimate_table take ranges, not {name}=; "
                                 f"estimate one {name} with curv.estimate")
    groups: dict = {}
    for m in methods:
        spec = get_spec(m)
        groups.setdefault(spec.shared_pass or ("alone", m), []).append(m)
    results = {}
    for group in groups.values():
        # a shared pass runs every range any of its estimators asks for (each range a level)
        union = tuple(dict.fromkeys(r for m in group for r in wanted[m]))
        table = yield from _iter_estimates(mesh, tuple(group), union, **keywords)
        for m in group:
            results[m] = [table[m][union.index(r)] for r in wanted[m]]
    return {m: results[m] for m in methods}


def estimate_table(mesh: Mesh, methods, ranges=(1, 2, 3, 4), **keywords) -> dict:
    """Estimate several estimators at several ranges on the same mesh: ``{method: [Curvature per range]}``.

    Each method's list equals ``estimate_ranges(mesh, method, its ranges, **keywords)``. Estimators
    whose specs name the same shared pass (:attr:`~curv.estimators.EstimatorSpec.shared_pass`) run
    in it together: ``csm`` and ``icc`` search each vertex's ball once per range and clip each
    face crossing its sphere once, for both (:mod:`curv.estimators.clipping_pair`); what they share
    with the others is done once per pass, as in :func:`estimate_ranges`. Asked for the same ranges,
    their results are :func:`estimate_ranges`' bit for bit; with different ranges the pass runs
    every range either asks for, and the values agree to rounding (the sums of a range are the
    narrower one's plus the vertices it adds). The other estimators run one
    :func:`estimate_ranges` each.

    Parameters
    ----------
    mesh :
        As in :func:`estimate`.
    methods : sequence of str
        Registry names, each once.
    ranges : sequence of (int, float or str), or dict
        The ranges of every method, or ``{method: ranges}``.
    **keywords
        As in :func:`estimate_ranges`; an estimator option goes to the methods that take it (it must
        be one's).

    Returns
    -------
    dict
        ``{method: [Curvature per range]}`` in the order of ``methods`` and of each one's ranges.
    """
    return run_to_end(iter_estimate_table(mesh, methods, ranges, **keywords))


def _split_options(specs, options: dict) -> dict:
    """``{name: its options}``: each estimator gets the options it takes; an option none takes is refused
    (by the first estimator's message, which names its options)."""
    taken = {spec.name: spec.check_options({k: v for k, v in options.items() if k in spec.options})
             for spec in specs}
    unknown = {k: v for k, v in options.items() if not any(k in spec.options for spec in specs)}
    specs[0].check_options(unknown)
    return taken


def _iter_estimates(
    mesh: Mesh,
    methods: tuple = (DEFAULT_ESTIMATOR,),
    ranges=(None,),
    *,
    radius: float | None = None,
    normals: np.ndarray | None = None,
    normal_weighting: NormalWeighting | str = NormalWeighting.MAX,
    smooth: Smoothing | str | None = None,
    smooth_iterations: int = 1,
    smooth_strength: float = 0.5,
    fit_range=2,
    block_size: int | None = None,
    features=None,
    vertices=None,
    knn: int | None = None,
    orient=None,
    standard_errors: bool = True,
    **options,
) -> Generator[float, None, dict]:
    """:func:`iter_estimate` of each of ``methods`` at each of ``ranges``: returns ``{method: [Curvature
    per range]}``, in the order of ``ranges``.

    The setup (mesh checks, normals, flags, a region's rows) is done once; an estimator whose
    function takes ``(levels, n)`` radii (``EstimatorSpec.takes_levels``: ``csm``, ``icc``, the fits
    ``nc``, ``qs``, ``an``, ``mru``, ``jet``) runs the ranges of a mesh in one call, in ascending order; the
    others (and a point cloud's) run once per range. Several ``methods`` must name one shared pass
    (:attr:`~curv.estimators.EstimatorSpec.shared_pass`), which runs them and their ranges in one call.
    """
    specs = [get_spec(m) for m in methods]
    spec = specs[0]  # the estimators of one pass take the same normals, ranges and supports
    if len(specs) > 1 and not (spec.shared_pass and all(s.shared_pass == spec.shared_pass for s in specs)):
        raise EstimatorError(f"{list(methods)} do not share a pass: estimate them one by one")
    rngs = [resolve(spec, r, radius, knn) for r in ranges]
    for other in specs[1:]:
        for r in ranges:
            resolve(other, r, radius, knn)
    options_of = _split_options(specs, options)
    mesh = mesh if isinstance(mesh, PointCloud) else as_mesh(mesh)
    for s in specs:
        why_not = refusal(s, mesh)
        if why_not is not None:
            raise MeshError(why_not)
    smooth = Smoothing(smooth or Smoothing.NONE)
    centres = _check_vertices(vertices, mesh.n_vertices)
    twin = _grid_ordered(mesh) if isinstance(mesh, PointCloud) else _locality_ordered(mesh, centres, features)
    if twin is not None:
        # a point cloud runs in its grid's order (curv.point_normals, notes 6), and so does a whole mesh
        # numbered too scattered for the caches (_locality_ordered); the rows go back at the end
        mesh, rows = twin
        normals = _rows_of(normals, rows)
        centres = None if centres is None else _rank(rows)[centres]
    if centres is not None and smooth is Smoothing.VALUES:
        raise EstimatorError("vertices= cannot be combined with smooth='values': smoothing needs the neighbours' values")
    if isinstance(mesh, PointCloud) and (features is not None or smooth is not Smoothing.NONE):
        raise EstimatorError("features= and smooth= need a mesh's edges and faces; a point cloud takes neither")
    feats = None if features is None else _feature_set(mesh, features)
    # before the connectivity and normals: on a first run their kernels compile too
    kernels = tuple(k for s in specs for k in s.kernels)
    yield Progress(0.0, COMPILE_MESSAGE if compile_pending((*kernels, _settle)) else "")
    t0 = time.perf_counter()
    if isinstance(mesh, PointCloud):
        work_mesh = mesh
        used_normals, flags, normals_label = _point_setup(mesh, normals, orient=orient, fit_range=fit_range)
        fused = False
    else:
        work_mesh, used_normals, flags, fused = _mesh_setup(mesh, spec, normals, normal_weighting, smooth,
                                                            smooth_iterations, smooth_strength, fit_range, feats)
        normals_label = _normals_label(normals, normal_weighting, fit_range)
    # a region's fits also run at its neighbours, whose residuals its standard errors pool
    skips = spec.skips_errors
    fitted = (pool_members(work_mesh, centres) if skips and standard_errors and centres is not None
              and not isinstance(work_mesh, PointCloud) else centres)
    kernel_options = {s.name: {**options_of[s.name], "standard_errors": bool(standard_errors)} if skips
                      else options_of[s.name] for s in specs}
    radii_of = [ball_radii(work_mesh, rng, uses_normals=spec.uses_normals, at=fitted) if spec.has_support else None
                for rng in rngs]
    on_crease = feats is not None and feats.any
    kernel_normals = used_normals
    if on_crease and used_normals is not None:
        # a crease vertex's normal blends both sides: no neighbour-normal term may use it (icc takes
        # its sector's normal instead, curv.core.features.sector_corner_normals; ru leaves its faces out)
        kernel_normals = latest_with_mesh(work_mesh, "crease normals", (used_normals, feats.vertices),
                                          lambda: _without(used_normals, feats.vertices))
    shared = len(rngs) > 1 and spec.takes_levels and not isinstance(work_mesh, PointCloud) and all(
        rng.radius is None and rng.knn is None for rng in rngs)
    if len(specs) > 1 or shared:
        # one call for every range, narrowest first (radius = factor(k) * unit is ascending in k)
        ascending = sorted(builtins_range(len(rngs)), key=lambda i: rngs[i].k)
        stacked = np.stack([radii_of[i] for i in ascending])
        common = dict(chunk=block_size, centres=centres, features=feats if on_crease else None)
        if len(specs) > 1:
            by_method = yield from SHARED_PASSES[spec.shared_pass](
                work_mesh, kernel_normals, stacked, tuple(methods), options=kernel_options, **common)
        else:
            by_method = {spec.name: (yield from spec.function(work_mesh, kernel_normals, stacked, **common,
                                                              **kernel_options[spec.name]))}
        raws_of = {}
        for name, levels in by_method.items():
            raws_of[name] = [None] * len(rngs)
            for i, level in zip(ascending, levels):
                raws_of[name][i] = level
    else:
        raws = []
        for radii in radii_of:
            order = centres
            if centres is None and isinstance(work_mesh, PointCloud) and radii is not None:
                # a whole cloud in its grid's cell order: neighbouring points are estimated one after
                # another and share what is in the cache (a random-order cloud's kernel ran about 3x
                # slower); every point writes its own rows, so the result is the same
                order = work_mesh.ball_grid(radii)[0][3]
            raws.append((yield from spec.function(work_mesh, kernel_normals, radii, chunk=block_size, centres=order,
                                                  features=feats if on_crease else None,
                                                  **kernel_options[spec.name])))
        raws_of = {spec.name: raws}
    # the neighbours an estimator that reads their normals can use (a NaN normal is left out)
    usable = (np.isfinite(kernel_normals).all(axis=1)
              if spec.uses_normals and kernel_normals is not None else None)
    results = {}
    for s in specs:
        results[s.name] = []
        for rng, radii, raw in zip(rngs, radii_of, raws_of[s.name]):
            results[s.name].append((yield from _finish(
                mesh, s, rng, radii, raw, flags, fused, used_normals, usable, centres, feats, on_crease, smooth,
                smooth_iterations, smooth_strength, standard_errors, normals_label, options_of[s.name], twin, t0)))
    yield 1.0
    return results


def _finish(mesh, spec, rng, radii, raw, flags, fused, used_normals, usable, centres, feats, on_crease, smooth,
            smooth_iterations, smooth_strength, standard_errors, normals_label, options, twin, t0):
    """The :class:`Curvature` of one range from the estimator's raw result: the validity rules,
    the settling pass, smoothing of the values, a region's full-length rows (a generator, as the
    support checks of a point cloud are)."""
    def at(flags: np.ndarray) -> np.ndarray:
        """The rows of a per-vertex array that this call estimates."""
        return flags if centres is None else flags[centres]

    found = {}
    for mask_of in flags.support_marks:
        # checks of the supports themselves (points: a support along a curve, or a few steps of the
        # coordinates' grid wide), on the estimated rows; the info counts each check's points
        mask, code, name = yield from mask_of(radii, centres, usable)
        flags = flags.marked(mask, code)
        found[name] = int(at(mask).sum())
    if fused:
        used_normals = raw.normals

    k1, k2, d1, d2, reason = at(raw.k1), at(raw.k2), at(raw.d1), at(raw.d2), at(raw.reason).copy()
    k1_se, k2_se = _standard_errors(raw if standard_errors else None, at, smooth, k1.shape[0])
    # root causes, whatever the estimator saw (no face or no other point at all; a normal whose
    # orientation was left undecided): later codes win
    for mask, code in flags.forced:
        reason[at(mask)] = code
    isolated = at(flags.isolated)
    if on_crease:
        # the smooth curvature is undefined on a crease; a large value there is the error to avoid
        reason[at(feats.vertices) & ~isolated] = Reason.FEATURE
    # in the order of precedence: the first that applies to a vertex names it
    for mask, code in flags.marks:
        reason[(reason == Reason.OK) & at(mask)] = code
    # non-finite values are SINGULAR; k1 >= k2 (the estimators order them already: the rare rows they
    # did not are repaired in place, the arrays are this call's own); (d1, d2, N) right-handed so
    # results are reproducible. One parallel pass over the rows.
    launch(_settle, k1, k2, d1, d2, k1_se, k2_se, used_normals, _NO_ROWS if centres is None else centres, reason)
    if smooth is Smoothing.VALUES:
        ok = reason == Reason.OK
        k1, k2 = smooth_values(mesh, np.stack([k1, k2], axis=1), ok,
                               iterations=smooth_iterations, strength=smooth_strength).T
        swap = k2 > k1
        k1, k2 = np.where(swap, k2, k1), np.where(swap, k1, k2)
        d1, d2 = np.where(swap[:, None], d2, d1), np.where(swap[:, None], -d1, d2)
    valid = reason == Reason.OK
    for arr in (k1, k2, k1_se, k2_se):
        arr[~valid] = np.nan
    d1[~valid] = np.nan
    d2[~valid] = np.nan
    if centres is not None:
        k1, k2, d1, d2, reason, valid = _full_length(mesh.n_vertices, centres, k1, k2, d1, d2, reason, valid)
        k1_se, k2_se = (_scatter(mesh.n_vertices, centres, se) for se in (k1_se, k2_se))
    result = Curvature(
        k1=k1, k2=k2, d1=d1, d2=d2, normals=used_normals, valid=valid, reason=reason.astype(np.uint8, copy=False),
        method=spec.name, range=rng.value, k1_se=k1_se, k2_se=k2_se,
        info={"seconds": time.perf_counter() - t0, "smooth": smooth.value, "range_label": rng.label,
              "normals": normals_label, **options,
              "radius": rng.radius,
              "smooth_iterations": smooth_iterations if smooth is not Smoothing.NONE else 0,
              "features": None if feats is None else feats.label,
              "feature_edges": 0 if feats is None else feats.count,
              "region": mesh.n_vertices if centres is None else int(centres.size), **flags.info, **found},
    )
    return result if twin is None else _rows_back(result, twin[1])


@dataclass(frozen=True)
class _Flags:
    """What the input says about its vertices, for the validity rules of :func:`iter_estimate`.

    ``isolated`` (n,) bool: no face or no other point; ``forced``: ``(mask, Reason)`` pairs set
    whatever the estimator found (later pairs win); ``marks``: pairs applied in order to the
    vertices still OK; ``info``: extra entries of the result's info.
    """

    isolated: np.ndarray
    marks: tuple
    info: dict
    forced: tuple = ()
    support_marks: tuple = ()
    """Generators ``(radii, centres, usable) -> (mask, Reason, name)`` run after the estimate; ``usable``
    (n,) bool marks the points whose normals the estimator reads (None: it reads none); the
    result's ``info[name]`` counts the estimated points the mask holds."""

    def marked(self, mask: np.ndarray, code) -> "_Flags":
        """These flags with one more ``(mask, code)`` mark, applied last."""
        return _Flags(isolated=self.isolated, marks=self.marks + ((mask, code),), info=self.info,
                      forced=self.forced)


def _mesh_setup(mesh: Mesh, spec, normals, normal_weighting, smooth, smooth_iterations, smooth_strength,
                fit_range, feats):
    """The working mesh, its normals (None when the estimator computes them), flags, and whether fused."""
    work_mesh = mesh
    if smooth is Smoothing.MESH:
        work_mesh = smooth_positions(mesh, iterations=smooth_iterations, strength=smooth_strength)
        if normals is not None and not _asks_for_fit(normals):
            raise EstimatorError("normals cannot be given with smooth='mesh': they are recomputed on the smoothed mesh")
    # an estimator that visits every corner anyway computes the default normals on the way
    fused = normals is None and spec.computes_normals and NormalWeighting(normal_weighting) is NormalWeighting.MAX
    if spec.has_support or not fused:
        # it will read the neighbours or the normals: the one walk over the corners gives the flags too
        mesh.corner_pass
    # Where the faces around a vertex are not one consistently oriented fan, its normal averages
    # unrelated sheets; neighbours must not use it (the vertex itself is marked invalid below).
    meaningless = unusable_normal_vertices(mesh)
    if fused:
        used_normals = None
    else:
        if normals is None:
            used_normals = _default_normals(work_mesh, normal_weighting, smoothed=work_mesh is not mesh)
        elif _asks_for_fit(normals):
            from .fitted_normals import fitted_normals

            used_normals = fitted_normals(work_mesh, range=fit_range, features=feats)
        else:
            used_normals = _check_normals(normals, mesh.n_vertices)
        if meaningless.any():
            used_normals = used_normals.copy()
            used_normals[meaningless] = np.nan
    flags = _Flags(isolated=mesh.isolated_vertices, info={"points": False},
                   forced=((mesh.isolated_vertices, Reason.DEGENERATE),), marks=(
        # no surface to fit where the faces around a vertex are not one fan (bow tie, fin)
        (mesh.nonmanifold_vertices, Reason.NONMANIFOLD),
        # faces of opposite orientation meet here: the vertex normal is meaningless
        (meaningless, Reason.DEGENERATE),
        # on a border the normal and every fit see one side only: the values there are not
        # estimates of the surface's curvature, whatever the estimator
        (mesh.border_vertices, Reason.BORDER),
    ))
    return work_mesh, used_normals, flags, fused


def _point_setup(cloud: PointCloud, normals, *, orient, fit_range):
    """A point cloud's normals (given, the cloud's own, or estimated and oriented) and flags.

    ``normals``: None (the cloud's if it has them, else jet fits), ``"fit"`` (jet), ``"pca"``, or
    an (n, 3) array.
    """
    from .point_normals import border_points, point_normals, support_floor

    n = cloud.n_points
    ambiguous = one_sided = widened = np.zeros(n, bool)
    orientation = None  # normals not estimated here are not turned
    if normals is None and cloud.normals is not None:
        used, label = normalize_rows(np.asarray(cloud.normals)), "file"
    elif normals is None or (isinstance(normals, str) and normals in ("pca", "fit")):
        method = "pca" if isinstance(normals, str) and normals == "pca" else "jet"
        est = point_normals(cloud, method=method, range=fit_range, orient=orient)
        used, ambiguous, one_sided, label = est.normals, est.ambiguous, est.one_sided, f"{method} {est.label}"
        orientation = est.orient if isinstance(est.orient, str) else tuple(float(v) for v in est.orient)
        widened = est.widened
    elif isinstance(normals, str):
        raise EstimatorError(f"normals on a point cloud must be an (n, 3) array, 'pca' or 'fit'; got {normals!r}")
    else:
        used, label = _check_normals(normals, n), "given"
    border = border_points(cloud)
    coincident = cloud.coincident_points
    flags = _Flags(isolated=cloud.isolated_vertices,
                   # a normal fitted across an empty side is not trusted
                   forced=((cloud.isolated_vertices, Reason.DEGENERATE), (one_sided, Reason.SINGULAR),
                           (ambiguous, Reason.ORIENTATION)), marks=(
        # a repeat of an earlier point: that one stands for it
        (coincident, Reason.DEGENERATE),
        # on the rim of an open scan the fits see one side only, as on a mesh border
        (border, Reason.BORDER),
    ), info={"points": True, "orientation": orientation,
             "border_points": int(border.sum()), "coincident_points": int(coincident.sum()),
             "ambiguous_normals": int(ambiguous.sum()), "one_sided_normals": int(one_sided.sum()),
             "coordinate_step": cloud.coordinate_step, "support_floor": support_floor(cloud),
             "widened_normals": int(widened.sum())},
                   support_marks=(_line_supports(cloud), _quantised_supports(cloud)))
    return used, flags, label


def _line_supports(cloud: PointCloud):
    """A support check: points whose support lies along a line or a curve (of the neighbours whose
    normals the estimator can use, when it reads them) are SINGULAR
    (:data:`curv.point_normals.MIN_SPREAD`)."""
    from .point_normals import MIN_SPREAD, support_spread

    def check(radii, centres, usable=None):
        spread = yield from support_spread(cloud, radii, centres, usable=usable)
        return ~(spread >= MIN_SPREAD), Reason.SINGULAR, "line_supports"

    return check


def _quantised_supports(cloud: PointCloud):
    """A support check: supports only a few steps of the grid the coordinates are stored on wide
    see its stairs, not the surface: SINGULAR (:data:`curv.point_normals.MIN_SUPPORT_STEPS`)."""
    from .point_normals import quantised_supports

    def check(radii, centres, usable=None):
        yield 1.0
        return quantised_supports(cloud, radii), Reason.SINGULAR, "quantised_supports"

    return check


def _grid_ordered(mesh):
    """A point cloud's twin in grid order and that order (:func:`curv.point_normals.grid_ordered`);
    None for a mesh or a twin."""
    if not isinstance(mesh, PointCloud):
        return None
    from .point_normals import grid_ordered

    return grid_ordered(mesh)


def _locality_ordered(mesh: Mesh, centres, features):
    """A whole-mesh estimate of a mesh numbered too scattered for the caches
    (:meth:`curv.Mesh.scattered_order`) runs on its twin in grid order (the point clouds' order,
    :func:`curv.core.knn.build_grid`): ``(twin, order)``, kept with the mesh; None otherwise (a
    region costs what the region costs, and a caller's feature mask is in the mesh's own numbering).
    """
    if centres is not None or (features is not None and np.ndim(features) != 0) or not mesh.scattered_order():
        return None

    def build():
        from .core.knn import build_grid

        order = np.ascontiguousarray(build_grid(mesh.vertices)[0][3], dtype=np.int64)
        order.setflags(write=False)
        return mesh.renumbered(order), order

    return cached_with_mesh(mesh, "locality order", build)


def _rank(order: np.ndarray) -> np.ndarray:
    """(n,) int64: the position of each row in ``order`` (its inverse)."""
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return rank


def _rows_of(normals, order: np.ndarray):
    """Given (n, 3) normals in ``order``; anything else as it is (its checks say the same)."""
    if normals is None or isinstance(normals, str) or np.shape(normals) != (order.size, 3):
        return normals
    return np.asarray(normals)[order]


def _rows_back(res: Curvature, order: np.ndarray) -> Curvature:
    """A result computed on rows in ``order``, in the cloud's own order."""
    def back(a):
        out = np.empty_like(a)
        out[order] = a
        return out

    return replace(res, **{f: back(getattr(res, f)) for f in
                           ("k1", "k2", "d1", "d2", "normals", "valid", "reason", "k1_se", "k2_se")})


def _check_vertices(vertices, n: int) -> np.ndarray | None:
    """``vertices=`` as an (c,) int64 index array, or None for all; a one-line error when invalid."""
    if vertices is None:
        return None
    arr = np.asarray(vertices)
    if arr.dtype == bool:
        raise EstimatorError("vertices must be an array of vertex indices, not a mask (use np.flatnonzero(mask))")
    if arr.ndim != 1 or (arr.size and not np.issubdtype(arr.dtype, np.integer)):
        raise EstimatorError(f"vertices must be a 1-D array of vertex indices; got shape {arr.shape}, {arr.dtype}")
    arr = np.ascontiguousarray(arr, dtype=np.int64)
    if arr.size and (arr.min() < 0 or arr.max() >= n):
        bad = int(arr[(arr < 0) | (arr >= n)][0])
        raise EstimatorError(f"vertex index {bad} is out of range for a mesh of {n} vertices")
    return arr


def _standard_errors(raw, at, smooth: Smoothing, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """This call's rows of the fit's standard errors (copies), NaN for an estimator without a fit
    (or a call without standard errors, ``raw`` None) and for the smoothing variants: smoothing
    correlates the noise of neighbouring vertices (before the fit with ``mesh``, after it with
    ``values``), which the residual model assumes independent."""
    if raw is None or raw.k1_se is None or smooth is not Smoothing.NONE:
        return np.full(rows, np.nan), np.full(rows, np.nan)
    return at(raw.k1_se).copy(), at(raw.k2_se).copy()


def _scatter(n: int, centres: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(n,) NaN with ``values`` at ``centres``, at the cost of the centres (:func:`curv.core.filled.filled`)."""
    out = filled(n, np.nan)
    out[centres] = values
    return out


def _full_length(n: int, centres: np.ndarray, k1, k2, d1, d2, reason, valid):
    """Scatter a region's rows into full-length outputs: NaN and ``NOT_COMPUTED`` elsewhere.

    At the cost of the region's rows, not of n (:func:`curv.core.filled.filled`).
    """
    out_k1, out_k2 = filled(n, np.nan), filled(n, np.nan)
    out_d1, out_d2 = filled((n, 3), np.nan), filled((n, 3), np.nan)
    out_reason = filled(n, Reason.NOT_COMPUTED, np.uint8)
    out_valid = np.zeros(n, bool)
    out_k1[centres], out_k2[centres], out_d1[centres], out_d2[centres] = k1, k2, d1, d2
    out_reason[centres], out_valid[centres] = reason, valid
    return out_k1, out_k2, out_d1, out_d2, out_reason, out_valid


def _feature_set(mesh: Mesh, features):
    """:func:`curv.core.features.feature_set`; the latest angle's is kept with the mesh, so that estimates
    over small regions at one angle do no whole-mesh work to find the creases again."""
    if isinstance(features, (bool, np.bool_)) or np.ndim(features) != 0:
        return feature_set(mesh, features)  # a caller's mask (or a one-line error)
    angle = check_angle(features)
    return latest_with_mesh(mesh, "feature set", (angle,), lambda: feature_set(mesh, angle))


def _without(normals: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """A read-only copy of ``normals`` (n, 3) with NaN rows at ``vertices`` (n,) bool, in the same layout."""
    out = normals.copy(order="K")
    out[vertices] = np.nan
    out.setflags(write=False)
    return out


def _default_normals(mesh: Mesh, weighting, *, smoothed: bool) -> np.ndarray:
    """The mesh's vertex normals; Max's weights on the mesh itself are cached with it (read-only),
    so that an estimate over a small region does not recompute them."""
    if smoothed or NormalWeighting(weighting) is not NormalWeighting.MAX:
        return vertex_normals(mesh, weighting=weighting)
    return cached_max_normals(mesh)


def _normals_label(normals, weighting, fit_range) -> str:
    """How the normals were made, for the result's info: ``max``, ``fit R2`` or ``given``."""
    if normals is None:
        return NormalWeighting(weighting).value
    if isinstance(normals, str):
        from .core.ranges import range_label

        return f"fit {range_label(parse_range(fit_range))}"
    return "given"


_NO_ROWS = np.empty(0, np.int64)

_OK, _SINGULAR = np.uint8(Reason.OK), np.uint8(Reason.SINGULAR)


@jit_parallel
def _settle(k1, k2, d1, d2, k1_se, k2_se, normals, rows, reason):
    """In place, per row i of this call's outputs: ``reason`` SINGULAR where it is OK but k1 or k2 is not
    finite; k1 >= k2 (k1, k2, d1, d2 and the standard errors swapped where k2 > k1); d2 negated where
    ``(d1 x d2) . N < 0`` (N the row's normal, NaN: left as it is).

    Parameters
    ----------
    k1, k2, k1_se, k2_se : (c,) float64
    d1, d2 : (c, 3) float64
    normals : (n, 3) float64
        Row i's normal is ``normals[rows[i]]``, or ``normals[i]`` when ``rows`` is empty.
    rows : (c,) or (0,) int64
    reason : (c,) uint8
    """
    for i in prange(k1.size):
        if reason[i] == _OK and not (math.isfinite(k1[i]) and math.isfinite(k2[i])):
            reason[i] = _SINGULAR
        if k2[i] > k1[i]:
            k1[i], k2[i] = k2[i], k1[i]
            k1_se[i], k2_se[i] = k2_se[i], k1_se[i]
            for j in range(3):
                d1[i, j], d2[i, j] = d2[i, j], d1[i, j]
        p = np.int64(i)
        if rows.size:
            p = np.int64(rows[i])
        a0, a1, a2 = d1[i, 0], d1[i, 1], d1[i, 2]
        b0, b1, b2 = d2[i, 0], d2[i, 1], d2[i, 2]
        c0, c1, c2 = normals[p, 0], normals[p, 1], normals[p, 2]
        if (a1 * b2 - a2 * b1) * c0 + (a2 * b0 - a0 * b2) * c1 + (a0 * b1 - a1 * b0) * c2 < 0:
            d2[i, 0], d2[i, 1], d2[i, 2] = -b0, -b1, -b2


def estimate(mesh: Mesh, method: str = DEFAULT_ESTIMATOR, range=None, **keywords) -> Curvature:
    """Estimate principal curvatures and directions at every vertex.

    Parameters
    ----------
    mesh : Mesh, PointCloud, trimesh.Trimesh, pyvista.PolyData or meshio.Mesh
        Other libraries' meshes are converted by :func:`curv.convert.as_mesh`. On a
        :class:`curv.PointCloud` the estimators with ``takes_points`` run (``nc``, ``qs``, ``an``,
        ``mru``, ``jet``); the range unit is each point's spacing (:mod:`curv.core.ranges`), points on
        the rim of an open scan are ``BORDER``, repeats of a point ``DEGENERATE``.
    method : str
        Registry name: ``meyer``, ``csm``, ``nc``, ``qs``, ``an``, ``ru``, ``mru`` (see ``curv.ESTIMATORS``).
    range : int, float or str, optional
        k of the range Rk: ``2``, ``2.5`` or ``"R2"`` (:mod:`curv.core.ranges`); any real k at least the
        estimator's smallest named range for the estimators with a support, the one named range
        for ``meyer`` (R1) and ``ru`` (R2). Default R2 where the estimator has it, else its range.
    radius : float, optional
        Instead of ``range``: the same ball radius in mesh units at every vertex.
    normals : (n, 3) array_like or "fit", optional
        Vertex normals to use (normalised here); ``"fit"``: each normal from a local jet fit at
        range ``fit_range`` (:func:`curv.fitted_normals.fitted_normals`); default Max-weighted
        normals of the mesh (the paper's protocol). On a point cloud the default is the cloud's
        own normals (from the file), else ``"fit"``: jet fits oriented as ``orient`` says
        (:mod:`curv.point_normals`; ``"pca"`` for plain PCA normals); points whose orientation
        stays ambiguous are ``Reason.ORIENTATION``.
    normal_weighting : {"max", "area", "angle"}
        Weights of the default normals.
    smooth : {None, "mesh", "values"}
        Smooth the mesh before (R2SM) or the curvature values after (R2SV) the estimate.
    smooth_iterations, smooth_strength : int, float
        Explicit cotan-Laplacian steps and their step size.
    fit_range : int, float or str
        Range of the normal fit when ``normals="fit"``.
    block_size : int, optional
        Vertices per kernel call (the granularity of progress and cancel); default adaptive, about
        every 0.05 s. Results do not depend on it.
    features : float or (e,) bool array_like, optional
        Sharp features (:mod:`curv.core.features`): edges whose dihedral angle exceeds this many degrees,
        or a per-edge mask aligned with ``mesh.edges``, are creases. Supports never cross them,
        neighbour-normal terms take each side's own normal, and vertices on a crease get
        ``Reason.FEATURE`` (NaN). Default none. A smooth mesh gives the same result as without.
    vertices : (c,) int array_like, optional
        Estimate only at these vertices (reading whatever their supports need): the arrays keep
        full length, the other vertices are NaN with ``Reason.NOT_COMPUTED``. The values equal the
        full run's at these vertices.
    knn : int, optional
        Point clouds only, instead of ``range``: each point's support is its ``knn`` nearest points.
    orient : {"up", "top", "outward"} or (3,) array_like, optional
        Point clouds whose normals are estimated: every normal up (nz >= 0 point by point, as
        PDAL does; a normal within 3 degrees of horizontal is ``Reason.ORIENTATION``), each
        connected part turned up at its highest point or outward and propagated (Hoppe et al.
        1992), or every normal towards this viewpoint (a scanner's position). Default
        (:func:`curv.point_normals.default_orientation`): ``"up"`` for a georeferenced cloud
        (LAS/LAZ), ``"top"`` for any other; ``info["orientation"]`` says which ran.
    standard_errors : bool
        False: the caller reads no standard errors; ``k1_se`` and ``k2_se`` are then NaN everywhere,
        and the fits that pool their noise level over each vertex's edge neighbours (``nc``, ``qs``,
        ``an``, ``mru``: the estimators whose spec says ``skips_errors``, which take the keyword)
        neither fit a region's neighbours nor run the pooling pass nor add up the standard
        errors' sums. k1, k2, the directions, ``valid`` and
        ``reason`` are the same either way. Default True.
    **options
        Estimator-specific options (``curv.ESTIMATORS[method].options``), e.g. ``degree=4`` for
        ``jet``.

    Returns
    -------
    Curvature
        ``k1 >= k2``, unit directions, ``valid`` mask; NaN where invalid.

    Raises
    ------
    EstimatorError
        Unknown method, or a range/radius the estimator does not take (the message names the
        allowed forms).
    MeshError
        A mesh the estimator cannot handle (e.g. quads for a triangle-only estimator).
    """
    return run_to_end(iter_estimate(mesh, method, range, **keywords))


# the keywords and their defaults are iter_estimate's, written once; help() and editors show them here too
estimate.__signature__ = inspect.signature(iter_estimate).replace(return_annotation="Curvature")
