"""Normal curvature approximation (Goldfeather & Interrante 2004; paper §4.1, any range).

At vertex p with normal N and tangent frame (U, V), write every neighbour q of the support (the
vertices within the ball of range Rk) as the offset ``q - p = u U + v V + w N``. The circle through
p and q tangent to p's plane has the normal curvature

    κ_n = 2 (p - q) · N / |p - q|²

(:func:`normal_curvature`), which is the second fundamental form in the unit tangent direction
``t = (u, v) / |(u, v)|``:

    e t_u² + 2 f t_u t_v + g t_v² = κ_n,

one equation per neighbour (:func:`tangent_row`) in the entries of the shape operator
W = [[e, f], [f, g]] itself, solved by least squares; its eigenpairs are the principal curvatures and
directions (an outward sphere of radius r gives k1 = k2 = +1/r). The flow (support -> frame -> rows
-> 3x3 solve -> W -> principal curvatures) is qs's too: :mod:`curv.estimators._three_unknowns`.

Works on any polygon mesh, on borders (one-sided there; the API marks the border vertices
themselves) and on point clouds. Standard errors (``standard_errors=True``): an equation's error is
``2 / |(u, v)|²`` times its two heights' errors, and the noise level is read with the frame's tilt as
two more unknowns: a tilt adds ``(u, v) / |(u, v)|²`` times its slopes to κ_n
(:func:`curv.uncertainty.propagation.normal_curvature_parts`).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..core.jit import jit, jit_inlined
from ..core.mesh import Mesh
from ..uncertainty.propagation import normal_curvature_parts
from ._fit_driver import fit_spec, run_fit
from ._three_unknowns import GOLDFEATHER_INTERRANTE, Equations, normal_matrix, register_three_unknowns, residual
from .registry import register

__all__ = ["iter_nc", "normal_curvature", "tangent_row", "NC"]


@jit_inlined
def normal_curvature(w, l2):
    """``κ_n = 2 (p - q) · N / |p - q|²`` of a neighbour at offset (u, v, w), ``l2 = u² + v²``."""
    return -2.0 * w / (l2 + w * w)


@jit_inlined
def tangent_row(u, v, l2):
    """The row ``(t_u², 2 t_u t_v, t_v²)`` of the unit tangent ``t = (u, v) / |(u, v)|`` (``l2 = u² + v²``)."""
    return u * u / l2, 2.0 * u * v / l2, v * v / l2


@jit_inlined
def _equation(u, v, w, l2):
    """``e t_u² + 2 f t_u t_v + g t_v² = κ_n``, and the frame tilt's columns ``(u, v) / l²``."""
    return tangent_row(u, v, l2), normal_curvature(w, l2), u / l2, v / l2


@jit_inlined
def _shape_operator(e, f, g):
    """The unknowns are W's entries."""
    return e, f, g


@jit
def _parts(p, errors, fit, tilt, offsets):
    """Each equation's error is its heights' difference times ``2 / l²`` (docs/UNCERTAINTY.md)."""
    sums, x, shape, used = fit
    normal_curvature_parts(p, errors, normal_matrix(sums), residual(sums, x, used), shape, tilt, offsets)


NcFit = namedtuple("NcFit", [])
NC = NcFit()
"""nc's marker for the fit kernels (:mod:`curv.estimators._fit_driver`)."""
register_three_unknowns(NcFit, Equations(_equation, _shape_operator, _parts))


def iter_nc(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, standard_errors: bool = False):
    """Normal-curvature least squares over each vertex's support (3 unknowns, 1 equation per
    neighbour) (:func:`~curv.estimators._fit_driver.run_fit`)."""
    return (yield from run_fit(mesh, normals, radii, NC, chunk=chunk, centres=centres, features=features,
                               standard_errors=standard_errors))


register(fit_spec(name="nc", title="Normal curvature approximation", ranges=(1, 2, 3, 4), function=iter_nc,
                  uses_normals=False, reference=GOLDFEATHER_INTERRANTE,
                  summary="least squares of edge normal curvatures 2 (p-q).N/|p-q|^2"))
