"""The one entry point: ``curv.estimate(mesh, method, range)`` and its generator form.

The public API; the set-up of an estimate is :mod:`curv.estimate_setup`, its validity policy and
finish :mod:`curv.estimate_finish`, the twins in grid order :mod:`curv.locality`.
"""

from __future__ import annotations

import builtins
import inspect
import time
from typing import Generator

import numpy as np

from .convert import as_input
from .core.errors import EstimatorError, MeshError, RadiusWarning, warn
from .core.jit import COMPILE_MESSAGE, Progress, compile_pending, iter_watched, rescaled, run_to_end
from .core.mesh import Mesh
from .core.ranges import ball_radii, parse_range, resolve
from .core.result import Curvature
from .core.support import support_of
from .core.validity import mark_ok_rows
from .estimate_finish import finish, radius_note, settle
from .estimate_setup import (Smoothing, cached_feature_set, check_vertices, mesh_normals_label, mesh_setup, point_setup,
                             without_rows)
from .estimators import SHARED_PASSES, default_estimator, get_spec, refusal
from .uncertainty.pooling import pool_members
from .geometry.neighbourhood import latest_with_mesh
from .geometry.normals import NormalWeighting
from .locality import cloud_twin, locality_ordered, rank, rows_of

__all__ = ["estimate", "iter_estimate", "estimate_ranges", "iter_estimate_ranges", "estimate_table",
           "iter_estimate_table", "Smoothing", "parse_range"]

builtins_range = builtins.range  # the keyword ``range`` shadows it in the functions below


def iter_estimate(mesh: Mesh, method: str | None = None, range=None, **keywords) -> Generator[float, None, Curvature]:
    """Estimate curvature step by step: yields the fraction done, returns the :class:`Curvature`.

    Every ``yield`` is a point where a caller may stop (cancel); the yielded values are
    :class:`curv.core.jit.Progress` floats, whose ``message`` says when kernels are being compiled
    and whose ``phase`` names the part of the work the fraction belongs to: ``"setup"`` (the
    input's connectivity, normals and flags; ``"normals"`` when they are fitted, then
    ``"orientation"`` on a point cloud), ``"estimate"`` (the estimator's kernels) and ``"checks"``
    (the supports' checks and the validity pass). The set-up reports through
    :func:`curv.core.jit.iter_watched`, so it is measured and a cancel reaches it too.
    Parameters as in :func:`estimate` (the keywords are ``_iter_estimates``', its signature shows them).
    """
    results = yield from _iter_estimates(mesh, (method,), (range,), **keywords)
    return next(iter(results.values()))[0]


def iter_estimate_ranges(mesh: Mesh, method: str | None = None, ranges=(1, 2, 3, 4), **keywords
                         ) -> Generator[float, None, list]:
    """:func:`estimate_ranges` step by step: yields the fraction done, returns the list of
    :class:`Curvature` (as :func:`iter_estimate` does for one range)."""
    mesh = as_input(mesh)
    method = default_estimator(mesh) if method is None else method
    results = yield from iter_estimate_table(mesh, (method,), ranges, **keywords)
    return results[method]


def estimate_ranges(mesh: Mesh, method: str | None = None, ranges=(1, 2, 3, 4), **keywords) -> list:
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
    discriminant, may land on the other side). So do the fits ``nc``, ``qs``, ``an`` and ``mru``
    without standard errors (the default) on a mesh: one walk, and each range's normal equations are
    the narrower range's plus the rows of the vertices it adds
    (:func:`curv.estimators._fit_driver.run_fit_levels`); with ``standard_errors=True``, or on a point
    cloud, they run each range on its own. The ``jet`` walks once on a mesh and fits each range anew (its
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
    mesh = as_input(mesh)
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
    methods: tuple = (None,),
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
    standard_errors: bool = False,
    **options,
) -> Generator[float, None, dict]:
    """:func:`iter_estimate` of each of ``methods`` at each of ``ranges``: returns ``{method: [Curvature
    per range]}``, in the order of ``ranges``.

    The setup (mesh checks, normals, flags, a region's rows) is done once; an estimator whose
    function takes ``(levels, n)`` radii (``EstimatorSpec.takes_levels``: ``csm``, ``icc``, the fits
    ``nc``, ``qs``, ``an``, ``mru``, ``jet``) runs the ranges of a mesh in one call, in ascending order; the
    others (and a point cloud's) run once per range. Several ``methods`` must name one shared pass
    (:attr:`~curv.estimators.EstimatorSpec.shared_pass`), which runs them and their ranges in one call.
    ``None`` in ``methods`` is the input's default estimator (:func:`curv.estimators.default_estimator`).
    """
    mesh = as_input(mesh)
    support = support_of(mesh)  # what the input's kind answers (a twin below is of the same kind)
    methods = tuple(default_estimator(mesh) if m is None else m for m in methods)
    specs = [get_spec(m) for m in methods]
    spec = specs[0]  # the estimators of one pass take the same normals, ranges and supports
    if len(specs) > 1 and not (spec.shared_pass and all(s.shared_pass == spec.shared_pass for s in specs)):
        raise EstimatorError(f"{list(methods)} do not share a pass: estimate them one by one")
    rngs = [resolve(spec, r, radius, knn) for r in ranges]
    for other in specs[1:]:
        for r in ranges:
            resolve(other, r, radius, knn)
    options_of = _split_options(specs, options)
    for s in specs:
        why_not = refusal(s, mesh)
        if why_not is not None:
            raise MeshError(why_not)
    smooth = Smoothing(smooth or Smoothing.NONE)
    centres = check_vertices(vertices, mesh.n_vertices)
    if centres is not None and smooth is Smoothing.VALUES:
        raise EstimatorError("vertices= cannot be combined with smooth='values': smoothing needs the neighbours' values")
    if not support.has_faces and (features is not None or smooth is not Smoothing.NONE):
        raise EstimatorError("features= and smooth= need a mesh's edges and faces; a point cloud takes neither")
    # before the connectivity and normals: on a first run their kernels compile too
    kernels = tuple(k for s in specs for k in s.kernels)
    first_phase = "normals" if support.fits_normals(normals) else "setup"
    yield Progress(0.0, COMPILE_MESSAGE if compile_pending((*kernels, settle, mark_ok_rows)) else "", first_phase)
    called_with = mesh, centres

    def prepare():
        """What every range and estimator shares, on iter_watched's thread: the twin in grid order,
        the creases, the normals and flags, the support radii (a large cloud's normals take longer
        than its estimate)."""
        mesh, centres, given = called_with[0], called_with[1], normals
        twin = cloud_twin(mesh) if support.grid_twin else locality_ordered(mesh, centres, features)
        if twin is not None:
            # a point cloud runs in its grid's order (curv.point_normals, notes 6), and so does a whole mesh
            # numbered too scattered for the caches (locality_ordered); the rows go back at the end
            mesh, rows = twin
            given = rows_of(given, rows)
            centres = None if centres is None else rank(rows)[centres]
        feats = None if features is None else cached_feature_set(mesh, features)
        t0 = time.perf_counter()
        if support.kind == "points":  # its normals fitted and oriented, its borders found
            work_mesh = mesh
            # an estimator that reads the normals' pass's fits (the jet and qs at their range) has them kept
            reads = len(specs) == 1 and spec.reads_normal_fits is not None and spec.reads_normal_fits(
                options_of[spec.name], bool(standard_errors))
            used_normals, flags, normals_label = point_setup(mesh, given, orient=orient, fit_range=fit_range,
                                                             keep_fits_at=rngs if reads else (),
                                                             keep_fits=reads or None)
            fused = False
        else:
            work_mesh, used_normals, flags, fused = mesh_setup(mesh, spec, given, normal_weighting, smooth,
                                                               smooth_iterations, smooth_strength, fit_range, feats)
            normals_label = mesh_normals_label(given, normal_weighting, fit_range)
        # a region's fits also run at its neighbours, whose residuals its standard errors pool
        fitted = (pool_members(work_mesh, centres) if spec.pools_errors and standard_errors and centres is not None
                  and support.has_faces else centres)
        radii_of = [ball_radii(work_mesh, rng, uses_normals=spec.uses_normals, at=fitted) if spec.has_support
                    else None for rng in rngs]
        return (mesh, twin, centres, feats, t0, work_mesh, used_normals, flags, normals_label, fused, fitted,
                radii_of)

    (mesh, twin, centres, feats, t0, work_mesh, used_normals, flags, normals_label, fused, fitted,
     radii_of) = yield from iter_watched(prepare, phase=first_phase)
    skips = spec.skips_errors
    kernel_options = {s.name: {**options_of[s.name], "standard_errors": bool(standard_errors)} if skips
                      else options_of[s.name] for s in specs}
    on_crease = feats is not None and feats.any
    kernel_normals = used_normals
    if on_crease and used_normals is not None:
        # a crease vertex's normal blends both sides: no neighbour-normal term may use it (icc takes
        # its sector's normal instead, curv.core.features.sector_corner_normals; ru leaves its faces out)
        kernel_normals = latest_with_mesh(work_mesh, "crease normals", (used_normals, feats.vertices),
                                          lambda: without_rows(used_normals, feats.vertices))
    shared = len(rngs) > 1 and spec.takes_levels and support.has_faces and all(
        rng.radius is None and rng.knn is None for rng in rngs)
    if len(specs) > 1 or shared:
        # one call for every range, narrowest first (radius = factor(k) * unit is ascending in k)
        ascending = sorted(builtins_range(len(rngs)), key=lambda i: rngs[i].k)
        stacked = np.stack([radii_of[i] for i in ascending])
        common = dict(chunk=block_size, centres=centres, features=feats if on_crease else None)
        if len(specs) > 1:
            by_method = yield from rescaled(SHARED_PASSES[spec.shared_pass](
                work_mesh, kernel_normals, stacked, tuple(methods), options=kernel_options, **common),
                0.0, 1.0, phase="estimate")
        else:
            by_method = {spec.name: (yield from rescaled(spec.function(
                work_mesh, kernel_normals, stacked, **common, **kernel_options[spec.name]),
                0.0, 1.0, phase="estimate"))}
        raws_of = {}
        for name, levels in by_method.items():
            raws_of[name] = [None] * len(rngs)
            for i, level in zip(ascending, levels):
                raws_of[name][i] = level
    else:
        raws = []
        for i, radii in enumerate(radii_of):
            # a whole input in the order its provider visits it (a cloud's grid cells); every row is its own
            order = support_of(work_mesh).visit_order(radii) if centres is None and radii is not None else centres
            raws.append((yield from rescaled(
                spec.function(work_mesh, kernel_normals, radii, chunk=block_size, centres=order,
                              features=feats if on_crease else None, **kernel_options[spec.name]),
                i / len(radii_of), (i + 1) / len(radii_of), phase="estimate")))
        raws_of = {spec.name: raws}
    # the neighbours an estimator that reads their normals can use (a NaN normal is left out)
    usable = (np.isfinite(kernel_normals).all(axis=1)
              if spec.uses_normals and kernel_normals is not None else None)
    results = {}
    parts = len(specs) * len(rngs)
    for s in specs:
        results[s.name] = []
        for rng, radii, raw in zip(rngs, radii_of, raws_of[s.name]):
            part = sum(map(len, results.values()))
            results[s.name].append((yield from rescaled(finish(
                mesh, s, rng, radii, raw, flags, fused, used_normals, usable, centres, feats, on_crease, smooth,
                smooth_iterations, smooth_strength, standard_errors, normals_label, options_of[s.name], twin, t0),
                part / parts, (part + 1) / parts, phase="checks")))
    if radius is not None:  # one range of one estimator (estimate_ranges and estimate_table take no radius)
        # the spacing of the twin (a cloud's is measured there already) has the same median
        _warn_of_radius(mesh, radius, results[spec.name][0], called_with[1])
    yield Progress(1.0, "", "checks")
    return results


def _warn_of_radius(mesh, radius: float, result: Curvature, centres) -> None:
    """A :class:`~curv.core.errors.RadiusWarning` when ``radius=`` is below the input's spacing or leaves
    most rows without an estimate (:func:`curv.estimate_finish.radius_note`); the note goes into the
    result's ``info["warnings"]`` too, for the command line's summary and the viewer's status."""
    note = radius_note(mesh, radius, result.reason, centres)
    if note is not None:
        result.info["warnings"] = (*result.info.get("warnings", ()), note)
        warn(note, RadiusWarning)


def estimate(mesh: Mesh, method: str | None = None, range=None, **keywords) -> Curvature:
    """Estimate principal curvatures and directions at every vertex.

    Parameters
    ----------
    mesh : Mesh, PointCloud, trimesh.Trimesh or PointCloud, pyvista.PolyData, meshio.Mesh or (n, 3) array
        Other libraries' meshes and point clouds are converted by :func:`curv.convert.as_input`
        (without faces: a point cloud). On a point cloud the estimators with ``takes_points`` run
        (``nc``, ``qs``, ``an``, ``mru``, ``jet``); the range unit is each point's spacing
        (:mod:`curv.core.ranges`), points on the rim of an open scan are ``BORDER``, repeats of a
        point ``DEGENERATE``.
    method : str, optional
        Registry name: ``meyer``, ``csm``, ``nc``, ``qs``, ``an``, ``ru``, ``mru``, ``jet``, ``icc``
        (see ``curv.ESTIMATORS``). Default the registry's for the input's kind
        (:data:`curv.estimators.DEFAULT_ESTIMATORS`): ``mru`` on a mesh, ``qs`` on a point cloud.
    range : int, float or str, optional
        k of the range Rk: ``2``, ``2.5`` or ``"R2"`` (:mod:`curv.core.ranges`); any real k at least the
        estimator's smallest named range for the estimators with a support, the one named range
        for ``meyer`` (R1) and ``ru`` (R2). Default R2 where the estimator has it, else its range.
    radius : float, optional
        Instead of ``range``: the same ball radius in mesh units at every vertex. A radius below the
        input's median spacing, or one that leaves more than half of the vertices with too few
        neighbours or a singular fit, gives a :class:`curv.RadiusWarning` (once per call; its text
        is in ``info["warnings"]`` too).
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
        True: also the standard errors ``k1_se`` and ``k2_se`` of the least-squares fits (``nc``,
        ``qs``, ``an``, ``mru``, ``jet``: the estimators whose spec says ``skips_errors``, which take
        the keyword; docs/UNCERTAINTY.md), and ``info["standard_errors"]`` is True. False (the
        default): ``k1_se`` and ``k2_se`` are NaN everywhere and the call pays nothing for them: the
        fits neither fit a region's neighbours nor run the pooling pass nor add up the standard
        errors' sums (their kernels are compiled without them). k1, k2, the directions, ``valid``
        and ``reason`` are the same either way.
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


def _signature_of_one(return_annotation: str) -> inspect.Signature:
    """``_iter_estimates``' signature for one method at one range: the keywords and their defaults are
    written once, there; help() and editors show them on :func:`iter_estimate` and :func:`estimate` too."""
    one = {"methods": inspect.Parameter("method", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=None,
                                        annotation="str | None"),
           "ranges": inspect.Parameter("range", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=None)}
    own = inspect.signature(_iter_estimates)
    return own.replace(parameters=[one.get(name, p) for name, p in own.parameters.items()],
                       return_annotation=return_annotation)


iter_estimate.__signature__ = _signature_of_one("Generator[float, None, Curvature]")
estimate.__signature__ = _signature_of_one("Curvature")
