"""What a fit leaves for its standard errors: one row of parts per vertex, finished by the pooling.

A fit computed with standard errors gets an :class:`Errors` bundle (a fit without them gets None,
and numba compiles it without any of this). Its kernel writes, per vertex, the propagation of the
noise through the fit and the eigen step per unit noise variance (in ``k1_se``, ``k2_se``) and the
parts the noise level is read from (:func:`store_parts`); :mod:`curv.uncertainty.pooling` then
reads the noise level over each vertex and its edge neighbours and turns both into the standard
errors.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..core.filled import filled
from ..core.jit import jit

__all__ = ["Errors", "new_errors", "SE_PARTS_BYTES", "clear_parts", "store_parts", "keep_alone"]

Errors = namedtuple("Errors", ["k1_se", "k2_se", "parts", "alone"])
"""A fit's standard errors in the making.

- ``k1_se``, ``k2_se`` (n,) float64: ``var(k_i) / sigma²``, the standard errors once pooled;
- ``parts`` (n, 4) float64: ``(RSS, spare equations, var_deviator / sigma², rad)``, the residual sum
  of squares, the (effective) number of spare equations it is spread over (0 when there is none),
  and what the eigen step's bias needs (:func:`curv.uncertainty.propagation.rad_bias`);
- ``alone`` (n,) bool: the vertex's noise level is in other units than its neighbours' (an and mru
  with independent equations: a noise level of normals, not of heights), so it is not pooled.
"""

SE_PARTS_BYTES = 16.5
"""The standard errors' parts (4 float64 and a bool per vertex) per size unit (vertices + faces / 2,
about 2 vertices on a triangle mesh)."""


def new_errors(n: int, *, most_written: bool) -> Errors:
    """:class:`Errors` of n vertices, NaN until written (:func:`curv.core.filled.filled`: a region
    pays for its rows, ``most_written`` a whole mesh)."""
    return Errors(filled(n, np.nan, most_written=most_written), filled(n, np.nan, most_written=most_written),
                  filled((n, 4), np.nan, most_written=most_written),
                  filled(n, False, np.bool_, most_written=most_written))


@jit
def clear_parts(p, errors):
    """Row p before a fit: no residual to pool. Nothing without ``errors`` (None)."""
    if errors is None:
        return
    errors.parts[p, 0] = math.nan
    errors.parts[p, 1] = 0.0
    errors.parts[p, 2] = 0.0
    errors.parts[p, 3] = 0.0
    errors.alone[p] = False


@jit
def store_parts(p, errors, var1, var2, rss, dof, var_deviator, rad):
    """Write vertex p's row of ``errors`` (:class:`Errors`): ``var(k_i) / sigma²``, the residual sum
    of squares ``rss`` over ``dof`` spare equations (0 when ``dof`` is not positive), the deviator's
    variance per unit noise variance and its length ``rad``."""
    errors.k1_se[p] = var1
    errors.k2_se[p] = var2
    errors.parts[p, 0] = rss
    errors.parts[p, 1] = dof if dof > 0.0 else 0.0
    errors.parts[p, 2] = var_deviator
    errors.parts[p, 3] = rad


@jit
def keep_alone(p, errors):
    """Vertex p's noise level is in other units than its neighbours': pooled with no other's."""
    errors.alone[p] = True
