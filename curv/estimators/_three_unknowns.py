"""Fits of three unknowns with one equation per neighbour (Goldfeather & Interrante's nc and qs): one
flow, each fit its own equation.

At vertex p the flow reads: support -> frame (p's normal and tangent basis) -> one row per
neighbour q (the fit's ``equation`` of q's offset ``(u, v, w)`` in that frame) -> the 3x3 normal
equations solved by Cramer's rule -> the fit's ``shape_operator`` of the solution -> the principal
curvatures (:func:`fit_at`). A fit registers its equation, shape operator and standard errors for
its marker (:func:`register_three_unknowns`); numba compiles the flow once per fit.

The normal equations travel as a 13-tuple of sums, carried in registers by the loop over the
support: ``(a00, a01, a02, a11, a12, a22, b0, b1, b2, bb, s0, s1, s2)``, the upper triangle of
``AᵀA``, ``Aᵀb``, ``bᵀb`` and the row sums ``Σ a`` (what the standard errors read).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba.extending import overload

from ..core.jit import JIT_OPTIONS, jit, jit_inlined
from ..core.small_linalg import solve_sym3
from ..uncertainty.parts import clear_parts
from ..uncertainty.propagation import NO_TILT, add_tilt, keep_offset, offsets_room
from ._fit_driver import FitFunctions, LevelSums, register_fit, register_level_sums
from ._frames import MIN_TANGENT_LENGTH, normal_frame, offset_in_frame
from ._principal import finish_fit, mark_degenerate

__all__ = ["Equations", "register_three_unknowns", "NO_SUMS", "add_equation", "normal_matrix", "residual",
           "row_sums", "fit_in_frame"]

Equations = namedtuple("Equations", ["equation", "shape_operator", "parts"])
"""A fit of three unknowns (``@jit`` functions):

- ``equation(u, v, w, l2)``: neighbour q's equation from its offset in p's frame (``l2 = u² + v²``):
  ``(row, rhs, lu, lv)``, its 3 coefficients, its right-hand side and the columns of the frame's
  tilt in it (what a tilt t adds to the right-hand side per unit slope);
- ``shape_operator(x0, x1, x2)``: W = (e, f, g) from the solution;
- ``parts(p, errors, fit, tilt, offsets)``: the standard errors' parts
  (:mod:`curv.uncertainty.propagation`) from ``fit = (sums, x, W, equations)``, the frame tilt's
  sums and the tangent offsets ``offsets[:equations]``; nothing without ``errors``."""

_EQUATIONS: dict = {}

GOLDFEATHER_INTERRANTE = ("Goldfeather & Interrante 2004, A novel cubic-order algorithm for approximating principal "
                          "direction vectors")

NO_SUMS = (0.0,) * 13
"""The sums before any equation."""


def register_three_unknowns(marker: type, equations: Equations) -> None:
    """Fit the markers of ``marker`` by this flow with ``equations`` (:func:`~curv.estimators._fit_driver.register_fit`)."""
    _EQUATIONS[marker] = equations
    levels = register_level_sums(marker, LevelSums(_no_sums, _level_add, _level_solve))
    register_fit(marker, FitFunctions(fit_at, offsets_scratch, *levels))


def equation(fit, u, v, w, l2):
    """The fit's ``equation`` (:class:`Equations`), chosen by the type of ``fit`` inside numba code."""
    raise NotImplementedError("called from numba code only")


def shape_operator(fit, x0, x1, x2):
    """The fit's ``shape_operator`` (:class:`Equations`), inside numba code."""
    raise NotImplementedError("called from numba code only")


def fit_parts(fit, p, errors, summary, tilt, offsets):
    """The fit's ``parts`` (:class:`Equations`), inside numba code."""
    raise NotImplementedError("called from numba code only")


@overload(equation, jit_options=JIT_OPTIONS)
def _equation(fit, u, v, w, l2):
    row = _EQUATIONS[fit.instance_class].equation
    return lambda fit, u, v, w, l2: row(u, v, w, l2)


@overload(shape_operator, jit_options=JIT_OPTIONS)
def _shape_operator(fit, x0, x1, x2):
    shape = _EQUATIONS[fit.instance_class].shape_operator
    return lambda fit, x0, x1, x2: shape(x0, x1, x2)


@overload(fit_parts, jit_options=JIT_OPTIONS)
def _fit_parts(fit, p, errors, summary, tilt, offsets):
    parts = _EQUATIONS[fit.instance_class].parts
    return lambda fit, p, errors, summary, tilt, offsets: parts(p, errors, summary, tilt, offsets)


@jit_inlined
def add_equation(sums, row, rhs):
    """``sums`` with the equation ``row · x = rhs`` (``row`` a 3-tuple) added."""
    c0, c1, c2 = row
    return (sums[0] + c0 * c0, sums[1] + c0 * c1, sums[2] + c0 * c2, sums[3] + c1 * c1, sums[4] + c1 * c2,
            sums[5] + c2 * c2, sums[6] + c0 * rhs, sums[7] + c1 * rhs, sums[8] + c2 * rhs, sums[9] + rhs * rhs,
            sums[10] + c0, sums[11] + c1, sums[12] + c2)


@jit
def _solve(sums):
    """The least-squares solution of the equations summed in ``sums`` (Cramer's rule,
    :func:`~curv.core.small_linalg.solve_sym3`). Returns ``(x0, x1, x2, singular)``."""
    return solve_sym3(sums[0], sums[1], sums[2], sums[3], sums[4], sums[5], sums[6], sums[7], sums[8])


@jit
def normal_matrix(sums):
    """``AᵀA``'s upper triangle, a 6-tuple."""
    return sums[0], sums[1], sums[2], sums[3], sums[4], sums[5]


@jit
def residual(sums, x, equations):
    """``(bᵀb, xᵀAᵀb, m)`` of the solution ``x`` (a 3-tuple) over m ``equations``."""
    return sums[9], x[0] * sums[6] + x[1] * sums[7] + x[2] * sums[8], equations


@jit
def row_sums(sums, equations):
    """``(m, Σ a)``: the equations and their row sums, as they share the centre's own error."""
    return equations, sums[10], sums[11], sums[12]


@jit
def fit_at(fit, p, queue, count, r, geometry, out, errors, noise, offsets):
    """The fit at vertex p over its support ``queue[1:count]`` in the ball of radius r: support ->
    frame -> rows -> solve -> W -> principal curvatures. ``offsets`` (rows, 2) keeps the tangent
    offsets for the standard errors (grown, perhaps, and returned); ``noise`` is not read."""
    clear_parts(p, errors)
    frame, ok = normal_frame(p, geometry)
    if not ok:
        mark_degenerate(p, out)
        return offsets
    offsets = offsets_room(errors, offsets, count)
    tiny2 = (MIN_TANGENT_LENGTH * r) ** 2
    sums, tilt, used = NO_SUMS, NO_TILT, 0
    for i in range(1, count):
        u, v, w = offset_in_frame(p, queue[i], geometry, frame)
        l2 = u * u + v * v
        if not (l2 > tiny2):
            continue  # no direction
        keep_offset(errors, offsets, used, u, v)
        used += 1
        row, rhs, lu, lv = equation(fit, u, v, w, l2)
        sums = add_equation(sums, row, rhs)
        tilt = add_tilt(errors, tilt, row, rhs, lu, lv)
    x0, x1, x2, singular = _solve(sums)
    shape = shape_operator(fit, x0, x1, x2)
    finish_fit(p, shape, singular, used, frame, out)
    fit_parts(fit, p, errors, (sums, (x0, x1, x2), shape, used), tilt, offsets)
    return offsets


@jit
def offsets_scratch(fit, t):
    """A thread slice's tangent offsets (grown as a support needs, :func:`fit_at`)."""
    return np.empty((64, 2))


@jit
def _no_sums(fit):
    return NO_SUMS


@jit
def _level_add(fit, sums, p, q, geometry, frame, tiny2):
    """q's equation added to ``sums`` when its offset carries a direction (several ranges in one
    walk, :func:`~curv.estimators._fit_driver.sums_levels_at`)."""
    u, v, w = offset_in_frame(p, q, geometry, frame)
    l2 = u * u + v * v
    if not (l2 > tiny2):
        return sums, l2, False
    row, rhs, _, _ = equation(fit, u, v, w, l2)
    return add_equation(sums, row, rhs), l2, True


@jit
def fit_in_frame(fit, p, queue, count, positions, frame, tiny2):
    """The fit at point p over ``queue[1:count]`` in ``frame`` without standard errors, as
    :func:`fit_at` makes it (the same rows in the same order: the same sums): ``(x0, x1, x2,
    singular, used)``. ``positions``: anything with the coordinate columns ``x, y, z`` that ``p``
    and the queue index (a pass's grid-ordered columns)."""
    sums, used = NO_SUMS, 0
    for j in range(1, count):
        sums, _, usable = _level_add(fit, sums, p, queue[j], positions, frame, tiny2)
        used += usable
    x0, x1, x2, singular = _solve(sums)
    return x0, x1, x2, singular, used


@jit
def _level_solve(fit, sums):
    """W and whether the system is singular."""
    x0, x1, x2, singular = _solve(sums)
    return shape_operator(fit, x0, x1, x2), singular
