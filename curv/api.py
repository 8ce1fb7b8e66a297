"""The one entry point: ``curv.estimate(mesh, method, range)`` and its generator form."""

from __future__ import annotations

import enum
import time
from typing import Generator

import numpy as np

from .errors import EstimatorError, MeshError
from .estimators import DEFAULT_ESTIMATOR, get_spec, refusal
from .jit import COMPILE_MESSAGE, Progress, compile_pending
from .convert import as_mesh
from .mesh import Mesh
from .ranges import ball_radii, parse_range, resolve
from .normals import NormalWeighting, normalize_rows, unusable_normal_vertices, vertex_normals
from .result import Curvature
from .smoothing import smooth_positions, smooth_values
from .validity import Reason

__all__ = ["estimate", "iter_estimate", "Smoothing", "parse_range"]


class Smoothing(str, enum.Enum):
    """The paper's smoothing variants (§5.3, Fig. 10), applied around an estimate."""

    NONE = "none"
    MESH = "mesh"
    """Cotan-smooth the vertex positions, then estimate (R2SM in the paper)."""
    VALUES = "values"
    """Estimate, then cotan-smooth k1 and k2 over valid neighbours (R2SV)."""


def _asks_for_fit(normals) -> bool:
    """``normals="fit"``; any other string is an error naming the choices."""
    if not isinstance(normals, str):
        return False
    if normals != "fit":
        raise EstimatorError(f"normals must be an (n, 3) array or 'fit', got {normals!r}")
    return True


def _check_normals(normals, n: int) -> np.ndarray:
    arr = np.asarray(normals, dtype=np.float64)
    if arr.shape != (n, 3):
        raise MeshError(f"normals must have shape ({n}, 3), got {arr.shape}")
    return normalize_rows(arr)


def iter_estimate(
    mesh: Mesh,
    method: str = DEFAULT_ESTIMATOR,
    range=None,
    *,
    radius: float | None = None,
    normals: np.ndarray | None = None,
    normal_weighting: NormalWeighting | str = NormalWeighting.MAX,
    smooth: Smoothing | str | None = None,
    smooth_iterations: int = 1,
    smooth_strength: float = 0.5,
    fit_range=2,
    block_size: int | None = None,
    **options,
) -> Generator[float, None, Curvature]:
    """Estimate curvature step by step: yields the fraction done, returns the :class:`Curvature`.

    Every ``yield`` is a point where a caller may stop (cancel); the yielded values are
    :class:`curv.jit.Progress` floats, whose ``message`` says when kernels are being compiled.
    Parameters as in :func:`estimate`.
    """
    spec = get_spec(method)
    rng = resolve(spec, range, radius)
    options = spec.check_options(options)
    mesh = as_mesh(mesh)
    why_not = refusal(spec, mesh)
    if why_not is not None:
        raise MeshError(why_not)
    smooth = Smoothing(smooth or Smoothing.NONE)
    # before the connectivity and normals: on a first run their kernels compile too
    yield Progress(0.0, COMPILE_MESSAGE if compile_pending(spec.kernels) else "")
    t0 = time.perf_counter()
    work_mesh = mesh
    if smooth is Smoothing.MESH:
        work_mesh = smooth_positions(mesh, iterations=smooth_iterations, strength=smooth_strength)
        if normals is not None and not _asks_for_fit(normals):
            raise EstimatorError("normals cannot be given with smooth='mesh': they are recomputed on the smoothed mesh")
    # Where the faces around a vertex are not one consistently oriented fan, its normal averages
    # unrelated sheets; neighbours must not use it (the vertex itself is marked invalid below).
    meaningless = unusable_normal_vertices(mesh)
    # an estimator that visits every corner anyway computes the default normals on the way
    fused = normals is None and spec.computes_normals and NormalWeighting(normal_weighting) is NormalWeighting.MAX
    if fused:
        used_normals = None
    else:
        if normals is None:
            used_normals = vertex_normals(work_mesh, weighting=normal_weighting)
        elif _asks_for_fit(normals):
            from .fitted_normals import fitted_normals

            used_normals = fitted_normals(work_mesh, range=fit_range)
        else:
            used_normals = _check_normals(normals, mesh.n_vertices)
        if meaningless.any():
            used_normals = used_normals.copy()
            used_normals[meaningless] = np.nan
    radii = ball_radii(work_mesh, rng, uses_normals=spec.uses_normals) if spec.has_support else None
    raw = yield from spec.function(work_mesh, used_normals, radii, chunk=block_size, **options)
    if fused:
        used_normals = raw.normals

    k1, k2, d1, d2, reason = raw.k1, raw.k2, raw.d1, raw.d2, raw.reason.copy()
    isolated = mesh.isolated_vertices
    # no face at all is the root cause, whatever the estimator saw (no support, no normal)
    reason[isolated] = Reason.DEGENERATE
    # no surface to fit where the faces around a vertex are not one fan (bow tie, fin)
    reason[(reason == Reason.OK) & mesh.nonmanifold_vertices] = Reason.NONMANIFOLD
    # faces of opposite orientation meet here: the vertex normal is meaningless
    reason[(reason == Reason.OK) & meaningless] = Reason.DEGENERATE
    # on a border the normal and every fit see one side only: the values there are not estimates
    # of the surface's curvature, whatever the estimator
    reason[(reason == Reason.OK) & mesh.border_vertices] = Reason.BORDER
    reason[(reason == Reason.OK) & ~(np.isfinite(k1) & np.isfinite(k2))] = Reason.SINGULAR
    # the estimators order k1 >= k2 already; repair in place (the arrays are this call's own) the
    # rare rows they did not
    swap = np.flatnonzero(k2 > k1)
    k1[swap], k2[swap] = k2[swap], k1[swap]
    d1[swap], d2[swap] = d2[swap], d1[swap]
    # keep (d1, d2, N) right-handed so results are reproducible
    d2[_triple_product(d1, d2, used_normals) < 0] *= -1.0
    if smooth is Smoothing.VALUES:
        ok = reason == Reason.OK
        k1, k2 = smooth_values(mesh, np.stack([k1, k2], axis=1), ok,
                               iterations=smooth_iterations, strength=smooth_strength).T
        swap = k2 > k1
        k1, k2 = np.where(swap, k2, k1), np.where(swap, k1, k2)
        d1, d2 = np.where(swap[:, None], d2, d1), np.where(swap[:, None], -d1, d2)
    valid = reason == Reason.OK
    for arr in (k1, k2):
        arr[~valid] = np.nan
    d1[~valid] = np.nan
    d2[~valid] = np.nan
    yield 1.0
    return Curvature(
        k1=k1, k2=k2, d1=d1, d2=d2, normals=used_normals, valid=valid, reason=reason.astype(np.uint8),
        method=spec.name, range=rng.value,
        info={"seconds": time.perf_counter() - t0, "smooth": smooth.value, "range_label": rng.label,
              "normals": _normals_label(normals, normal_weighting, fit_range), **options,
              "radius": rng.radius,
              "smooth_iterations": smooth_iterations if smooth is not Smoothing.NONE else 0},
    )


def _normals_label(normals, weighting, fit_range) -> str:
    """How the normals were made, for the result's info: ``max``, ``fit R2`` or ``given``."""
    if normals is None:
        return NormalWeighting(weighting).value
    if isinstance(normals, str):
        from .ranges import range_label

        return f"fit {range_label(parse_range(fit_range))}"
    return "given"


def _triple_product(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Row-wise ``(a x b) . c`` of three (n, 3) arrays: (n,); NaN where a row has a NaN."""
    a0, a1, a2 = a.T
    b0, b1, b2 = b.T
    c0, c1, c2 = c.T
    return (a1 * b2 - a2 * b1) * c0 + (a2 * b0 - a0 * b2) * c1 + (a0 * b1 - a1 * b0) * c2


def estimate(
    mesh: Mesh,
    method: str = DEFAULT_ESTIMATOR,
    range=None,
    *,
    radius: float | None = None,
    normals: np.ndarray | None = None,
    normal_weighting: NormalWeighting | str = NormalWeighting.MAX,
    smooth: Smoothing | str | None = None,
    smooth_iterations: int = 1,
    smooth_strength: float = 0.5,
    fit_range=2,
    block_size: int | None = None,
    **options,
) -> Curvature:
    """Estimate principal curvatures and directions at every vertex.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh, pyvista.PolyData or meshio.Mesh
        Other libraries' meshes are converted by :func:`curv.convert.as_mesh`.
    method : str
        Registry name: ``meyer``, ``csm``, ``nc``, ``qs``, ``an``, ``ru``, ``mru`` (see ``curv.ESTIMATORS``).
    range : int, float or str, optional
        k of the range Rk: ``2``, ``2.5`` or ``"R2"`` (:mod:`curv.ranges`); any real k at least the
        estimator's smallest named range for the estimators with a support, the one named range
        for ``meyer`` (R1) and ``ru`` (R2). Default R2 where the estimator has it, else its range.
    radius : float, optional
        Instead of ``range``: the same ball radius in mesh units at every vertex.
    normals : (n, 3) array_like or "fit", optional
        Vertex normals to use (normalised here); ``"fit"``: each normal from a local jet fit at
        range ``fit_range`` (:func:`curv.fitted_normals.fitted_normals`); default Max-weighted
        normals of the mesh (the paper's protocol).
    normal_weighting : {"max", "area", "angle"}
        Weights of the default normals.
    smooth : {None, "mesh", "values"}
        Smooth the mesh before (R2SM) or the curvature values after (R2SV) the estimate.
    smooth_iterations, smooth_strength : int, float
        Explicit cotan-Laplacian steps and their step size.
    fit_range : int, float or str
        Range of the normal fit when ``normals="fit"``.
    block_size : int, optional
        Vertices per kernel call (the granularity of progress and cancel); default adaptive, about
        every 0.05 s. Results do not depend on it.
    **options
        Estimator-specific options (``curv.ESTIMATORS[method].options``), e.g. ``degree=4`` for
        ``jet``.

    Returns
    -------
    Curvature
        ``k1 >= k2``, unit directions, ``valid`` mask; NaN where invalid.

    Raises
    ------
    EstimatorError
        Unknown method, or a range/radius the estimator does not take (the message names the
        allowed forms).
    MeshError
        A mesh the estimator cannot handle (e.g. quads for a triangle-only estimator).
    """
    gen = iter_estimate(mesh, method, range, radius=radius, normals=normals, normal_weighting=normal_weighting,
                        smooth=smooth, smooth_iterations=smooth_iterations,
                        smooth_strength=smooth_strength, fit_range=fit_range, block_size=block_size,
                        **options)
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value
