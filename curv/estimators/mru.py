"""Modified Rusinkiewicz (paper §4.2): per-vertex least squares of normal differences.

At vertex p with normal N_p and tangent frame (U, V), write every neighbour q of the support (the
vertices within (k - 1) longest 1-ring edges at Rk) as the tangent offset (u, v) of ``q - p`` and the
tangent part (a, b) of its normal N_q. The shape operator W = [[e, f], [f, g]] maps a tangent offset
to the change of the normal along it (house sign, ``dN = W t``), so each neighbour gives two equations
(eq. 4.1/4.2)

    [u  v  0] (e f g)ᵀ = a,
    [0  u  v] (e f g)ᵀ = b,

solved by least squares for W directly; N_p is orthogonal to its own frame's U and V, so only N_q
enters (a, b). The eigenpairs of W are the principal curvatures and directions (an outward sphere of
radius r gives k1 = k2 = +1/r). The module reads support -> frame -> rows (:func:`normal_difference_rows`,
summed by :func:`add_pair`) -> 3x3 solve -> W -> principal curvatures (:func:`_mru_at`).

No per-face step, so it works on any polygon mesh, on borders and on point clouds. Standard errors
(``standard_errors=True``): :func:`curv.uncertainty.factored.normal_difference_parts`, with the model
of the normals' errors of ``noise_model`` (:mod:`curv.uncertainty.noise_models`).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..core.jit import jit, jit_inlined
from ..core.mesh import Mesh
from ..core.small_linalg import solve_sym3
from ..uncertainty.factored import normal_difference_parts
from ..uncertainty.noise_models import DEFAULT_NOISE_MODEL, NOISE_MODELS, checked_noise_model
from ..uncertainty.normals_model import SLOT_BYTES, model_slopes, model_start, new_lists
from ..uncertainty.parts import SE_PARTS_BYTES, clear_parts
from ._fit_driver import FitFunctions, LevelSums, fit_spec, register_fit, register_level_sums, run_fit
from ._frames import MIN_TANGENT_LENGTH, normal_frame, normal_in_frame, offset_in_frame
from ._principal import finish_fit, mark_degenerate
from .registry import register

__all__ = ["iter_mru", "normal_difference_rows", "add_pair", "solve_pairs", "MRU"]

NO_SUMS = (0.0,) * 12
"""The sums of :func:`add_pair` before any neighbour."""


@jit
def _neighbour(p, q, geometry, frame, tiny2):
    """q's tangent offset (u, v) in p's frame and the tangent part (a, b) of its normal; ``ok`` when
    the offset carries a direction (:data:`~curv.estimators._frames.MIN_TANGENT_LENGTH`) and the
    normal is finite. Returns ``(u, v, a, b, ok)``."""
    u, v, _ = offset_in_frame(p, q, geometry, frame)
    a, b, _ = normal_in_frame(q, geometry, frame)
    return u, v, a, b, u * u + v * v > tiny2 and math.isfinite(a) and math.isfinite(b)


@jit_inlined
def normal_difference_rows(u, v):
    """The rows of eq. 4.1/4.2 in (e, f, g): ``(u, v, 0)`` (= a) and ``(0, u, v)`` (= b)."""
    return (u, v, 0.0), (0.0, u, v)


@jit_inlined
def add_pair(s, u, v, a, b):
    """The sums ``s`` with one neighbour's two equations added: ``Σ uu, uv, vv`` (the normal matrix
    ``[[uu, uv, 0], [uv, uu + vv, uv], [0, uv, vv]]``), ``Σ au, av, bu, bv`` (its right-hand side
    ``(au, av + bu, bv)``), and for the standard errors ``Σ a² + b², u, v, a, b``."""
    return (s[0] + u * u, s[1] + u * v, s[2] + v * v, s[3] + a * u, s[4] + a * v, s[5] + b * u, s[6] + b * v,
            s[7] + (a * a + b * b), s[8] + u, s[9] + v, s[10] + a, s[11] + b)


@jit
def solve_pairs(s):
    """W's ``(e, f, g, singular)`` from :func:`add_pair`'s sums
    (:func:`~curv.core.small_linalg.solve_sym3`)."""
    return solve_sym3(s[0], s[1], 0.0, s[0] + s[2], s[1], s[2], s[3], s[4] + s[5], s[6])


@jit
def _mru_at(fit, p, queue, count, r, geometry, out, errors, noise, thread):
    """Normal-difference least squares at vertex p over its support ``queue[1:count]`` (ball radius r).

    ``noise = (model, mesh)`` (:mod:`curv.estimators._fit_driver`) serves the standard errors: the
    normals' model (:mod:`curv.uncertainty.normals_model`) and whether the normals share a mesh's
    faces (None on a point cloud); ``thread = (t, (factor, grads), lists)`` the slice's index, the
    standard errors' scratch and the model's short lists. Returns ``thread`` (its lists grown,
    perhaps)."""
    t, scratch, lists = thread
    clear_parts(p, errors)
    frame, ok = normal_frame(p, geometry)
    if not ok:
        mark_degenerate(p, out)
        return thread
    model, mesh = noise
    tiny2 = (MIN_TANGENT_LENGTH * r) ** 2
    sums, used = NO_SUMS, 0
    state, lists = model_start(p, t, queue, count, model, geometry, frame, lists)
    for i in range(1, count):
        q = queue[i]
        u, v, a, b, usable = _neighbour(p, q, geometry, frame, tiny2)
        if not usable:
            continue
        used += 1
        sums = add_pair(sums, u, v, a, b)
        ru, rv = normal_difference_rows(u, v)
        state = model_slopes(state, q, ru, rv, model, geometry, frame, lists)
    e, f, g, singular = solve_pairs(sums)
    finish_fit(p, (e, f, g), singular, used, frame, out)
    normal_difference_parts(p, errors, (sums, (e, f, g), used, singular), mesh, model, state, lists, scratch)
    return t, scratch, lists


@jit
def _mru_thread(fit, t):
    """Thread slice t's scratch of :func:`_mru_at`."""
    return t, (np.empty((4, 3)), np.empty((7, 3))), new_lists(3)


@jit
def _no_sums(fit):
    return NO_SUMS


@jit
def _level_add(fit, sums, p, q, geometry, frame, tiny2):
    """q's two equations added to ``sums`` when usable (several ranges in one walk,
    :func:`~curv.estimators._fit_driver.sums_levels_at`)."""
    u, v, a, b, usable = _neighbour(p, q, geometry, frame, tiny2)
    if not usable:
        return sums, 0.0, False
    return add_pair(sums, u, v, a, b), u * u + v * v, True


@jit
def _level_solve(fit, sums):
    """W and whether the system is singular."""
    e, f, g, singular = solve_pairs(sums)
    return (e, f, g), singular


MruFit = namedtuple("MruFit", [])
MRU = MruFit()
"""mru's marker for the fit kernels (:mod:`curv.estimators._fit_driver`)."""
register_fit(MruFit, FitFunctions(_mru_at, _mru_thread,
                                  *register_level_sums(MruFit, LevelSums(_no_sums, _level_add, _level_solve))))


def iter_mru(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
             centres: np.ndarray | None = None, features=None, noise_model: str = DEFAULT_NOISE_MODEL,
             standard_errors: bool = False):
    """Normal-difference least squares over each vertex's support (within (k-1) longest 1-ring edges
    at Rk) (:func:`~curv.estimators._fit_driver.run_fit`).

    ``noise_model`` (:data:`~curv.uncertainty.noise_models.NOISE_MODELS`) says how the standard errors
    take the errors of the neighbours' normals; the curvatures do not depend on it."""
    return (yield from run_fit(mesh, normals, radii, MRU, chunk=chunk, centres=centres, features=features,
                               noise_model=checked_noise_model(noise_model), standard_errors=standard_errors))


register(fit_spec(name="mru", title="Modified Rusinkiewicz", ranges=(2, 3, 4), function=iter_mru, uses_normals=True,
                  reference="Multivariate analysis of curvature estimators, §4.2 (after Rusinkiewicz 2004)",
                  summary="per-vertex least squares of neighbour normal differences (eq. 4.1/4.2)",
                  options={"noise_model": NOISE_MODELS}, extra_bytes_per_unit=SE_PARTS_BYTES + SLOT_BYTES))
