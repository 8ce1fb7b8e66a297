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

On a point cloud whose jet normals were fitted over the same balls (the normals' range,
:mod:`curv.point_normals`), the normals' pass also fits qs there, in the frame of the point's
fitted normal, on the support it holds (:func:`_keep_fit`), and the estimate without standard
errors finishes from that fit (:mod:`curv.estimators._handover`): no second search, no second fit.
The estimate's normal is the fitted one oriented, so either that normal or its opposite. Turned
over (N -> -N), the frame's U = N x axis turns over and V = N x U stays
(:func:`~curv.estimators._frames.tangent_frame`), so an offset's u and w change sign and v does
not; the rows ``(u²/2, uv, v²/2)`` become ``(u²/2, -uv, v²/2)`` and the heights -w: the normal
equations are ``S AᵀA S`` and ``-S Aᵀb`` with ``S = diag(1, -1, 1)``, whose solution is
``(-A, B, -C)``, to the bit (every product and sum only changes sign, and Cramer's rule,
:func:`~curv.core.small_linalg.solve_sym3`, gives the same determinant and verdict).
:func:`_handed_fit` turns the kept fit so and finishes as :func:`fit_at` does; a normal that is
neither the kept one nor its opposite is fitted again.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

import math

from ..core.jit import jit, jit_inlined, rescaled
from ..core.mesh import Mesh
from ..core.result import Principal
from ..core.validity import OK, SINGULAR, TOO_FEW
from ..geometry.neighbourhood import all_centres
from ..uncertainty.propagation import three_unknown_parts
from ._fit_driver import fit_spec, run_fit
from ._frames import MIN_TANGENT_LENGTH, tangent_frame
from ._handover import Handover, NormalFits, iter_handed, kept_fits, register_handover
from ._principal import MIN_PAIRS, finish_fit, mark_degenerate, new_rows
from ._three_unknowns import (GOLDFEATHER_INTERRANTE, Equations, fit_in_frame, normal_matrix, register_three_unknowns,
                              residual, row_sums)
from .registry import register

__all__ = ["iter_qs", "height_equation", "shape_operator", "QS", "QS_FITS", "QsFits"]


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


QsFits = namedtuple("QsFits", ["radii", "state", "rows"])
"""The qs fits a normals' pass keeps (module notes): the radius of every point's ball (n,), the
states (n,) uint8 (:data:`NO_FIT`, or the fit's verdict: ``TOO_FEW_NEIGHBOURS``, ``SINGULAR``,
``OK``) and the rows (n, 6): the fitted normal the fit's frame was built on, then (A, B, C)."""

Positions = namedtuple("Positions", ["x", "y", "z"])
"""Coordinate columns as :func:`~curv.estimators._frames.offset_in_frame` reads them."""

NO_FIT = np.uint8(250)
"""State of a point the pass did not fit (no fitted normal)."""


def new_qs_fits(radii: np.ndarray) -> QsFits:
    """An unfilled :class:`QsFits` for a pass over balls of these radii (n,)."""
    n = radii.shape[0]
    return QsFits(np.asarray(radii, np.float64), np.empty(n, np.uint8), np.empty((n, 6)))


QS_FITS = NormalFits(("qs",), new_qs_fits, 8 * 6 + 1 + 8)
"""qs's fits as the normals' pass keeps them: the bundle's rows, state and radius per point."""


@jit
def _frame_of(n0, n1, n2):
    """The frame :func:`~curv.estimators._frames.normal_frame` builds on the normal (n0, n1, n2)."""
    ux, uy, uz, vx, vy, vz = tangent_frame(n0, n1, n2)
    return ux, uy, uz, vx, vy, vz, n0, n1, n2


@jit
def _keep_fit(fits, p, i, fit, support, coords, fitted):
    """qs at point p in the frame of its fitted normal ``fitted[p]``, over the jet fit's support
    (:class:`~curv.estimators._handover.Handover`'s ``keep``): row p of ``fits``."""
    n0, n1, n2 = fitted[p, 0], fitted[p, 1], fitted[p, 2]
    if not (fit[0] == OK and math.isfinite(n0) and math.isfinite(n1) and math.isfinite(n2)):
        fits.state[p] = NO_FIT
        return
    sub, count = support
    x0, x1, x2, singular, used = fit_in_frame(QsFit(), i, sub, count, Positions(coords[0], coords[1], coords[2]),
                                              _frame_of(n0, n1, n2), (MIN_TANGENT_LENGTH * fits.radii[p]) ** 2)
    # finish_fit's verdicts before its finite test: too few rows, then a singular system
    fits.state[p] = TOO_FEW if used < MIN_PAIRS else (SINGULAR if singular else OK)
    row = fits.rows[p]
    row[0], row[1], row[2], row[3], row[4], row[5] = n0, n1, n2, x0, x1, x2


@jit
def _same_bits(a, b):
    """``a`` and ``b`` are the same float, sign of zero included."""
    return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)


@jit
def _handed_fit(fits, p, normals, scratch, out):
    """Row p of ``out`` as :func:`fit_at` with the normal ``normals[p]`` writes it, from the kept fit
    (module notes); False (nothing written) where only a fit can tell. Not inlined: the reason is
    written here (as :func:`curv.estimators._jet_handover.handed_fit` notes)."""
    n0, n1, n2 = normals[p, 0], normals[p, 1], normals[p, 2]
    if not (math.isfinite(n0) and math.isfinite(n1) and math.isfinite(n2)):
        mark_degenerate(p, out)  # no frame: fit_at's first verdict, whatever the support
        return True
    state = fits.state[p]
    if state == NO_FIT:
        return False
    row = fits.rows[p]
    if _same_bits(n0, row[0]) and _same_bits(n1, row[1]) and _same_bits(n2, row[2]):
        x0, x2 = row[3], row[5]
    elif _same_bits(n0, -row[0]) and _same_bits(n1, -row[1]) and _same_bits(n2, -row[2]):
        x0, x2 = -row[3], -row[5]  # the frame turned over: (-A, B, -C)
    else:
        return False
    finish_fit(p, shape_operator(x0, row[4], x2), state == SINGULAR, 0 if state == TOO_FEW else MIN_PAIRS,
               _frame_of(n0, n1, n2), out)
    return True


@jit
def _no_scratch(fits):
    return 0


register_handover(QsFits, Handover(_keep_fit, _handed_fit, _no_scratch))


def iter_qs(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, *, chunk: int | None = None,
            centres: np.ndarray | None = None, features=None, standard_errors: bool = False):
    """Quadratic height fit over each vertex's support (3 unknowns, 1 equation per neighbour)
    (:func:`~curv.estimators._fit_driver.run_fit`); on a point cloud whose normals' pass kept qs's
    fits at these radii, read from them where they answer (module notes)."""
    fits = None
    if np.ndim(radii) == 1 and features is None and not standard_errors:
        fits = kept_fits(mesh, QS_FITS.options)
    if fits is None:
        return (yield from run_fit(mesh, normals, radii, QS, chunk=chunk, centres=centres, features=features,
                                   standard_errors=standard_errors))
    out = new_rows(mesh.n_vertices)
    rest = yield from rescaled(iter_handed(fits, normals, radii, all_centres(mesh.n_vertices, centres), out,
                                           chunk=chunk), 0.0, 0.2)
    if rest.size:
        fitted = yield from rescaled(run_fit(mesh, normals, radii, QS, chunk=chunk, centres=rest), 0.2, 1.0)
        for name in out._fields:
            getattr(out, name)[rest] = getattr(fitted, name)[rest]
    return Principal(k1=out.k1, k2=out.k2, d1=out.d1, d2=out.d2, reason=out.reason)


register(fit_spec(name="qs", title="Quadratic surface approximation", ranges=(1, 2, 3, 4), function=iter_qs,
                  uses_normals=False, reference=GOLDFEATHER_INTERRANTE,
                  reads_normal_fits=lambda options, standard_errors: None if standard_errors else QS_FITS,
                  extra_bytes_per_point=QS_FITS.bytes_per_point,
                  summary="least-squares height fit A/2 u^2 + B uv + C/2 v^2 in the tangent frame"))
