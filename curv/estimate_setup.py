"""What an estimate starts from: the input's normals, the flags of its validity rules, a region's rows.

:func:`mesh_setup` and :func:`point_setup` give the working mesh, the normals the estimators read and
:class:`Flags` (what the input says about its vertices, which :func:`curv.estimate_finish.finish`
turns into reason codes); :class:`Smoothing` names the paper's smoothing variants.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from .core.errors import EstimatorError, MeshError
from .core.features import check_angle, feature_set
from .core.mesh import Mesh
from .core.pointcloud import PointCloud
from .core.ranges import parse_range
from .core.validity import Reason
from .geometry.neighbourhood import latest_with_mesh
from .geometry.normals import NormalWeighting, cached_max_normals, normalize_rows, unusable_normal_vertices, vertex_normals
from .geometry.smoothing import smooth_positions

__all__ = ["Smoothing", "Flags", "mesh_setup", "point_setup", "check_vertices", "cached_feature_set", "without_rows",
           "mesh_normals_label"]


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


@dataclass(frozen=True)
class Flags:
    """What the input says about its vertices, for the validity rules of :func:`curv.api.iter_estimate`.

    ``isolated`` (n,) bool: no face or no other point; ``forced``: ``(mask, Reason)`` pairs set
    whatever the estimator found (later pairs win); ``marks``: ``(mask, Reason)`` pairs of the
    causes in :data:`curv.core.validity.PRECEDENCE`, which the vertices the estimator left OK take
    in that precedence (:func:`curv.core.validity.mark_ok_rows`); ``info``: extra entries of the
    result's info.
    """

    isolated: np.ndarray
    marks: tuple
    info: dict
    forced: tuple = ()
    support_marks: tuple = ()
    """Generators ``(radii, centres, usable) -> (mask, Reason, name)`` run after the estimate; ``usable``
    (n,) bool marks the points whose normals the estimator reads (None: it reads none); the
    result's ``info[name]`` counts the estimated points the mask holds."""

    def marked(self, mask: np.ndarray, code) -> "Flags":
        """These flags with one more ``(mask, code)`` mark, applied last."""
        return Flags(isolated=self.isolated, marks=self.marks + ((mask, code),), info=self.info,
                     forced=self.forced)


def mesh_setup(mesh: Mesh, spec, normals, normal_weighting, smooth, smooth_iterations, smooth_strength,
               fit_range, feats):
    """The working mesh, its normals (None when the estimator computes them), flags, and whether fused."""
    work_mesh = mesh
    if smooth is Smoothing.MESH:
        work_mesh = smooth_positions(mesh, iterations=smooth_iterations, strength=smooth_strength)
        if normals is not None and not _asks_for_fit(normals):
            raise EstimatorError("normals cannot be given with smooth='mesh': they are recomputed on the smoothed mesh")
    # an estimator that visits every corner anyway computes the default normals on the way
    fused = normals is None and spec.computes_normals and NormalWeighting(normal_weighting) is NormalWeighting.MAX
    if spec.has_support or not fused:
        # it will read the neighbours or the normals: the one walk over the corners gives the flags too
        mesh.corner_pass
    # Where the faces around a vertex are not one consistently oriented fan, its normal averages
    # unrelated sheets; neighbours must not use it (the vertex itself is marked invalid below).
    meaningless = unusable_normal_vertices(mesh)
    if fused:
        used_normals = None
    else:
        if normals is None:
            used_normals = _default_normals(work_mesh, normal_weighting, smoothed=work_mesh is not mesh)
        elif _asks_for_fit(normals):
            from .fitted_normals import fitted_normals

            used_normals = fitted_normals(work_mesh, range=fit_range, features=feats)
        else:
            used_normals = _check_normals(normals, mesh.n_vertices)
        if meaningless.any():
            used_normals = used_normals.copy()
            used_normals[meaningless] = np.nan
    flags = Flags(isolated=mesh.isolated_vertices, info={"points": False},
                  forced=((mesh.isolated_vertices, Reason.DEGENERATE),), marks=(
        # no surface to fit where the faces around a vertex are not one fan (bow tie, fin)
        (mesh.nonmanifold_vertices, Reason.NONMANIFOLD),
        # faces of opposite orientation meet here: the vertex normal is meaningless
        (meaningless, Reason.DEGENERATE),
        # on a border the normal and every fit see one side only: the values there are not
        # estimates of the surface's curvature, whatever the estimator
        (mesh.border_vertices, Reason.BORDER),
    ))
    return work_mesh, used_normals, flags, fused


def point_setup(cloud: PointCloud, normals, *, orient, fit_range, keep_fits_at=(), keep_fits=None):
    """A point cloud's normals (given, the cloud's own, or estimated and oriented) and flags.

    ``normals``: None (the cloud's if it has them, else jet fits), ``"fit"`` (jet), ``"pca"``, or
    an (n, 3) array. ``keep_fits_at``, ``keep_fits``: the ranges of an estimate that reads the
    normals' fits, and the fits it reads (:func:`curv.point_normals.point_normals`).
    """
    from .point_normals import border_points, point_normals, support_floor

    n = cloud.n_points
    ambiguous = one_sided = widened = np.zeros(n, bool)
    orientation = None  # normals not estimated here are not turned
    if normals is None and cloud.normals is not None:
        used, label = normalize_rows(np.asarray(cloud.normals)), "file"
    elif normals is None or (isinstance(normals, str) and normals in ("pca", "fit")):
        method = "pca" if isinstance(normals, str) and normals == "pca" else "jet"
        est = point_normals(cloud, method=method, range=fit_range, orient=orient, keep_fits_at=keep_fits_at,
                            keep_fits=keep_fits)
        used, ambiguous, one_sided, label = est.normals, est.ambiguous, est.one_sided, f"{method} {est.label}"
        orientation = est.orient if isinstance(est.orient, str) else tuple(float(v) for v in est.orient)
        widened = est.widened
    elif isinstance(normals, str):
        raise EstimatorError(f"normals on a point cloud must be an (n, 3) array, 'pca' or 'fit'; got {normals!r}")
    else:
        used, label = _check_normals(normals, n), "given"
    border = border_points(cloud)
    coincident = cloud.coincident_points
    flags = Flags(isolated=cloud.isolated_vertices,
                  # a normal fitted across an empty side is not trusted
                  forced=((cloud.isolated_vertices, Reason.DEGENERATE), (one_sided, Reason.SINGULAR),
                          (ambiguous, Reason.ORIENTATION)), marks=(
        # a repeat of an earlier point: that one stands for it
        (coincident, Reason.DEGENERATE),
        # on the rim of an open scan the fits see one side only, as on a mesh border
        (border, Reason.BORDER),
    ), info={"points": True, "orientation": orientation,
             "border_points": int(border.sum()), "coincident_points": int(coincident.sum()),
             "ambiguous_normals": int(ambiguous.sum()), "one_sided_normals": int(one_sided.sum()),
             "coordinate_step": cloud.coordinate_step, "support_floor": support_floor(cloud),
             "widened_normals": int(widened.sum())},
                  support_marks=(_line_supports(cloud), _quantised_supports(cloud)))
    return used, flags, label


def _line_supports(cloud: PointCloud):
    """A support check: points whose support lies along a line or a curve (of the neighbours whose
    normals the estimator can use, when it reads them) are SINGULAR
    (:data:`curv.point_normals.MIN_SPREAD`)."""
    from .point_normals import MIN_SPREAD, support_spread

    def check(radii, centres, usable=None):
        spread = yield from support_spread(cloud, radii, centres, usable=usable)
        return ~(spread >= MIN_SPREAD), Reason.SINGULAR, "line_supports"

    return check


def _quantised_supports(cloud: PointCloud):
    """A support check: supports only a few steps of the grid the coordinates are stored on wide
    see its stairs, not the surface: SINGULAR (:data:`curv.point_normals.MIN_SUPPORT_STEPS`)."""
    from .point_normals import quantised_supports

    def check(radii, centres, usable=None):
        yield 1.0
        return quantised_supports(cloud, radii), Reason.SINGULAR, "quantised_supports"

    return check


def check_vertices(vertices, n: int) -> np.ndarray | None:
    """``vertices=`` as an (c,) int64 index array, or None for all; a one-line error when invalid."""
    if vertices is None:
        return None
    arr = np.asarray(vertices)
    if arr.dtype == bool:
        raise EstimatorError("vertices must be an array of vertex indices, not a mask (use np.flatnonzero(mask))")
    if arr.ndim != 1 or (arr.size and not np.issubdtype(arr.dtype, np.integer)):
        raise EstimatorError(f"vertices must be a 1-D array of vertex indices; got shape {arr.shape}, {arr.dtype}")
    arr = np.ascontiguousarray(arr, dtype=np.int64)
    if arr.size and (arr.min() < 0 or arr.max() >= n):
        bad = int(arr[(arr < 0) | (arr >= n)][0])
        raise EstimatorError(f"vertex index {bad} is out of range for a mesh of {n} vertices")
    return arr


def cached_feature_set(mesh: Mesh, features):
    """:func:`curv.core.features.feature_set`; the latest angle's is kept with the mesh, so that estimates
    over small regions at one angle do no whole-mesh work to find the creases again."""
    if isinstance(features, (bool, np.bool_)) or np.ndim(features) != 0:
        return feature_set(mesh, features)  # a caller's mask (or a one-line error)
    angle = check_angle(features)
    return latest_with_mesh(mesh, "feature set", (angle,), lambda: feature_set(mesh, angle))


def without_rows(normals: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """A read-only copy of ``normals`` (n, 3) with NaN rows at ``vertices`` (n,) bool, in the same layout."""
    out = normals.copy(order="K")
    out[vertices] = np.nan
    out.setflags(write=False)
    return out


def _default_normals(mesh: Mesh, weighting, *, smoothed: bool) -> np.ndarray:
    """The mesh's vertex normals; Max's weights on the mesh itself are cached with it (read-only),
    so that an estimate over a small region does not recompute them."""
    if smoothed or NormalWeighting(weighting) is not NormalWeighting.MAX:
        return vertex_normals(mesh, weighting=weighting)
    return cached_max_normals(mesh)


def mesh_normals_label(normals, weighting, fit_range) -> str:
    """How the normals were made, for the result's info: ``max``, ``fit R2`` or ``given``."""
    if normals is None:
        return NormalWeighting(weighting).value
    if isinstance(normals, str):
        from .core.ranges import range_label

        return f"fit {range_label(parse_range(fit_range))}"
    return "given"
