"""Standard errors of a fit from its factored normal matrix (an, mru, the jet).

The fit hands over the Jacobi-scaled Cholesky factor of its normal matrix M
(:func:`~curv.core.small_linalg.cholesky_scaled`) and the gradients of what it reports over its
unknowns, one row each (:func:`shape_gradients` fills those of a fit whose first three unknowns are
the shape operator's entries). Whitened by the factor (``L⁻¹ D g``), ``gᵀM⁻¹h`` is a dot product of
two rows (:func:`~curv.core.small_linalg.row_dot`).
"""

from __future__ import annotations

import math

from ..core.jit import jit
from ..core.small_linalg import cholesky_scaled, factor_whiten, row_dot
from .normals_model import model_finish, model_release
from .parts import keep_alone, store_parts
from .propagation import deviator_gradients, principal_gradients, three_unknown_parts

__all__ = ["shape_gradients", "shared_error_parts", "whitened_errors", "add_row_sums", "height_slope_parts",
           "normal_difference_parts"]


@jit
def shape_gradients(grads, w):
    """Rows 0, 1, 5 and 6 of ``grads`` (7, K): the gradients of k1, k2 and of the two components of
    the deviator (:func:`~curv.uncertainty.propagation.deviator_gradients`) of ``w = (e, f, g)``
    over K unknowns whose first three are W's entries (up to a common factor; 0 on the others)."""
    e, f, g = w
    for j in range(grads.shape[1]):
        grads[0, j] = 0.0
        grads[1, j] = 0.0
    grads[0, 0], grads[0, 1], grads[0, 2], grads[1, 0], grads[1, 1], grads[1, 2] = principal_gradients(e, f, g)
    for j in range(grads.shape[1]):
        grads[5, j] = 0.0
        grads[6, j] = 0.0
    grads[5, 0], grads[5, 1], grads[5, 2], grads[6, 0], grads[6, 1], grads[6, 2] = deviator_gradients(e, f, g)


@jit
def shared_error_parts(p, errors, grads, size, equations, shares, rss, rad, scale):
    """Row p of the standard errors' parts of a fit whose equations' errors are independent but for
    a few errors several equations share (an: p's own height in every height equation, the tilt of
    p's normal in every slope equation of each kind), each modelled as one more independent error
    of the same variance on the equations that share it.

    Parameters
    ----------
    p : int
    errors : Errors
    grads : (7, K) float64
        Whitened (:func:`~curv.core.small_linalg.factor_whiten`): rows 0, 1 the gradients of k1 and
        k2 (:func:`shape_gradients`), rows 2-4 the shared errors' columns (the sums of the rows of
        the equations sharing each), rows 5, 6 the deviator's.
    size : int
        The unknowns.
    equations : int
    shares : (int, int, int)
        How many equations share each of the three.
    rss, rad : float
        The residual sum of squares and the length of W's deviator.
    scale : float
        Factor of the variances (to the reported units).

    The noise level is the vertex's own (pooled with no other, :func:`~curv.uncertainty.parts.keep_alone`).
    """
    dof = float(equations - size)
    for k in range(3):
        dof += shares[k]
        dof -= row_dot(grads, 2 + k, 2 + k, size)
    var_dev = 0.0
    for i in range(5, 7):
        var_dev += row_dot(grads, i, i, size)
        for shared in range(2, 5):
            var_dev += row_dot(grads, i, shared, size) ** 2
    var1 = row_dot(grads, 0, 0, size)
    var2 = row_dot(grads, 1, 1, size)
    for shared in range(2, 5):
        var1 += row_dot(grads, 0, shared, size) ** 2
        var2 += row_dot(grads, 1, shared, size) ** 2
    store_parts(p, errors, var1 * scale, var2 * scale, rss, dof, var_dev * scale, rad)
    keep_alone(p, errors)


@jit
def whitened_errors(factor, srow, size, grads, sigma2):
    """The standard errors ``sqrt(sigma² gᵀM⁻¹g)`` of the two quantities whose gradients over the
    unknowns are ``grads[0]`` and ``grads[1]`` (whitened here in place), with independent errors of
    variance ``sigma2``."""
    factor_whiten(factor, srow, size, grads)
    return math.sqrt(sigma2 * row_dot(grads, 0, 0, size)), math.sqrt(sigma2 * row_dot(grads, 1, 1, size))


@jit
def add_row_sums(errors, sums, row):
    """``sums + row`` for 7-tuples: the sum of the rows of the equations that share an error
    (:func:`height_slope_parts`); ``sums`` as it is without ``errors`` (None)."""
    if errors is None:
        return sums
    return (sums[0] + row[0], sums[1] + row[1], sums[2] + row[2], sums[3] + row[3], sums[4] + row[4],
            sums[5] + row[5], sums[6] + row[6])


@jit
def height_slope_parts(p, errors, fit, shares, model, state, lists):
    """Row p of the standard errors' parts of a fit of K unknowns (the first three W's entries times
    ``-r``) from height and slope equations (an), in coordinates divided by the ball radius r.

    With ``model`` (:mod:`curv.uncertainty.normals_model`, fed during the fit: ``state``, ``lists``)
    the equations' errors are those the normals take from noisy heights, whose noise level pools
    with the neighbours'. Without it (a point cloud, the independent model, or a ring without a
    gradient) they are taken as independent but for p's own height, shared by the height equations,
    and the tilt of p's normal, shared by each kind of slope equation (:func:`shared_error_parts`);
    that noise level, of heights and slopes alike, is the vertex's own.

    Parameters
    ----------
    p : int
    errors : Errors or None
        Nothing without (no standard errors asked).
    fit : tuple
        ``(factor, vec, grads, w, bᵀb, 1 / r, singular, factored)``: the normal matrix's factor
        (:func:`~curv.core.small_linalg.cholesky_scaled`, scales in row K), ``vec`` (2, K) its
        right-hand side and solution, ``grads`` (7, K) scratch, W, the squared right-hand sides'
        sum, and whether the solve failed or the factor holds.
    shares : tuple
        ``(Σ height rows, Σ u-slope rows, Σ v-slope rows, heights, sloped neighbours)``
        (:func:`add_row_sums`).
    model, state, lists :
        The normals' model (None: not run) and its state.
    """
    if errors is None:
        return
    factor, vec, grads, w, bb, inv_r, singular, factored = fit
    heights, u_slopes, v_slopes, used, sloped = shares
    size = vec.shape[1]
    xatb = 0.0
    for j in range(size):
        xatb += vec[1, j] * vec[0, j]
    for j in range(size):
        grads[2, j], grads[3, j], grads[4, j] = heights[j], u_slopes[j], v_slopes[j]
    # k_i's gradient over the unknowns: (c², 2cs, s²) on the quadratic terms, 0 on the cubic ones
    shape_gradients(grads, w)
    equations = used + 2 * sloped
    usable = equations > size and factored
    if usable:
        factor_whiten(factor, size, size, grads)
    e, f, g = w
    rad = math.hypot(0.5 * (e - g), f)
    scale = inv_r * inv_r  # the variances in unscaled coordinates
    if _modelled(p, errors, model, state, lists, (factor, grads, inv_r, usable and not singular),
                 (bb - xatb, rad, scale)):
        return
    if usable:
        shared_error_parts(p, errors, grads, size, equations, (used, sloped, sloped), bb - xatb, rad, scale)


@jit
def _modelled(p, errors, model, state, lists, fit, residual):
    """Finish the normals' model (``fit = (factor, grads, 1 / r, usable)``: the fit's factor with its
    scales in row K, and ``grads`` whitened by it) and write row p when it holds; True when it did.
    Without a model, False."""
    if model is None:
        return False
    factor, grads, inv_r, usable = fit
    if not usable:
        model_release(state, model, lists)
        return False
    rss, rad, scale = residual
    var1, var2, var_dev, spare, ok = model_finish(state, factor, grads.shape[1], grads, inv_r, model, lists)
    if ok and spare > 0.0:
        store_parts(p, errors, var1 * scale, var2 * scale, rss, spare, var_dev * scale, rad)
        return True
    return False


@jit
def normal_difference_parts(p, errors, fit, mesh, model, state, lists, scratch):
    """Row p of the standard errors' parts of the 3-unknown fit of W from the tangent parts (a, b) of
    the neighbours' normals, two equations ``[u v 0] (e f g)ᵀ = a`` and ``[0 u v] (e f g)ᵀ = b`` per
    neighbour (mru).

    With ``model`` the equations' errors are those the normals take from noisy heights
    (:mod:`curv.uncertainty.normals_model`), pooled with the neighbours'. Otherwise they are taken as
    independent, the vertex's own noise level (of the normals, not of the heights: never pooled): on a
    mesh from the plain residuals (a term for the tilt of p's own normal read it smaller still, as
    neighbouring normals share faces and their errors move together: mru R2 put 70 % of noisy meshes'
    vertices within 2 se with it, 85 % without); on a point cloud (``mesh`` None: normals fitted, not
    shared faces), where a tilt t of p's own normal (the frame) adds -t to every a (and b) equation,
    from the residuals of the fit with those two constants as unknowns
    (:func:`~curv.uncertainty.propagation.three_unknown_parts`).

    Parameters
    ----------
    fit : tuple
        ``(sums, w, neighbours, singular)``: the 12 sums ``Σ uu, uv, vv, au, av, bu, bv, a² + b², u, v,
        a, b`` over the neighbours, W and whether the solve failed.
    mesh : OnMesh or None
        On a mesh (:data:`~curv.estimators._fit_driver.ON_MESH`); None on a point cloud.
    scratch : tuple
        ``(factor (4, 3), grads (7, 3))``.
    """
    if errors is None:
        return
    sums, w, used, singular = fit
    suu, suv, svv, sau, sav, sbu, sbv, saa_bb, su, sv, sa, sb = sums
    e, f, g = w
    normal = (suu, suv, 0.0, suu + svv, suv, svv)
    xatb = e * sau + f * (sav + sbu) + g * sbv
    rad = math.hypot(0.5 * (e - g), f)
    if _normal_differences_modelled(p, errors, model, state, lists, (normal, w, used > 3 and not singular),
                                    (saa_bb - xatb, rad, 1.0), scratch):
        return
    residual = (saa_bb, xatb, 2 * used)
    if mesh is None:
        # the tilt's columns are constant: its sums (add_tilt) are counts and the rows' sums
        m = float(used)
        tilt = (m, 0.0, m, su, sv, 0.0, 0.0, su, sv, sa, sb, m, m)
        three_unknown_parts(p, errors, normal, residual, (0, 0.0, 0.0, 0.0), w, w, tilt)
    else:
        three_unknown_parts(p, errors, normal, residual, (0, 0.0, 0.0, 0.0), w, w, None)
    keep_alone(p, errors)


@jit
def _normal_differences_modelled(p, errors, model, state, lists, fit, residual, scratch):
    """:func:`_modelled` for :func:`normal_difference_parts`, its normal matrix factored first."""
    if model is None:
        return False
    normal, w, usable = fit
    factor, grads = scratch
    factor[0, 0], factor[0, 1], factor[0, 2], factor[1, 1], factor[1, 2], factor[2, 2] = normal
    usable = usable and cholesky_scaled(factor, 3, 3)
    if usable:
        grads[2:5, :] = 0.0
        shape_gradients(grads, w)
        factor_whiten(factor, 3, 3, grads)
    return _modelled(p, errors, model, state, lists, (factor, grads, 0.0, usable), residual)
