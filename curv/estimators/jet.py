"""Osculating jet fitting (Cazals & Pouget, SGP 2003), over the range support.

At each vertex p, with support S(p) = p and the vertices of its ball (:mod:`curv.geometry.neighbourhood`):

1. **Frame.** PCA of S(p): the eigenvector of the smallest eigenvalue of the covariance about the
   centroid is the height axis ``e3`` (turned to agree with the given vertex normal), the largest
   gives ``e1``, ``e2 = e3 x e1``. The origin is p.
2. **Fit.** In coordinates divided by ``h`` (the largest distance from p to its support, for
   conditioning), least squares of the height ``w = J(u, v) = sum_{i+j<=d} J_ij u^i v^j`` over S(p):
   ``N_d = (d+1)(d+2)/2`` unknowns, constant and linear terms included, so the jet finds its own
   tangent plane. With ``weights="smooth"`` a support point at distance d counts with
   ``w = (1 - d²/r²)^4`` (r the ball radius; 1 at the centre, 0 at the edge with its first three
   derivatives, as in MLS and APSS) in the PCA and in the fit (weighted least squares); the default
   ``"uniform"`` counts every point alike. Normal equations, Jacobi-scaled, Cholesky; fewer than ``N_d`` points is
   ``TOO_FEW_NEIGHBOURS``, an estimated reciprocal condition number below :data:`RCOND` is
   ``SINGULAR``.
3. **Differential quantities** of the graph ``(u, v, J(u, v))`` at ``(0, 0)``: the jet normal
   ``n = (-J_10, -J_01, 1) / sqrt(1 + J_10^2 + J_01^2)``, first fundamental form ``E = 1 + J_10^2``,
   ``F = J_10 J_01``, ``G = 1 + J_01^2``, second ``L = 2 J_20 / |.|``, ``M = J_11 / |.|``,
   ``N = 2 J_02 / |.|``; the shape operator ``I^-1 II`` in an orthonormal tangent basis, its
   eigenpairs the principal curvatures (sign of the house: ``W = -II`` for a graph along ``n``,
   so an outward sphere gives +1/r) and directions, mapped back to 3-D and to unscaled units.
4. **Standard errors** (``standard_errors=True``) of k1, k2 from the fit's residuals, propagated
   through step 3 to first order (:func:`~curv.estimators._jet_fit.jet_errors`, docs/UNCERTAINTY.md).

Which normal: the given vertex normal (Max by default) only orients the fit and is the normal the
result reports; k1, k2 are the jet's own (its normal ``n``). The directions are carried from the
jet's tangent plane to the reported normal's by the smallest rotation taking ``n`` to it, so they are
tangent to the reported normal. The angle between the two is about the Max normal's own error:
0.01-0.07 degrees (median) on the study's clean meshes, 5-9 degrees at its 100 % noise. :func:`curv.fitted_normals.fitted_normals` gives the jet normals.

Width: with ``width="adaptive"`` the given ball is the widest of several candidate fits (narrower
balls at the same degree, then the degree-2 smooth fit over the whole ball), chosen per vertex by
the intersection of their confidence intervals (:mod:`curv.estimators.jet_width`); the default
``"fixed"`` is the single fit above.

Works on any polygon mesh and on borders (a one-sided fit there).

On a point cloud whose jet normals were fitted over the same balls (the normals' range, degree 2,
uniform weights: :mod:`curv.point_normals`), the fixed width without standard errors reads the fits
their pass kept instead of fitting again (:mod:`curv.estimators._jet_handover`): one fit per point.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..core.errors import EstimatorError
from ..core.filled import filled
from ..core.jit import iter_chunks, jit, jit_inlined, launch, rescaled, threads
from ..core.mesh import Mesh
from ..core.support import support_of
from ..core.result import Principal
from ..core.validity import OK
from ..geometry.neighbourhood import (all_centres, blocked_vertices, coordinate_columns, expansion_adjacency, new_scratch,
                                      start_ball_support)
from ._fit_driver import (KERNELS, FitFunctions, Search, Walk, fit_kernel, fit_levels_kernel, fit_spec, register_fit,
                          walk_level)
from ._jet_fit import (MAX_UNKNOWNS, RCOND, Points, fit_jet, jet_errors, jet_normal, jet_principal, jet_scratch,
                       smooth_weight)
from ._handover import NormalFits, iter_handed, kept_fits
from ._jet_handover import BYTES_PER_POINT, new_jet_fits
from ._principal import Rows, level_rows
from .jet_width import DEFAULT_WIDTH, WIDTHS, iter_adaptive_jet
from .registry import register

__all__ = ["iter_jet", "DEFAULT_DEGREE", "DEGREES", "DEFAULT_WEIGHTS", "WEIGHTS", "DEFAULT_WIDTH", "WIDTHS", "RCOND",
           "unknowns", "jet_normals", "smooth_weight"]

DEGREES = (2, 3, 4)
"""The jet degrees offered."""

DEFAULT_DEGREE = 2
"""Degree of :func:`iter_jet` unless told otherwise (``curv.estimate(..., degree=d)``). Measured on
the study's protocol meshes (docs/ACCURACY.md): degree 2 is the only one that fits a triangle 1-ring
(R1), and on noisy meshes it is as accurate as degree 3 and 4x more than degree 4 at R4; on clean
meshes degree 4 at R2-R3 is 100-300x more accurate than degree 2."""

WEIGHTS = ("uniform", "smooth")
"""The fit weightings offered (``curv.estimate(..., weights=...)``): ``"uniform"`` (the default)
counts every support point alike; ``"smooth"`` weighs a point at distance d from the centre by
``(1 - d²/r²)^4``, r the ball radius (:func:`smooth_weight`), as MLS and APSS fits do."""

DEFAULT_WEIGHTS = "uniform"


def unknowns(degree: int) -> int:
    """``N_d = (d+1)(d+2)/2``: coefficients of a bivariate polynomial of degree d."""
    return (degree + 1) * (degree + 2) // 2


@jit
def _jet_fit_at(fit, p, level, queue, count, r2, points, out, errors, scratch):
    """The jet at vertex p over its support ``queue[:count]`` in the ball of squared radius ``r2``:
    row p of ``out`` (:class:`~curv.estimators._principal.Rows`) and, with ``errors``, of row
    ``level`` of the standard errors; ``fit = JetFit(degree, smooth)``, ``scratch = (the fit's,
    grads (2, K))``.

    Not inlined: under numba 0.68 the inlined form lost its write of ``out.reason[p]`` (every
    too-small support came out OK), the issue docs/ARCHITECTURE.md notes for csm's ``finish``. The
    scratch is read by index, not unpacked (docs/ARCHITECTURE.md, performance conventions)."""
    code, h, ww = fit_jet(p, count, queue, points, fit.degree, scratch[0], r2 if fit.smooth else 0.0)
    if code == OK:
        code = jet_principal(scratch[0], h, points.normals, out, p)
        if errors is not None:
            jet_errors(p, level, errors, scratch[0], (h, count, fit.degree, ww), scratch[1])
    out.reason[p] = code


@jit_inlined
def _jet_at(fit, p, queue, count, r, points, out, errors, noise, thread):
    """The jet at vertex p (:func:`~curv.estimators._fit_driver.fit_kernel`; ``errors`` (1, n) each
    or None; ``noise`` is not read)."""
    _jet_fit_at(fit, p, 0, queue, count, r ** 2, points, out, errors, thread)
    return thread


@jit
def _jet_thread(fit, t):
    """Thread slice t's scratch: the fit's and the standard errors' gradients."""
    return jet_scratch(), np.empty((2, MAX_UNKNOWNS))


@jit
def _jet_levels_at(fit, p, walk, points, out, errors, walker, thread):
    """The jet at vertex p at every level of ``walk`` in one walk (:func:`~curv.geometry.neighbourhood.widen_ball_support`:
    each level's support is exactly the single search's). The PCA frame and the scale h follow the
    support, so every level fits its own support anew: the walk is what the levels share. ``out`` and
    ``errors`` hold (levels, n) rows."""
    queue = walker[1]
    state = (start_ball_support(p, walker[0], queue), 0, 0)
    for level in range(walk.radii.shape[0]):
        state = walk_level(p, level, walk, points, walker, state)
        _jet_fit_at(fit, p, level, queue, state[0], walk.radii[level, p] ** 2, points, level_rows(out, level), errors,
                    thread)


JetFit = namedtuple("JetFit", ["degree", "smooth"])
"""The jet's marker for the fit kernels (:mod:`curv.estimators._fit_driver`), with its options."""
register_fit(JetFit, FitFunctions(_jet_at, _jet_thread, _jet_levels_at, _jet_thread))


@jit
def _normal_at(fit, p, queue, count, r, points, out, errors, noise, thread):
    """The unit normal of the jet at vertex p: rows p of ``out = (normals (n, 3), reason (n,))``."""
    normals, reason = out
    code, _, _ = fit_jet(p, count, queue, points, fit.degree, thread, r ** 2 if fit.smooth else 0.0)
    if code == OK:
        jet_normal(thread[1], thread[3], normals, p)
    reason[p] = code
    return thread


@jit
def _normal_thread(fit, t):
    """Thread slice t's scratch of the fit."""
    return jet_scratch()


JetNormalsFit = namedtuple("JetNormalsFit", ["degree", "smooth"])
"""The jet normals' marker for the fit kernels (:func:`jet_normals`)."""
register_fit(JetNormalsFit, FitFunctions(_normal_at, _normal_thread, None, None))


def _matches_normal_fits(degree: int, smooth: bool, adaptive: bool, standard_errors: bool) -> bool:
    """Whether a jet with these options is the fit of a point cloud's jet normals (degree
    :data:`DEFAULT_DEGREE`, uniform weights, :mod:`curv.point_normals`), finished as a fit would
    finish it: the fixed width, no standard errors (they read the fit's normal matrix, not kept)."""
    return degree == DEFAULT_DEGREE and not smooth and not adaptive and not standard_errors


JET_FITS = NormalFits(("jet", DEFAULT_DEGREE, False), new_jet_fits, BYTES_PER_POINT)
"""The jet normals' fits as the jet estimator reads them (:mod:`curv.estimators._jet_handover`)."""


def _reads_normal_fits(options: dict, standard_errors: bool) -> NormalFits | None:
    """The registry's ``reads_normal_fits``: :data:`JET_FITS` when :func:`_matches_normal_fits` of these options."""
    matches = _matches_normal_fits(check_degree(options.get("degree", DEFAULT_DEGREE)),
                                   check_weights(options.get("weights", DEFAULT_WEIGHTS)),
                                   check_width(options.get("width", DEFAULT_WIDTH)), bool(standard_errors))
    return JET_FITS if matches else None


def check_degree(degree) -> int:
    """The degree as an int; :class:`~curv.core.errors.EstimatorError` unless it is one of :data:`DEGREES`."""
    if isinstance(degree, (bool, np.bool_)) or degree not in DEGREES:
        raise EstimatorError(f"jet degree must be one of {', '.join(map(str, DEGREES))}; got {degree!r}")
    return int(degree)


def check_weights(weights) -> bool:
    """True for ``"smooth"``, False for ``"uniform"``; :class:`~curv.core.errors.EstimatorError` otherwise."""
    if not isinstance(weights, str) or weights not in WEIGHTS:
        raise EstimatorError(f"jet weights must be one of {', '.join(WEIGHTS)}; got {weights!r}")
    return weights == "smooth"


def check_width(width) -> bool:
    """True for ``"adaptive"``, False for ``"fixed"``; :class:`~curv.core.errors.EstimatorError` otherwise."""
    if not isinstance(width, str) or width not in WIDTHS:
        raise EstimatorError(f"jet width must be one of {', '.join(WIDTHS)}; got {width!r}")
    return width == "adaptive"


def _inputs(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, centres: np.ndarray, features):
    """The jet's :class:`Points` and its search's adjacency and scratch (:class:`~curv.estimators._fit_driver.Search`,
    or the radii and the walk's extra scratch for (levels, n) radii)."""
    indptr, indices = expansion_adjacency(mesh, blocked_vertices(features), radii)
    x, y, z = coordinate_columns(mesh)
    # any layout: the cached normals are column-major, and a copy would cost the whole mesh per region
    points = Points(x, y, z, np.asarray(normals, dtype=np.float64))
    radius = np.ascontiguousarray(radii, dtype=np.float64)
    parts = max(1, min(threads(), centres.size))
    # A queue as long as the mesh per thread: ball_support never has to grow it. Growing it inside
    # the prange body (reassigning the array there) returned garbage supports on large balls.
    stamps, queues = new_scratch(mesh.n_vertices, parts), np.empty((parts, mesh.n_vertices), np.int64)
    if radius.ndim == 2:
        # the walk's vertices met beyond a level, waiting for a wider one: never past the mesh's size
        return points, Walk(radius, indptr, indices, stamps, queues, np.empty_like(queues), np.empty(queues.shape))
    return points, Search(radius, indptr, indices, stamps, queues)


def iter_jet(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
             degree: int = DEFAULT_DEGREE, weights: str = DEFAULT_WEIGHTS, centres: np.ndarray | None = None,
             features=None, width: str = DEFAULT_WIDTH, standard_errors: bool = False):
    """Osculating jet of degree ``degree`` over each vertex's ball support.

    Parameters
    ----------
    mesh : Mesh
        Any polygon mesh.
    normals : (n, 3) float64
        Unit vertex normals; they orient each fit and its curvature sign (NaN rows: ``DEGENERATE``).
    radii : (n,) or (levels, n) float64
        Ball radius of every vertex (:func:`curv.core.ranges.ball_radii`, ``uses_normals=False``), or
        of every vertex at each of several levels, ascending per vertex (several ranges in one call:
        on a mesh with the fixed width one walk serves them all, :func:`_jet_levels_at`; the
        values agree with a call per level to rounding, as the support's sums are added in the
        walk's order).
    chunk : int, optional
        Vertices per kernel call (default adaptive).
    degree : {2, 3, 4}
        Jet degree; the support must hold at least ``(d+1)(d+2)/2`` points, the centre included.
    weights : {"uniform", "smooth"}
        How the support points count in the PCA frame and the fit (:data:`WEIGHTS`). At a given
        range the smooth fit has less bias and more noise than the uniform one (about half the
        degree-2 bias on a sphere, 2.6-2.8x the spread under noise); its standard errors treat the
        weights as inverse variances (first order), which puts them about 20 % below the spread
        measured on a noisy sphere (within 10 % with uniform weights).
    centres : (c,) int64, optional
        The vertices to estimate (default all); other rows are left unset.
    features : curv.core.features.FeatureSet, optional
        The supports do not expand through feature vertices.
    width : {"fixed", "adaptive"}
        ``"fixed"`` (the default) fits over the given ball. ``"adaptive"`` chooses per vertex among
        the degree-``degree`` jets over narrower balls and the degree-2 smooth jet over the whole
        ball, by the intersection of their confidence intervals (:mod:`curv.estimators.jet_width`;
        7 fits, all within the given ball).
    standard_errors : bool
        Also the standard errors of k1 and k2 (:func:`~curv.estimators._jet_fit.jet_errors`); False (the default): none,
        and the kernels compile without them.

    Yields
    ------
    float
        Fraction of vertices done.

    Returns
    -------
    Principal, or a list of one per level
        k1 >= k2 of the jet, directions tangent to ``normals``; reasons ``TOO_FEW_NEIGHBOURS``,
        ``SINGULAR``, ``DEGENERATE`` where there is no fit; ``k1_se``, ``k2_se`` when asked.
    """
    degree = check_degree(degree)
    smooth = check_weights(weights)
    levels = np.ndim(radii) == 2
    if levels and (check_width(width) or not support_of(mesh).has_faces):
        # the adaptive width, and a point cloud's grid: a fit per level
        out = []
        for level in range(len(radii)):
            out.append((yield from iter_jet(mesh, normals, radii[level], chunk=chunk, degree=degree, weights=weights,
                                            centres=centres, features=features, width=width,
                                            standard_errors=standard_errors)))
        return out
    if check_width(width):
        return (yield from iter_adaptive_jet(mesh, normals, radii, chunk=chunk, degree=degree, weights=weights,
                                             centres=centres, features=features, standard_errors=standard_errors))
    n = mesh.n_vertices
    centres = all_centres(n, centres)
    whole = centres.size == n
    count = len(radii) if levels else 1
    shape = (count, n) if levels else (n,)

    def nan(*tail):
        return filled(shape + tail, np.nan, most_written=whole)

    out = Rows(nan(), nan(), nan(3), nan(3), np.zeros(shape, np.uint8))
    # a leading axis of levels (one for a single range)
    errors = (filled((count, n), np.nan, most_written=whole),
              filled((count, n), np.nan, most_written=whole)) if standard_errors else None
    fitted = centres
    kept = None
    if not levels and features is None and _matches_normal_fits(degree, smooth, False, standard_errors):
        # a cloud's jet normals fitted these balls already (their pass kept the fits): read them
        kept = kept_fits(mesh, JET_FITS.options)
    if kept is not None:
        fitted = yield from rescaled(iter_handed(kept, normals, radii, centres, out, chunk=chunk), 0.0, 0.2)
    if fitted.size:
        points, search = _inputs(mesh, normals, radii, fitted, features)
        fit = JetFit(degree, smooth)

        def run(lo, hi):
            if levels:
                launch(fit_levels_kernel, fit, (fitted, lo, hi), search, points, out, errors)
            else:
                launch(fit_kernel, fit, (fitted, lo, hi), search, points, out, errors, None, None)

        yield from rescaled(iter_chunks(fitted.size, run, chunk=chunk), 0.0 if kept is None else 0.2, 1.0)
    results = []
    for level in range(count):
        at = level if levels else slice(None)
        res = Principal(k1=out.k1[at], k2=out.k2[at], d1=out.d1[at], d2=out.d2[at], reason=out.reason[at],
                        k1_se=None if errors is None else errors[0][level],
                        k2_se=None if errors is None else errors[1][level])
        bad = centres[res.reason[centres] != OK]
        for arr in (res.k1, res.k2, res.d1, res.d2, res.k1_se, res.k2_se):
            if arr is not None:
                arr[bad] = np.nan
        results.append(res)
    return results if levels else results[0]


def jet_normals(mesh: Mesh, reference: np.ndarray, radii: np.ndarray, *, degree: int = DEFAULT_DEGREE,
                weights: str = DEFAULT_WEIGHTS, chunk: int | None = None, features=None,
                centres: np.ndarray | None = None):
    """Unit normals of the jets fitted over each vertex's ball support, a generator.

    Parameters as in :func:`iter_jet` (``reference`` orients each fit; with ``features`` the fits
    do not reach across a crease; ``centres``: only these vertices are fitted).

    Returns
    -------
    normals : (n, 3) float64
        NaN where there is no fit (and at the vertices not in ``centres``).
    reason : (n,) uint8
    """
    degree = check_degree(degree)
    smooth = check_weights(weights)
    n = mesh.n_vertices
    out = np.full((n, 3), np.nan)
    reason = np.zeros(n, np.uint8)
    centres = all_centres(n, centres)
    points, search = _inputs(mesh, reference, radii, centres, features)

    def run(lo, hi):
        launch(fit_kernel, JetNormalsFit(degree, smooth), (centres, lo, hi), search, points, (out, reason), None,
               None, None)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    out[reason != OK] = np.nan
    return out, reason


register(fit_spec(
    name="jet", in_paper=False, title="Osculating jet fitting", ranges=(1, 2, 3, 4), function=iter_jet,
    uses_normals=False, options={"degree": DEGREES, "weights": WEIGHTS, "width": WIDTHS},
    reference="Cazals & Pouget 2003, Estimating differential quantities using polynomial fitting of osculating jets",
    summary="least-squares bivariate polynomial (degree 2-4, with constant and linear terms) in a PCA frame",
    min_neighbours=lambda options: unknowns(options.get("degree", DEFAULT_DEGREE)) - 1,
    extra_bytes_per_unit=0.0, kernels=KERNELS[:2], pools_errors=False,
    reads_normal_fits=_reads_normal_fits, extra_bytes_per_point=JET_FITS.bytes_per_point,
))
