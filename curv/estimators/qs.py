"""Quadratic surface approximation (Goldfeather & Interrante 2004; paper §4.1, any range).

At vertex p with normal N and tangent frame (U, V), write every neighbour q of the support (the
vertices within the ball of range Rk) as the offset ``q - p = u U + v V + w N``. The surface near p
is the height field over its tangent plane

    w = A/2 u² + B uv + C/2 v²,

one equation per neighbour in the unknowns (A, B, C) (:func:`height_equation`), solved by least
squares. The height's Hessian is [[A, B], [B, C]], and with the house sign (the derivative of the
unit normal along a tangent t is ``dN = W t``) the shape operator is

    W = -[[A, B], [B, C]]

(:func:`shape_operator`), whose eigenpairs are the principal curvatures and directions (an outward
sphere of radius r gives k1 = k2 = +1/r). The flow (support -> frame -> rows -> 3x3 solve -> W ->
principal curvatures) is nc's too: :mod:`curv.estimators._three_unknowns`.

Works on any polygon mesh, on borders (one-sided there; the API marks the border vertices
themselves) and on point clouds. Standard errors (``standard_errors=True``): p's own height error
enters every equation, and the noise level is read with the frame's tilt as two more unknowns: a
tilt adds the linear term ``u, v`` to w (:func:`curv.uncertainty.propagation.three_unknown_parts`).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..core.jit import jit, jit_inlined
from ..core.mesh import Mesh
from ..uncertainty.propagation import three_unknown_parts
from ._fit_driver import fit_spec, run_fit
from ._three_unknowns import (GOLDFEATHER_INTERRANTE, Equations, normal_matrix, register_three_unknowns, residual,
                              row_sums)
from .registry import register

__all__ = ["iter_qs", "height_equation", "shape_operator", "QS"]


@jit_inlined
def height_equation(u, v, w, l2):
    """``A/2 u² + B uv + C/2 v² = w``: the row ``(u²/2, uv, v²/2)``, the height w, and the frame
    tilt's columns ``(u, v)``."""
    return (0.5 * u * u, u * v, 0.5 * v * v), w, u, v


@jit_inlined
def shape_operator(a, b, c):
    """``W = -[[A, B], [B, C]]`` as ``(e, f, g)``."""
    return -a, -b, -c


@jit
def _parts(p, errors, fit, tilt, offsets):
    """p's own height error is shared by every equation (``row_sums``), the noise level read with
    the frame's tilt."""
    sums, x, shape, used = fit
    three_unknown_parts(p, errors, normal_matrix(sums), residual(sums, x, used), row_sums(sums, used), shape, x,
                        tilt)


QsFit = namedtuple("QsFit", [])
QS = QsFit()
"""qs's marker for the fit kernels (:mod:`curv.estimators._fit_driver`)."""
register_three_unknowns(QsFit, Equations(height_equation, shape_operator, _parts))


def iter_qs(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, standard_errors: bool = False):
    """Quadratic height fit over each vertex's support (3 unknowns, 1 equation per neighbour)
    (:func:`~curv.estimators._fit_driver.run_fit`)."""
    return (yield from run_fit(mesh, normals, radii, QS, chunk=chunk, centres=centres, features=features,
                               standard_errors=standard_errors))


register(fit_spec(name="qs", title="Quadratic surface approximation", ranges=(1, 2, 3, 4), function=iter_qs,
                  uses_normals=False, reference=GOLDFEATHER_INTERRANTE,
                  summary="least-squares height fit A/2 u^2 + B uv + C/2 v^2 in the tangent frame"))
