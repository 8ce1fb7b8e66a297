"""The driver of the per-vertex fits (nc, qs, an, mru, jet): their inputs as bundles, one pair of
kernels for all of them, the chunked launches, the standard errors' finish, several ranges in one walk.

A fit is its per-vertex functions, registered for the type of a marker value (:func:`register_fit`);
the two ``@jit_parallel`` kernels here run any of them, numba choosing the fit's own functions at
compile time by the marker's type (a separately compiled kernel per fit, no branch on a method):

- :func:`fit_kernel` ``(fit, chunk, search, geometry, out, errors, model, mesh)`` fits the vertices
  ``centres[lo:hi]`` of ``chunk = (centres, lo, hi)`` at one radius each, splitting them into
  ``search.stamps.shape[0]`` slices, each with its own row of the stamps and queues and its own
  scratch (the fit's ``thread``);
- :func:`fit_levels_kernel` ``(fit, chunk, walk, geometry, out, errors)`` fits them at every row of
  ``walk.radii`` (levels, n) in one walk (:func:`run_fit_levels`: the least-squares fits without
  standard errors, whose sums do not share; the jet with them).

The bundles: :class:`Search` / :class:`Walk` (the radius, the support's adjacency and per-thread
scratch), :class:`~curv.estimators._frames.Geometry` (positions and normals),
:class:`~curv.estimators._principal.Rows` (the outputs), and for the standard errors an
:class:`~curv.uncertainty.parts.Errors` or None, the normals' model
(:class:`~curv.uncertainty.normals_model.NoiseModel`, ``noise_model="normals"``) or None, and
:data:`ON_MESH` or None (a point cloud, or no standard errors); a fit's ``at`` gets the last two as
``noise = (model, mesh)`` (numba's parallel loop takes bundles of arrays or scalars, or None, as a
kernel's arguments, not a tuple that nests a bundle). A fit compiled with None for any of them has
none of their code: numba drops the branches on an argument that is None (only then: a helper never
returns None for a value it was given, which would make its result Optional), so the default call
pays nothing for the standard errors.
"""

from __future__ import annotations

from collections import namedtuple
from typing import Generator

import numpy as np
from numba.extending import overload

from ..core.jit import (JIT_OPTIONS, iter_chunks, jit, jit_inlined, jit_parallel, launch, prange, rescaled, slice_bounds,
                        threads)
from ..core.mesh import Mesh
from ..core.support import support_of as input_support  # not this module's support_of (a walk)
from ..core.result import Principal
from ..geometry.neighbourhood import (all_centres, ball_support, blocked_vertices, coordinate_columns,
                                      expansion_adjacency, new_queues, new_scratch, start_ball_support,
                                      widen_ball_support)
from ..uncertainty.noise_models import SAMPLE_RUN, sampled_scales
from ..uncertainty.normals_model import NoiseModel
from ..uncertainty.parts import new_errors
from ..uncertainty.pooling import POOL_KERNEL, pool_members, pool_rings, pool_standard_errors
from ..uncertainty.parts import SE_PARTS_BYTES
from ._frames import MIN_TANGENT_LENGTH, geometry_of, normal_frame
from ._principal import MIN_PAIRS, finish_fit, level_rows, mark_degenerate, new_rows
from .registry import EstimatorSpec

__all__ = ["Search", "Walk", "FitFunctions", "LevelSums", "ON_MESH", "register_fit", "register_level_sums",
           "fit_kernel", "fit_levels_kernel", "KERNELS",
           "fit_spec", "run_fit",
           "run_fit_levels", "support_of", "start_levels", "walk_level"]

Search = namedtuple("Search", ["radius", "indptr", "indices", "stamps", "queues"])
"""One radius per vertex: ``radius`` (n,), the search's adjacency (``indptr``, ``indices``:
:func:`~curv.geometry.neighbourhood.expansion_adjacency`), and per thread slice a row of the visited
``stamps`` and of the ``queues`` ((slices, n) int64)."""

Walk = namedtuple("Walk", ["radii", "indptr", "indices", "stamps", "queues", "waiting", "waiting_d2"])
"""Several radii per vertex in one walk: ``radii`` (levels, n) ascending per vertex, the adjacency and
the stamps and queues as in :class:`Search`, and per thread slice the vertices met beyond a level
(``waiting`` int64, ``waiting_d2`` float64, (slices, n))."""

OnMesh = namedtuple("OnMesh", [])
ON_MESH = OnMesh()
"""The standard errors of a fit on a mesh, whose vertex normals share faces (None on a point cloud)."""

FitFunctions = namedtuple("FitFunctions", ["at", "thread", "levels_at", "level_thread"])
"""A fit's ``@jit`` functions (:func:`register_fit`):

- ``at(fit, p, queue, count, r, geometry, out, errors, noise, thread)``: the fit at vertex p over its
  support ``queue[:count]`` (p first) in the ball of radius r; writes row p of ``out`` (and of
  ``errors``) and returns ``thread`` (its scratch, grown perhaps);
- ``thread(fit, t)``: thread slice t's scratch;
- ``levels_at(fit, p, walk, geometry, out, errors, walker, thread)``: the fit at every level of
  ``walk`` (``walker = (stamp, queue, waiting, waiting_d2)``, the slice's rows), or None: a fit per
  level;
- ``level_thread(fit, t)``: its scratch."""

LevelSums = namedtuple("LevelSums", ["empty", "add", "solve"])
"""A fit whose rows do not depend on the radius, several ranges in one walk (:func:`sums_levels_at`;
``@jit`` functions of the fit's marker and more): ``empty(fit)`` its sums before any row;
``add(fit, sums, p, q, geometry, frame, tiny2)`` -> ``(sums, l2, usable)``, q's rows added when q is
usable (its tangent length squared ``l2`` above ``tiny2``, and whatever else the fit needs), else
``sums`` as they were; ``solve(fit, sums)`` -> ``(W, singular)``."""

_FITS: dict = {}
_LEVEL_SUMS: dict = {}


def register_fit(marker: type, functions: FitFunctions) -> None:
    """Run ``functions`` for the fits whose marker is an instance of ``marker`` (a namedtuple class:
    its fields, if any, are the fit's options, e.g. the jet's degree)."""
    _FITS[marker] = functions


def register_level_sums(marker: type, sums: LevelSums) -> tuple:
    """``(levels_at, level_thread)`` of the :class:`FitFunctions` of a fit whose rows do not depend
    on the radius: :func:`sums_levels_at` with ``sums`` (:class:`LevelSums`)."""
    _LEVEL_SUMS[marker] = sums
    return sums_levels_at, no_scratch


def _functions(fit) -> FitFunctions:
    return _FITS[fit.instance_class]


def fit_at(fit, p, queue, count, r, geometry, out, errors, noise, thread):
    """The fit's ``at`` (:class:`FitFunctions`), chosen by the type of ``fit`` inside numba code."""
    raise NotImplementedError("called from numba code only")


def fit_thread(fit, t):
    """The fit's per-thread scratch (:class:`FitFunctions`), inside numba code."""
    raise NotImplementedError("called from numba code only")


def fit_levels_at(fit, p, walk, geometry, out, errors, walker, thread):
    """The fit's ``levels_at`` (:class:`FitFunctions`), inside numba code."""
    raise NotImplementedError("called from numba code only")


def fit_level_thread(fit, t):
    """The fit's ``level_thread`` (:class:`FitFunctions`), inside numba code."""
    raise NotImplementedError("called from numba code only")


# inlined: the kernel calls the fit's own function, not a wrapper that would take every array of the
# bundles again (a call's array arguments are reference-counted on entry and exit, per vertex)
@overload(fit_at, jit_options=JIT_OPTIONS, inline="always")
def _fit_at(fit, p, queue, count, r, geometry, out, errors, noise, thread):
    at = _functions(fit).at
    return lambda fit, p, queue, count, r, geometry, out, errors, noise, thread: at(
        fit, p, queue, count, r, geometry, out, errors, noise, thread)


@overload(fit_thread, jit_options=JIT_OPTIONS)
def _fit_thread(fit, t):
    make = _functions(fit).thread
    return lambda fit, t: make(fit, t)


@overload(fit_levels_at, jit_options=JIT_OPTIONS, inline="always")
def _fit_levels_at(fit, p, walk, geometry, out, errors, walker, thread):
    levels_at = _functions(fit).levels_at
    return lambda fit, p, walk, geometry, out, errors, walker, thread: levels_at(
        fit, p, walk, geometry, out, errors, walker, thread)


@overload(fit_level_thread, jit_options=JIT_OPTIONS)
def _fit_level_thread(fit, t):
    make = _functions(fit).level_thread
    return lambda fit, t: make(fit, t)


def level_sums_empty(fit):
    """The fit's :class:`LevelSums` ``empty``, inside numba code."""
    raise NotImplementedError("called from numba code only")


def level_sums_add(fit, sums, p, q, geometry, frame, tiny2):
    """The fit's :class:`LevelSums` ``add``, inside numba code."""
    raise NotImplementedError("called from numba code only")


def level_sums_solve(fit, sums):
    """The fit's :class:`LevelSums` ``solve``, inside numba code."""
    raise NotImplementedError("called from numba code only")


@overload(level_sums_empty, jit_options=JIT_OPTIONS)
def _level_sums_empty(fit):
    empty = _LEVEL_SUMS[fit.instance_class].empty
    return lambda fit: empty(fit)


@overload(level_sums_add, jit_options=JIT_OPTIONS)
def _level_sums_add(fit, sums, p, q, geometry, frame, tiny2):
    add = _LEVEL_SUMS[fit.instance_class].add
    return lambda fit, sums, p, q, geometry, frame, tiny2: add(fit, sums, p, q, geometry, frame, tiny2)


@overload(level_sums_solve, jit_options=JIT_OPTIONS)
def _level_sums_solve(fit, sums):
    solve = _LEVEL_SUMS[fit.instance_class].solve
    return lambda fit, sums: solve(fit, sums)


@jit_inlined
def support_of(p, search, geometry, stamp, queue):
    """Vertex p's support in the ball of ``search.radius[p]`` (:func:`~curv.geometry.neighbourhood.ball_support`):
    ``queue[:count]``, p first. Returns ``(count, queue)``."""
    return ball_support(p, search.radius[p] ** 2, search.indptr, search.indices, geometry.x, geometry.y, geometry.z, stamp, queue)


@jit
def start_levels(p, walk, geometry, out):
    """Start vertex p's fit at every level of ``walk`` (:func:`run_fit_levels`): its frame
    (:func:`~curv.estimators._frames.normal_frame`) and ``(MIN_TANGENT_LENGTH * r)²`` at the widest
    level, the bound below which a row's tangent length may count at one level and not at a wider one.

    Returns
    -------
    frame : 9-tuple of float
    band2 : float
    ok : bool
        False without a finite normal: every level's row p is marked
        (:func:`~curv.estimators._principal.mark_degenerate`).
    """
    frame, ok = normal_frame(p, geometry)
    levels = walk.radii.shape[0]
    if not ok:
        for level in range(levels):
            mark_degenerate(p, level_rows(out, level))
        return frame, 0.0, False
    return frame, (MIN_TANGENT_LENGTH * walk.radii[levels - 1, p]) ** 2, True


@jit
def walk_level(p, level, walk, geometry, walker, state):
    """Widen p's support to level ``level`` of ``walk`` (:func:`~curv.geometry.neighbourhood.widen_ball_support`;
    start with ``state = (1, 0, 0)`` after :func:`~curv.geometry.neighbourhood.start_ball_support`).
    ``walker = (stamp, queue, waiting, waiting_d2)`` are the slice's rows. Returns the new
    ``(count, head, pending)``: ``queue[:count]`` is the support at this level, the rows from the
    last count on are new."""
    r = walk.radii[level, p]
    stamp, queue, waiting, waiting_d2 = walker
    return widen_ball_support(p, r ** 2, level + 1 < walk.radii.shape[0], (walk.indptr, walk.indices),
                              (geometry.x, geometry.y, geometry.z), stamp, queue, state, (waiting, waiting_d2))


@jit
def sums_levels_at(fit, p, walk, geometry, out, errors, walker, thread):
    """The fit at vertex p at every level of ``walk`` in one walk, for a fit whose rows do not depend
    on the radius (:class:`LevelSums`): the rows of each level's new vertices are added to the last
    level's sums. A row whose tangent length is so short that a wider level's bound would drop it
    (``banded``) makes the following levels add up their whole support again, each with its own
    bound."""
    frame, band2, ok = start_levels(p, walk, geometry, out)
    if not ok:
        return
    queue = walker[1]
    state = (start_ball_support(p, walker[0], queue), 0, 0)
    empty = level_sums_empty(fit)
    sums, used, done, banded = empty, 0, 1, False
    for level in range(walk.radii.shape[0]):
        state = walk_level(p, level, walk, geometry, walker, state)
        if banded:
            sums, used, done, banded = empty, 0, 1, False
        tiny2 = (MIN_TANGENT_LENGTH * walk.radii[level, p]) ** 2
        for i in range(done, state[0]):
            sums, l2, usable = level_sums_add(fit, sums, p, queue[i], geometry, frame, tiny2)
            if usable:
                banded = banded or not (l2 > band2)
                used += 1
        done = state[0]
        shape, singular = level_sums_solve(fit, sums)
        finish_fit(p, shape, singular, used, frame, level_rows(out, level))


@jit
def no_scratch(fit, t):
    """No scratch beyond the walk's."""
    return t


@jit_parallel
def fit_kernel(fit, chunk, search, geometry, out, errors, model, mesh):
    """``fit`` at the vertices ``centres[lo:hi]`` of ``chunk = (centres, lo, hi)``, one radius each
    (module notes)."""
    centres, lo, hi = chunk
    # the search's arrays apart before the parallel loop and together again in it: numba's parallel
    # loop does not take a bundle that nests a tuple (a point cloud's grid) from outside
    radius, indptr, indices, stamps, queues = search
    slices = stamps.shape[0]
    for t in prange(slices):
        stamp, queue = stamps[t], queues[t]
        here = Search(radius, indptr, indices, stamps, queues)
        thread = fit_thread(fit, t)
        noise = (model, mesh)
        start, stop = slice_bounds(lo, hi, t, slices)
        for i in range(start, stop):
            p = centres[i]
            count, queue = support_of(p, here, geometry, stamp, queue)
            thread = fit_at(fit, p, queue, count, radius[p], geometry, out, errors, noise, thread)


@jit_parallel
def fit_levels_kernel(fit, chunk, walk, geometry, out, errors):
    """``fit`` at every level of ``walk`` at the vertices ``centres[lo:hi]`` of ``chunk``, one walk
    per vertex (module notes)."""
    centres, lo, hi = chunk
    radii, indptr, indices, stamps, queues, waiting, waiting_d2 = walk  # apart, as in fit_kernel
    slices = stamps.shape[0]
    for t in prange(slices):
        here = Walk(radii, indptr, indices, stamps, queues, waiting, waiting_d2)
        walker = (stamps[t], queues[t], waiting[t], waiting_d2[t])
        thread = fit_level_thread(fit, t)
        start, stop = slice_bounds(lo, hi, t, slices)
        for i in range(start, stop):
            fit_levels_at(fit, centres[i], here, geometry, out, errors, walker, thread)


KERNELS = (fit_kernel, fit_levels_kernel, POOL_KERNEL)
"""What a fit's registry entry lists among its kernels (a first run compiles them)."""


def fit_spec(**fields) -> EstimatorSpec:
    """A fit's registry entry: ``fields`` over what the fits share (any polygon mesh and point
    clouds, no closed ring needed, :data:`~curv.estimators._principal.MIN_PAIRS` neighbours at least,
    the kernels above, standard errors when asked, several ranges in one call)."""
    shared = dict(triangles_only=False, closed_ring=False, takes_points=True, min_neighbours=MIN_PAIRS,
                  kernels=KERNELS, extra_bytes_per_unit=SE_PARTS_BYTES, skips_errors=True, pools_errors=True,
                  takes_levels=True)
    return EstimatorSpec(**{**shared, **fields})


def run_fit(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, fit, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, noise_model: str | None = None,
            standard_errors: bool = False) -> Generator[float, None, Principal | list]:
    """Run a fit's kernel over all (or some) vertices, a chunk of them per call, and assemble the result.

    ``radii`` of shape ``(levels, n)`` (several ranges, ascending per vertex) gives one result per
    level (:func:`run_fit_levels`).

    Parameters
    ----------
    mesh : Mesh or PointCloud
    normals : (n, 3) float64
        Unit vertex normals (NaN rows: no frame, the vertex is ``DEGENERATE``).
    radii : (n,) float64
        Ball radius of every vertex (:func:`curv.core.ranges.ball_radii`).
    fit : namedtuple
        The fit's marker (:func:`register_fit`).
    chunk : int, optional
        Vertices per call (default adaptive).
    centres : (c,) int64, optional
        The vertices to estimate (default all); the other rows of the outputs are left unset. With
        standard errors on a mesh the fits also run at their neighbours
        (:func:`curv.uncertainty.pooling.pool_members`; ``radii`` must cover them), whose residuals
        the standard errors pool.
    features : curv.core.features.FeatureSet, optional
        The search does not expand through feature vertices.
    noise_model : str, optional
        For the fits with a model of their normals' errors (an, mru;
        :data:`~curv.uncertainty.noise_models.NOISE_MODELS`): ``"normals"`` runs the kernel with that
        model on a mesh; ``"sampled"`` runs it without and scales the standard errors by
        :func:`~curv.uncertainty.noise_models.sampled_scales`.
    standard_errors : bool
        True: the kernels also write the standard errors' parts, a second pass pools them, and the
        result carries ``k1_se``, ``k2_se``. False (the default): none of that, and the fits run at
        ``centres`` only. The curvatures, directions and reasons are the same either way (each
        vertex's fit reads only its own support).

    It yields the fraction of vertices done and returns the :class:`~curv.core.result.Principal`,
    as the estimators' functions do (:data:`~curv.estimators.registry.EstimatorFunction`).
    """
    if np.ndim(radii) == 2:
        return (yield from run_fit_levels(mesh, normals, radii, fit, chunk=chunk, centres=centres,
                                          features=features, noise_model=noise_model,
                                          standard_errors=standard_errors))
    n = mesh.n_vertices
    given = centres is not None
    centres = all_centres(n, centres)
    if standard_errors:
        # each vertex once (the pooling pass updates its rows in place)
        pooled = np.unique(centres) if given else centres
        whole = pooled.size == n
        # a region's standard errors pool its neighbours' residuals too: fit them as well
        fitted = centres if whole else pool_members(mesh, pooled)
    else:
        # no pooling: a vertex listed twice is fitted twice, to the same values
        fitted = centres
    rings = pool_rings(mesh)
    indptr, indices = expansion_adjacency(mesh, blocked_vertices(features), radii)
    geometry = geometry_of(coordinate_columns(mesh), normals)
    radius = np.ascontiguousarray(radii, dtype=np.float64)
    slices = max(1, min(threads(), fitted.size))
    search = Search(radius, indptr, indices, new_scratch(n, slices), new_queues(n, slices))
    out = new_rows(n)
    errors = new_errors(n, most_written=whole) if standard_errors else None
    on_mesh = standard_errors and input_support(mesh).has_faces  # pooling reads edge neighbours
    model = NoiseModel(*rings, new_scratch(n, slices)) if on_mesh and noise_model == "normals" else None
    mesh_errors = ON_MESH if on_mesh else None

    def run(lo: int, hi: int) -> None:
        launch(fit_kernel, fit, (fitted, lo, hi), search, geometry, out, errors, model, mesh_errors)

    yield from iter_chunks(fitted.size, run, chunk=chunk)
    if not standard_errors:
        return Principal(k1=out.k1, k2=out.k2, d1=out.d1, d2=out.d2, reason=out.reason)
    if noise_model == "sampled" and on_mesh:
        def run_normals(sample: np.ndarray) -> None:
            parts = max(1, min(threads(), sample.size // SAMPLE_RUN))
            fresh = Search(radius, indptr, indices, new_scratch(n, parts), search.queues)  # fresh marks
            launch(fit_kernel, fit, (sample, 0, sample.size), fresh, geometry, out, errors,
                   NoiseModel(*rings, new_scratch(n, parts)), ON_MESH)

        scales = sampled_scales(run_normals, fitted, out.reason, errors)
        if scales is not None:
            # the independent model's noise levels, now all of the same units: pooled
            at = slice(None) if whole else fitted
            errors.k1_se[at] *= scales[0]
            errors.k2_se[at] *= scales[1]
            errors.parts[at, 2] *= scales[2]
            errors.alone[:] = False
    pool_standard_errors(pooled, rings[0], rings[1], out.reason, errors)
    if not whole:
        extra = np.setdiff1d(fitted, pooled, assume_unique=True)
        errors.k1_se[extra] = np.nan
        errors.k2_se[extra] = np.nan
    return Principal(k1=out.k1, k2=out.k2, d1=out.d1, d2=out.d2, reason=out.reason, k1_se=errors.k1_se,
                     k2_se=errors.k2_se)


def run_fit_levels(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, fit, *,
                   chunk: int | None = None, centres: np.ndarray | None = None, features=None,
                   noise_model: str | None = None, standard_errors: bool = False) -> Generator[float, None, list]:
    """A fit at several ranges: one :class:`~curv.core.result.Principal` per row of ``radii``.

    Without standard errors, on a mesh, the ranges share one walk per vertex and its sums:
    the fit's ``levels_at`` widens the support level by level
    (:func:`~curv.geometry.neighbourhood.widen_ball_support`: each level's support is exactly the
    single search's at its radius), adds the rows of the vertices each level brings to the normal
    equations of the last and solves them at every level. The sums are added in the walk's order,
    not the single search's, so the values agree with one call per range to rounding (the first
    level's order is the single search's: its values are bit for bit those of its own call where
    the rows do not depend on the radius, nc, qs and mru; an's are summed in the widest level's
    coordinates). Otherwise (standard errors, whose sums do not share, or a point cloud) each level
    runs :func:`run_fit` on its own.

    Parameters
    ----------
    mesh, normals, fit, chunk, centres, features, noise_model, standard_errors :
        As in :func:`run_fit`.
    radii : (levels, n) float64
        The radii of every vertex at each level, ascending per vertex.
    """
    radii = np.ascontiguousarray(radii, dtype=np.float64)
    count = radii.shape[0]
    if standard_errors or _FITS[type(fit)].levels_at is None or not input_support(mesh).has_faces:
        out = []
        for level in range(count):
            gen = run_fit(mesh, normals, radii[level], fit, chunk=chunk, centres=centres, features=features,
                          noise_model=noise_model, standard_errors=standard_errors)
            out.append((yield from rescaled(gen, level / count, (level + 1) / count)))
        return out
    n = mesh.n_vertices
    centres = all_centres(n, centres)
    indptr, indices = expansion_adjacency(mesh, blocked_vertices(features))
    geometry = geometry_of(coordinate_columns(mesh), normals)
    slices = max(1, min(threads(), centres.size))
    walk = Walk(radii, indptr, indices, new_scratch(n, slices), new_queues(n, slices), new_queues(n, slices),
                np.empty((slices, n)))
    out = new_rows(n, count)

    def run(lo: int, hi: int) -> None:
        launch(fit_levels_kernel, fit, (centres, lo, hi), walk, geometry, out, None)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return [Principal(k1=out.k1[i], k2=out.k2[i], d1=out.d1[i], d2=out.d2[i], reason=out.reason[i])
            for i in range(count)]
