"""A vertex's row of an estimate from its shape operator: the principal curvatures and directions,
and the reason code of a fit.

An estimate's rows travel as one :class:`Rows` bundle: ``k1, k2`` (n,), ``d1, d2`` (n, 3),
``reason`` (n,) uint8 (for several ranges at once, (levels, n) and (levels, n, 3): :func:`level_rows`
gives one level's).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..core.jit import jit
from ..core.validity import DEGENERATE, OK, SINGULAR, TOO_FEW
from ..core.small_linalg import sym2_eigen

__all__ = ["Rows", "new_rows", "level_rows", "MIN_PAIRS", "store_principal", "finish_fit", "mark_degenerate"]

Rows = namedtuple("Rows", ["k1", "k2", "d1", "d2", "reason"])
"""An estimate's rows (module notes)."""

MIN_PAIRS = 3
"""Fewer usable neighbours than this make the vertex ``TOO_FEW_NEIGHBOURS`` (the fits have 3
curvature unknowns)."""


def new_rows(n: int, levels: int | None = None) -> Rows:
    """Unset :class:`Rows` of n vertices (at each of ``levels`` ranges when given)."""
    lead = () if levels is None else (levels,)
    return Rows(np.empty(lead + (n,)), np.empty(lead + (n,)), np.empty(lead + (n, 3)), np.empty(lead + (n, 3)),
                np.empty(lead + (n,), np.uint8))


@jit
def level_rows(out, level):
    """The :class:`Rows` of one level of ``(levels, n)`` rows."""
    return Rows(out.k1[level], out.k2[level], out.d1[level], out.d2[level], out.reason[level])


@jit
def store_principal(p, w, frame, k1, k2, d1, d2):
    """Eigen-decompose the shape operator ``W = [[e, f], [f, g]]`` (``w = (e, f, g)``) written in the
    tangent basis (U, V) (the first six entries of ``frame``: ux, uy, uz, vx, vy, vz) and write row p
    of ``k1, k2`` (n,) and ``d1, d2`` (n, 3).

    k1 >= k2 (:func:`~curv.core.small_linalg.sym2_eigen`); ``d1 = c U + s V``,
    ``d2 = -s U + c V`` = N x d1.
    """
    e, f, g = w
    ux, uy, uz, vx, vy, vz = frame[0], frame[1], frame[2], frame[3], frame[4], frame[5]
    k1[p], k2[p], c, s = sym2_eigen(e, f, g)
    d1[p, 0] = c * ux + s * vx
    d1[p, 1] = c * uy + s * vy
    d1[p, 2] = c * uz + s * vz
    d2[p, 0] = -s * ux + c * vx
    d2[p, 1] = -s * uy + c * vy
    d2[p, 2] = -s * uz + c * vz


@jit
def finish_fit(p, w, singular, used, frame, out):
    """Write vertex p's row of ``out`` (:class:`Rows`) from its fitted shape operator ``w = (e, f, g)``.

    ``used`` is the number of usable neighbours. The fit's own codes: TOO_FEW_NEIGHBOURS before
    SINGULAR (too few rows decide no system), else OK. They stand where
    :func:`curv.core.validity.precedence` puts SINGULAR: the input's flags (non-manifold,
    degenerate, border) then mark only the rows left OK (:func:`curv.estimate_finish.finish`).
    """
    store_principal(p, w, frame, out.k1, out.k2, out.d1, out.d2)
    if used < MIN_PAIRS:
        out.reason[p] = TOO_FEW
    elif singular or not math.isfinite(out.k1[p]):
        out.reason[p] = SINGULAR
    else:
        out.reason[p] = OK


@jit
def mark_degenerate(p, out):
    """Vertex p has no usable normal, so no frame to fit in: a NaN row, ``DEGENERATE``."""
    out.k1[p] = math.nan
    out.k2[p] = math.nan
    out.d1[p, :] = math.nan
    out.d2[p, :] = math.nan
    out.reason[p] = DEGENERATE
