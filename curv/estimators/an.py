"""Adjacent-normal cubic approximation (Goldfeather & Interrante 2004; paper §4.1, ranges R2 and up).

At vertex p with normal N and tangent frame (U, V), write every neighbour q of the support (the
vertices within (k - 1) longest 1-ring edges at Rk) as the offset ``q - p = u U + v V + w N``, in
coordinates divided by the ball radius r. The surface near p is the cubic height field

    w = A/2 u² + B uv + C/2 v² + D u³ + E u²v + F uv² + G v³,

and q's own normal ``N_q = (a, b, c)`` in p's frame gives its two slopes

    w_u = A u + B v + 3D u² + 2E uv + F v² = -a / c,
    w_v = B u + C v + E u² + 2F uv + 3G v² = -b / c,

three equations per neighbour in the seven unknowns (A .. G), solved by least squares (Jacobi-scaled
Cholesky). Back in unscaled coordinates the shape operator is (house sign, ``dN = W t``)

    W = -[[A, B], [B, C]] / r,

whose eigenpairs are the principal curvatures and directions (an outward sphere of radius R gives
k1 = k2 = +1/R). The module reads support -> frame -> rows (:func:`height_row`, :func:`slope_rows`;
summed by :func:`add_height`, :func:`add_slopes`) -> 7x7 solve -> :func:`shape_operator` ->
principal curvatures (:func:`_an_at`).

Heights and slopes enter with equal weight in the radius-scaled coordinates, so the balance of the
two kinds of equation does not depend on the mesh's scale. A neighbour whose normal is tilted more
than about 84 degrees from p's (:data:`MIN_NORMAL_Z`) gives no slope equations. Works on any polygon
mesh, on borders (one-sided there) and on point clouds. Standard errors (``standard_errors=True``):
:func:`curv.uncertainty.factored.height_slope_parts`, with the model of the normals' errors of
``noise_model`` (:mod:`curv.uncertainty.noise_models`).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..core.jit import jit, jit_inlined
from ..core.mesh import Mesh
from ..core.small_linalg import RCOND, cholesky_scaled, cholesky_solve_scaled, scaled_determinant
from ..geometry.neighbourhood import start_ball_support
from ..uncertainty.factored import add_row_sums, height_slope_parts
from ..uncertainty.noise_models import DEFAULT_NOISE_MODEL, NOISE_MODELS, checked_noise_model
from ..uncertainty.normals_model import SLOT_BYTES, model_height, model_slopes, model_start, new_lists
from ..uncertainty.parts import SE_PARTS_BYTES, clear_parts
from ._fit_driver import FitFunctions, fit_spec, register_fit, run_fit, start_levels, walk_level
from ._frames import MIN_TANGENT_LENGTH, normal_frame, normal_in_frame, scaled_offset
from ._principal import finish_fit, level_rows, mark_degenerate
from ._three_unknowns import GOLDFEATHER_INTERRANTE
from .registry import register

__all__ = ["iter_an", "height_row", "slope_rows", "add_height", "add_slopes", "shape_operator", "MIN_NORMAL_Z", "AN"]

MIN_NORMAL_Z = 0.1
"""A neighbour normal tilted more than ~84 degrees from the centre normal gives no slope equation."""

UNKNOWNS = 7

AN_SUMS = 35
"""The normal equations of the 7 unknowns as one tuple of scalars: the upper triangle of ``AᵀA``
row by row (28 entries), then ``Aᵀb`` (7): :func:`add_height`, :func:`add_slopes`."""
NO_SUMS = (0.0,) * AN_SUMS
"""The sums before any equation."""
NO_ROW = (0.0,) * UNKNOWNS


@jit_inlined
def height_row(u, v):
    """The height equation's row ``(u²/2, uv, v²/2, u³, u²v, uv², v³)`` in (A .. G)."""
    uu, uv, vv = u * u, u * v, v * v
    return 0.5 * uu, uv, 0.5 * vv, uu * u, uu * v, u * vv, vv * v


@jit_inlined
def slope_rows(u, v):
    """The slope equations' rows in (A .. G): ``w_u``: (u, v, 0, 3u², 2uv, v², 0) and ``w_v``:
    (0, u, v, 0, u², 2uv, 3v²)."""
    uu, uv, vv = u * u, u * v, v * v
    return (u, v, 0.0, 3.0 * uu, 2.0 * uv, vv, 0.0), (0.0, u, v, 0.0, uu, 2.0 * uv, 3.0 * vv)


@jit_inlined
def add_height(s, u, v, w):
    """The sums ``s`` (:data:`AN_SUMS` float tuple) with the height equation ``height_row(u, v) · x = w``
    added.

    Scalars, not arrays: each product lands in a register, where a row array and a loop over it
    cost a load and a store per entry."""
    uu, uv, vv = u * u, u * v, v * v
    h0, h1, h2, h3, h4, h5, h6 = 0.5 * uu, uv, 0.5 * vv, uu * u, uu * v, u * vv, vv * v
    return (
            s[0] + h0 * h0, s[1] + h0 * h1, s[2] + h0 * h2, s[3] + h0 * h3, s[4] + h0 * h4, s[5] + h0 * h5,
            s[6] + h0 * h6, s[7] + h1 * h1, s[8] + h1 * h2, s[9] + h1 * h3, s[10] + h1 * h4, s[11] + h1 * h5,
            s[12] + h1 * h6, s[13] + h2 * h2, s[14] + h2 * h3, s[15] + h2 * h4, s[16] + h2 * h5, s[17] + h2 * h6,
            s[18] + h3 * h3, s[19] + h3 * h4, s[20] + h3 * h5, s[21] + h3 * h6, s[22] + h4 * h4, s[23] + h4 * h5,
            s[24] + h4 * h6, s[25] + h5 * h5, s[26] + h5 * h6, s[27] + h6 * h6, s[28] + h0 * w, s[29] + h1 * w,
            s[30] + h2 * w, s[31] + h3 * w, s[32] + h4 * w, s[33] + h5 * w, s[34] + h6 * w,
    )


@jit_inlined
def add_slopes(s, u, v, a, b):
    """The sums ``s`` (:data:`AN_SUMS` float tuple) with the slope equations ``w_u = a`` and
    ``w_v = b`` (:func:`slope_rows`) added, the u-slope's products before the v-slope's; their
    rows' zeros are left out."""
    uu, uv2, vv = u * u, 2.0 * (u * v), v * v
    su3, sv3 = 3.0 * uu, 3.0 * vv
    return (
            s[0] + u * u, s[1] + u * v, s[2], s[3] + u * su3, s[4] + u * uv2, s[5] + u * vv, s[6],
            s[7] + v * v + u * u, s[8] + u * v, s[9] + v * su3, s[10] + v * uv2 + u * uu, s[11] + v * vv + u * uv2,
            s[12] + u * sv3, s[13] + v * v, s[14], s[15] + v * uu, s[16] + v * uv2, s[17] + v * sv3, s[18] + su3 * su3,
            s[19] + su3 * uv2, s[20] + su3 * vv, s[21], s[22] + uv2 * uv2 + uu * uu, s[23] + uv2 * vv + uu * uv2,
            s[24] + uu * sv3, s[25] + vv * vv + uv2 * uv2, s[26] + uv2 * sv3, s[27] + sv3 * sv3, s[28] + u * a,
            s[29] + v * a + u * b, s[30] + v * b, s[31] + su3 * a, s[32] + uv2 * a + uu * b, s[33] + vv * a + uv2 * b,
            s[34] + sv3 * b,
    )


@jit_inlined
def shape_operator(a, b, c, inv_r):
    """``W = -[[A, B], [B, C]] / r`` as ``(e, f, g)`` (the fit's second derivatives back in unscaled
    coordinates)."""
    return -a * inv_r, -b * inv_r, -c * inv_r


@jit
def _normal_equations(t2, h, s, ata, vec):
    """``ata`` (8, 7): the upper triangle of the normal matrix, and ``vec[0]`` its right-hand side,
    from the sums ``h`` times ``t2`` plus ``s`` (both :data:`AN_SUMS` tuples; ``t2 = 0``: ``s``
    alone, as it is)."""
    k = 0
    for i in range(UNKNOWNS):
        for j in range(i, UNKNOWNS):
            ata[i, j] = t2 * h[k] + s[k]
            k += 1
        vec[0, i] = t2 * h[28 + i] + s[28 + i]


@jit
def _solve(ata, vec):
    """Solve the normal equations (:func:`_normal_equations`) by the Jacobi-scaled Cholesky factor
    (:func:`~curv.core.small_linalg.cholesky_scaled`, left in ``ata`` with its scales in row 7);
    ``vec[1]`` receives the solution (NaN when singular).

    Returns
    -------
    singular : bool
        The factorisation broke down, a diagonal entry is not finite, or the scaled matrix's
        determinant is at most ``RCOND²``.
    factored : bool
        Whether the factor holds (it then serves the standard errors).
    """
    for i in range(UNKNOWNS):
        if not math.isfinite(ata[i, i]):
            vec[1, :UNKNOWNS] = math.nan
            return True, False
    if not cholesky_scaled(ata, UNKNOWNS, UNKNOWNS):
        vec[1, :UNKNOWNS] = math.nan
        return True, False
    cholesky_solve_scaled(ata, UNKNOWNS, UNKNOWNS, vec)
    if not scaled_determinant(ata, UNKNOWNS) > RCOND * RCOND:
        vec[1, :UNKNOWNS] = math.nan
        return True, True
    return False, True


@jit
def _an_at(fit, p, queue, count, r, geometry, out, errors, noise, thread):
    """The adjacent-normal cubic fit at vertex p over its support ``queue[1:count]`` (ball radius r).

    ``thread`` is the slice's ``(t, (ata (8, 7), vec (2, 7), grads (7, 7)), lists)``: its index; the
    normal equations, then their factor, the right-hand side and the solution, the standard
    errors' gradients; the short lists of the normals' model (:mod:`curv.uncertainty.normals_model`,
    run when ``noise = (model, mesh)`` has a model). Returns ``thread`` (its lists grown, perhaps).
    """
    t, (ata, vec, grads), lists = thread
    clear_parts(p, errors)
    frame, ok = normal_frame(p, geometry)
    if not ok:
        mark_degenerate(p, out)
        return thread
    model, _ = noise  # without it, the standard errors are the same on a mesh and a cloud
    inv_r = 1.0 / r
    tiny2 = MIN_TANGENT_LENGTH ** 2
    sums, bb, used, sloped = NO_SUMS, 0.0, 0, 0
    heights, u_slopes, v_slopes = NO_ROW, NO_ROW, NO_ROW  # the standard errors' shared columns
    state, lists = model_start(p, t, queue, count, model, geometry, frame, lists)
    for i in range(1, count):
        q = queue[i]
        u, v, w = scaled_offset(p, q, geometry, inv_r, frame)
        if not (u * u + v * v > tiny2):
            continue  # no direction
        used += 1
        sums = add_height(sums, u, v, w)
        bb += w * w
        row = height_row(u, v)
        heights = add_row_sums(errors, heights, row)
        state = model_height(state, q, row, u, v, inv_r, model, lists)
        a, b, c = normal_in_frame(q, geometry, frame)
        if not (c > MIN_NORMAL_Z) or not (math.isfinite(a) and math.isfinite(b)):
            continue
        sums = add_slopes(sums, u, v, -a / c, -b / c)
        bb += (a * a + b * b) / (c * c)
        sloped += 1
        ru, rv = slope_rows(u, v)
        u_slopes = add_row_sums(errors, u_slopes, ru)
        v_slopes = add_row_sums(errors, v_slopes, rv)
        state = model_slopes(state, q, ru, rv, model, geometry, frame, lists)
    _normal_equations(0.0, sums, sums, ata, vec)
    singular, factored = _solve(ata, vec)
    shape = shape_operator(vec[1, 0], vec[1, 1], vec[1, 2], inv_r)
    finish_fit(p, shape, singular, used, frame, out)
    height_slope_parts(p, errors, (ata, vec, grads, shape, bb, inv_r, singular, factored),
                       (heights, u_slopes, v_slopes, used, sloped), model, state, lists)
    return t, (ata, vec, grads), lists


@jit
def _an_thread(fit, t):
    """Thread slice t's scratch of :func:`_an_at`."""
    return t, (np.empty((UNKNOWNS + 1, UNKNOWNS)), np.empty((2, UNKNOWNS)), np.empty((7, UNKNOWNS))), new_lists(UNKNOWNS)


@jit
def _an_levels_at(fit, p, walk, geometry, out, errors, walker, thread):
    """an at vertex p at every level of ``walk`` in one walk.

    A level of radius r fits in coordinates divided by r (:func:`_an_at`); written in coordinates
    divided by the widest radius R instead, its height equations are the same ones multiplied by
    ``t = R / r`` and its slope equations the same, with the unknowns rescaled by a diagonal
    (``t`` on the quadratic terms, ``t²`` on the cubic ones). So the height and slope equations are
    summed apart in R's coordinates (two :data:`AN_SUMS` tuples), level by level, and each level
    solves ``(t² H + S) y = t² h + s``: the Jacobi-scaled solve does not depend on the diagonal, and
    the second derivatives come back as ``-y / R``. Rows short enough for a wider level to drop: as
    in :func:`curv.estimators._three_unknowns.levels_at`. ``thread``: ``(ata (8, 7), vec (2, 7))``."""
    ata, vec = thread
    frame, _, ok = start_levels(p, walk, geometry, out)
    if not ok:
        return
    levels = walk.radii.shape[0]
    widest = walk.radii[levels - 1, p]
    inv_w = 1.0 / widest
    band2 = MIN_TANGENT_LENGTH ** 2
    queue = walker[1]
    state = (start_ball_support(p, walker[0], queue), 0, 0)
    used, done, banded = 0, 1, True  # banded: clears the sums below
    heights = slopes = NO_SUMS
    for level in range(levels):
        state = walk_level(p, level, walk, geometry, walker, state)
        if banded:
            heights, slopes, used, done, banded = NO_SUMS, NO_SUMS, 0, 1, False
        r = walk.radii[level, p]
        tiny2 = (MIN_TANGENT_LENGTH * r * inv_w) ** 2
        for i in range(done, state[0]):
            q = queue[i]
            u, v, w = scaled_offset(p, q, geometry, inv_w, frame)
            l2 = u * u + v * v
            if not (l2 > tiny2):
                continue
            banded = banded or not (l2 > band2)
            used += 1
            heights = add_height(heights, u, v, w)
            a, b, c = normal_in_frame(q, geometry, frame)
            if not (c > MIN_NORMAL_Z) or not (math.isfinite(a) and math.isfinite(b)):
                continue
            slopes = add_slopes(slopes, u, v, -a / c, -b / c)
        done = state[0]
        t = widest / r
        _normal_equations(t * t, heights, slopes, ata, vec)
        singular, _ = _solve(ata, vec)
        finish_fit(p, shape_operator(vec[1, 0], vec[1, 1], vec[1, 2], inv_w), singular, used, frame,
                   level_rows(out, level))


@jit
def _an_level_thread(fit, t):
    """Thread slice t's scratch of :func:`_an_levels_at`."""
    return np.empty((UNKNOWNS + 1, UNKNOWNS)), np.empty((2, UNKNOWNS))


AnFit = namedtuple("AnFit", [])
AN = AnFit()
"""an's marker for the fit kernels (:mod:`curv.estimators._fit_driver`)."""
register_fit(AnFit, FitFunctions(_an_at, _an_thread, _an_levels_at, _an_level_thread))


def iter_an(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, noise_model: str = DEFAULT_NOISE_MODEL,
            standard_errors: bool = False):
    """Adjacent-normal cubic fit over each vertex's support (7 unknowns, 3 equations per neighbour)
    (:func:`~curv.estimators._fit_driver.run_fit`).

    ``noise_model`` (:data:`~curv.uncertainty.noise_models.NOISE_MODELS`) says how the standard errors
    take the errors of the neighbours' normals; the curvatures do not depend on it."""
    return (yield from run_fit(mesh, normals, radii, AN, chunk=chunk, centres=centres, features=features,
                               noise_model=checked_noise_model(noise_model), standard_errors=standard_errors))


register(fit_spec(name="an", title="Adjacent-normal cubic approximation", ranges=(2, 3, 4), function=iter_an,
                  uses_normals=True, reference=GOLDFEATHER_INTERRANTE, options={"noise_model": NOISE_MODELS},
                  summary="cubic height fit using positions and the neighbours' normals (7 unknowns)",
                  extra_bytes_per_unit=SE_PARTS_BYTES + SLOT_BYTES))
