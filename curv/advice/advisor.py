"""Which estimator for this mesh? Measured mesh features -> ranked estimator variants (from the study).

>>> adv = curv.advise(mesh)                        # doctest: +SKIP
>>> adv.method, adv.range, adv.expected_erel, adv.why
('mru', 4, 0.12, 'noise about 0.6 of the paper's level, irregular (22 degrees): mru R4, expected median e_rel 0.12')

The advisor measures the three features the paper's study varies (density, noise, irregularity)
and the mesh's shape and tessellation (valence and edge spread, curvature spread, anisotropy, saddle
share, border share; see :class:`MeshFeatures`) and predicts the median e_rel of every candidate variant from a table
of study results (``curv/data/advisor_table.json``, built by :mod:`curv.advice.table`; the module is not named ``advise`` so that importing it cannot shadow the function ``curv.advise``). The
table holds one point per mesh of a study run (the paper's Monge patches on the hexagon, plus
noisy closed analytic surfaces, which widen the range of densities and tessellations): the
advisor's own features measured on that mesh, and the median e_rel every variant reached on it
against the exact curvature. A prediction is the
Gaussian-kernel weighted mean of ``log(e_rel)`` (floored at the table's ``erel_floor``) over the
table's meshes in the scaled feature space ``(log density, noise level or its square root,
irregularity)`` and the further axes the table chose (``kernel["axes"]``); axes, transforms, scales
and bandwidth are the table's (chosen by grouped leave-one-out regret when the table is built). Because the table's coordinates are
measured exactly as on the user's mesh, a bias of a measure cancels instead of misplacing the
mesh; far outside the table the nearest meshes decide (the grid's edge acts as a clip). There is
no hand-written rule: a different table gives different advice.
"""

from __future__ import annotations

import functools
import json
from dataclasses import asdict, dataclass, field
from importlib import resources

import numpy as np

from ..core.errors import MeshError
from ..core.mesh import Mesh
from .answer import Advice, Candidate

__all__ = ["Advice", "Candidate", "MeshFeatures", "advise", "measure_features", "load_table", "valid_shares", "valid_masks",
           "TABLE_RESOURCE", "FIT_METHOD", "FIT_RANGE", "VALID_SHARE_SLACK", "VALID_SAMPLE", "SHAPE_MEASURES",
           "RESIDUAL_MEASURES", "residual_measures",
           "BASE_COLUMNS", "kernel_axes", "table_coordinates", "feature_values", "shape_measures", "table_ranking",
           "describe_mesh"]

TABLE_RESOURCE = "data/advisor_table.json"
"""The table inside the ``curv`` package (see :mod:`curv.advice.table`)."""

FIT_METHOD = "qs"
FIT_RANGE = 3
"""The local fit the noise and density measures use: the quadratic height fit at R3 (it works on
polygons and at borders, and over R3 its curvature is not yet dominated by the noise it measures)."""

VALID_SHARE_SLACK = 0.02
"""A candidate that leaves more than this share of the vertices invalid beyond the candidate that
leaves the fewest ranks after every candidate that does not (whatever its predicted error)."""

VALID_SAMPLE = 2000
"""Vertices the valid shares are counted on (all of them on smaller meshes; a fixed random sample,
seed 0, on larger ones: the share then has a standard error of at most 1.1 %)."""

_MAD_TO_SIGMA = 1.4826
"""Median absolute deviation -> standard deviation of a Gaussian."""


@dataclass(frozen=True)
class MeshFeatures:
    """What the advisor measured on a mesh.

    Attributes
    ----------
    irregularity_deg : float
        The paper's irregularity (§5.1), RMS deviation of all triangle angles from 60 degrees,
        measured in 3D on the mesh as given (polygons fan-triangulated from their first corner) and
        corrected for the angle jitter the noise itself adds:
        ``sqrt(max(raw² - (c * noise level)², 0))``, ``c`` calibrated on the study's meshes (stored
        with the table). The study sets its irregularity on the planar hexagon before lifting it
        onto the surface; the lift of a steep patch adds its own distortion, which this 3D measure
        (the mesh the estimators see) includes: a regular hexagon lifted onto a steep quadratic
        patch measures about 25 degrees.
    noise : float
        Estimated standard deviation per coordinate of Gaussian vertex noise, as a fraction of the
        mean edge length (the study's unit: its 100 % level is
        :data:`curv.variants.NOISE_FRACTION` = 0.1). Measured as the robust spread of the
        1-ring residuals of a local quadric: at every validly fitted vertex p the ``qs`` fit at R3
        gives k1, k2, d1, d2 in the frame of p's normal n; each 1-ring neighbour j gives the residual
        ``n·(x_j - x_p) + (k1 u² + k2 v²) / 2`` with ``u = d1·(x_j - x_p)``, ``v = d2·(x_j - x_p)``;
        ``raw = 1.4826 MAD(residuals) / mean edge``. The fit's own model error (it grows with the
        square of the density: a quadric misses the cubic terms) and the absorbed part of the noise
        are removed by a calibration ``raw² = a² + c density⁴ + (b noise)²``, least squares over the
        table's meshes of known noise (study patches and closed surfaces):
        ``noise = sqrt(max(raw² - a² - c density⁴, 0)) / b``; the numbers are the table's
        ``calibration``.
    density : float
        Dimensionless resolution: mean edge length times the median of ``|k1| + |k2|`` over the
        validly fitted vertices of the same R3 fit (the table's points use this same measure; the
        value from the exact curvature is stored beside it). A sphere of radius r with edge h gives
        about 2 h / r; noise inflates it, the more the denser the mesh (at the paper's 100 % level
        by about a quarter on 3169 vertices and 90 % on 12481: medians over the table's patches).
    border_share : float
        Share of the vertices on a border.
    polygon_kinds : dict
        Face size -> number of faces, e.g. ``{3: 6000}`` or ``{3: 10, 4: 5000}``.
    n_vertices : int
    mean_edge : float
        Mean edge length in mesh units.
    noise_raw : float
        The uncalibrated noise measure (``raw`` above). The table's kernel may use its logarithm as
        an axis: it keeps what the calibration clips to zero (a coarse mesh's noise swallowed by the
        density term, a hundredth of the paper's level on a dense mesh).
    irregularity_raw_deg : float
        The uncorrected RMS angle deviation.
    edge_cv : float
        Coefficient of variation of the edge lengths (standard deviation over mean): the
        tessellation's regularity in size, 0 for equal edges.
    valence_sd : float
        Standard deviation of the valence over the vertices off the border: 0 for a regular grid, a
        little above for a geodesic sphere (12 vertices of valence 5), larger for a scan.
    anisotropy : float
        Median of ``(k1 - k2) / (|k1| + |k2|)`` over the validly fitted vertices of the R3 fit: 0
        where the surface is umbilic (a sphere), up to 1 where it bends one way only (a cylinder).
    curvature_spread : float
        Interquartile range of ``log(|k1| + |k2|)`` over the same vertices: how unevenly the
        curvature is spread over the surface (0 on a sphere).
    hyperbolic_share : float
        Share of the same vertices with ``k1 k2 < 0`` (saddle-shaped).
    noise_raw4 : float
        Median over sampled vertices of the residual spread of a quartic height fit over the R3
        ball, over the mean edge (:func:`curv.advice.residuals.fit_residual_spreads`): the quartic
        absorbs most of the model error a quadric leaves (a coarse or irregularly lifted mesh's, a
        strongly curved surface's) and none of the noise, so this reads noise where :attr:`noise_raw`
        reads both.
    residual_ratio : float
        Median over the same vertices of the quartic's residual spread over the quadric's: about 1
        where noise dominates the residuals, near 0 where the surface's own shape does.

    The shape measures, :attr:`noise_raw`, the residual measures and :attr:`border_share` are measures the table's kernel may
    use as further axes (which, and how wide, is chosen when the table is built:
    ``kernel["axes"]``); the open/closed distinction is :attr:`border_share`.
    """

    irregularity_deg: float
    noise: float
    density: float
    border_share: float
    polygon_kinds: dict = field(default_factory=dict)
    n_vertices: int = 0
    mean_edge: float = float("nan")
    noise_raw: float = float("nan")
    irregularity_raw_deg: float = float("nan")
    edge_cv: float = float("nan")
    valence_sd: float = float("nan")
    anisotropy: float = float("nan")
    curvature_spread: float = float("nan")
    hyperbolic_share: float = float("nan")
    noise_raw4: float = float("nan")
    residual_ratio: float = float("nan")

    @property
    def noise_level(self) -> float:
        """:attr:`noise` as a fraction of the paper's 100 % level."""
        from ..variants import NOISE_FRACTION

        return self.noise / NOISE_FRACTION

    @property
    def triangular(self) -> bool:
        return set(self.polygon_kinds) <= {3}


# ---------------------------------------------------------------------------- features
def polygon_kinds(mesh: Mesh) -> dict:
    """Face size -> count, in increasing size."""
    sizes, counts = np.unique(mesh.face_sizes, return_counts=True)
    return {int(s): int(c) for s, c in zip(sizes, counts)}


def fan_triangles(mesh: Mesh) -> np.ndarray:
    """(t, 3) int64: the triangles, and every polygon fan-triangulated from its first corner."""
    faces = mesh.faces
    parts = [np.stack([faces[:, 0], faces[:, i], faces[:, i + 1]], axis=1)[faces[:, i + 1] >= 0]
             for i in range(1, faces.shape[1] - 1)]
    return np.concatenate(parts) if parts else np.empty((0, 3), np.int64)


def angle_deviation_deg(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """RMS deviation of the 3D triangle angles from 60 degrees (degenerate triangles left out)."""
    p = vertices[triangles]
    a = np.roll(p, -1, axis=1) - p
    b = np.roll(p, -2, axis=1) - p
    cross = np.linalg.norm(np.cross(a, b), axis=2)
    dot = np.einsum("mij,mij->mi", a, b)
    ok = np.all(cross > 0, axis=1)
    if not ok.any():
        return float("nan")
    ang = np.degrees(np.arctan2(cross[ok], dot[ok]))
    return float(np.sqrt(np.mean((ang - 60.0) ** 2)))


def _fit_residuals(mesh: Mesh, res) -> np.ndarray:
    """Residuals of each validly fitted vertex's quadric at its 1-ring neighbours (all directed edges)."""
    adj = mesh.adjacency.tocoo()
    p, j = adj.row.astype(np.int64), adj.col.astype(np.int64)
    keep = res.valid[p] & (p != j)
    p, j = p[keep], j[keep]
    dx = mesh.vertices[j] - mesh.vertices[p]
    h = np.einsum("ij,ij->i", res.normals[p], dx)
    u = np.einsum("ij,ij->i", res.d1[p], dx)
    v = np.einsum("ij,ij->i", res.d2[p], dx)
    # positive curvature bends away from the normal: the neighbours lie below the tangent plane
    return h + 0.5 * (res.k1[p] * u * u + res.k2[p] * v * v)


def raw_measures(mesh: Mesh, *, normals=None) -> dict:
    """The uncalibrated measures: ``noise_raw``, ``irregularity_raw_deg``, ``density`` and the rest.

    Parameters
    ----------
    mesh : Mesh
    normals : (n, 3) array_like, optional
        Vertex normals for the fit; default Max-weighted.

    Returns
    -------
    dict
        Keys ``noise_raw``, ``irregularity_raw_deg``, ``density``, ``border_share``,
        ``polygon_kinds``, ``n_vertices``, ``mean_edge`` and the shape and tessellation measures
        :data:`SHAPE_MEASURES` and :data:`RESIDUAL_MEASURES` (see :class:`MeshFeatures`).

    Raises
    ------
    MeshError
        When no vertex can be fitted (too small or degenerate a mesh).
    """
    from ..api import estimate

    edge = float(mesh.mean_edge_length)
    if not (np.isfinite(edge) and edge > 0):
        raise MeshError("cannot advise on a mesh without edges of positive length")
    res = estimate(mesh, method=FIT_METHOD, range=FIT_RANGE, normals=normals)
    if not res.valid.any():
        raise MeshError(f"cannot advise: the {FIT_METHOD} R{FIT_RANGE} fit is invalid at every vertex")
    r = _fit_residuals(mesh, res)
    r = r[np.isfinite(r)]
    mad = float(np.median(np.abs(r - np.median(r)))) if r.size else float("nan")
    k1, k2 = res.k1[res.valid], res.k2[res.valid]
    scale = np.abs(k1) + np.abs(k2)
    return {
        "noise_raw": _MAD_TO_SIGMA * mad / edge,
        "irregularity_raw_deg": angle_deviation_deg(mesh.vertices, fan_triangles(mesh)),
        "density": edge * float(np.median(scale)),
        "border_share": float(mesh.border_vertices.mean()) if mesh.n_vertices else 0.0,
        "polygon_kinds": polygon_kinds(mesh),
        "n_vertices": int(mesh.n_vertices),
        "mean_edge": edge,
        **shape_measures(mesh, k1, k2),
        **residual_measures(mesh, normals=res.normals),
    }


SHAPE_MEASURES = ("edge_cv", "valence_sd", "anisotropy", "curvature_spread", "hyperbolic_share")
"""The shape and tessellation measures of :class:`MeshFeatures` (raw: no calibration)."""

RESIDUAL_MEASURES = ("noise_raw4", "residual_ratio")
"""The measures of :class:`MeshFeatures` that tell model error from noise (raw: no calibration)."""


def residual_measures(mesh: Mesh, *, normals=None) -> dict:
    """:data:`RESIDUAL_MEASURES` from the quadratic and quartic fits'
    residual spreads (:func:`curv.advice.residuals.fit_residual_spreads`; see :class:`MeshFeatures`).

    Parameters
    ----------
    mesh : Mesh
    normals : (n, 3) array_like, optional
        Unit vertex normals of the fits' frames; default Max-weighted.

    Returns
    -------
    dict
        :data:`RESIDUAL_MEASURES` -> float (NaN when no vertex can be fitted).
    """
    from .residuals import fit_residual_spreads

    s2, s4 = fit_residual_spreads(mesh, normals=normals)
    ok = np.isfinite(s2) & np.isfinite(s4) & (s2 > 0)
    if not ok.any():
        return {"noise_raw4": float("nan"), "residual_ratio": float("nan")}
    return {"noise_raw4": float(np.median(s4[ok])) / float(mesh.mean_edge_length),
            "residual_ratio": float(np.median(s4[ok] / s2[ok]))}


def shape_measures(mesh: Mesh, k1: np.ndarray, k2: np.ndarray) -> dict:
    """The tessellation's regularity and the curvature's shape (see :class:`MeshFeatures`).

    Parameters
    ----------
    mesh : Mesh
    k1, k2 : (m,) float64
        Principal curvatures of the validly fitted vertices (k1 >= k2).

    Returns
    -------
    dict
        :data:`SHAPE_MEASURES` -> float.
    """
    lengths = mesh.edge_lengths
    interior = ~mesh.border_vertices
    valence = mesh.valence[interior]
    scale = np.abs(k1) + np.abs(k2)
    ok = scale > 0
    log_scale = np.log(scale[ok])
    nan = float("nan")
    return {
        "edge_cv": float(np.std(lengths) / np.mean(lengths)) if lengths.size else nan,
        "valence_sd": float(np.std(valence)) if valence.size else nan,
        "anisotropy": float(np.median((k1[ok] - k2[ok]) / scale[ok])) if ok.any() else nan,
        "curvature_spread": float(np.subtract(*np.percentile(log_scale, [75, 25]))) if ok.any() else nan,
        "hyperbolic_share": float(np.mean(k1 * k2 < 0)) if k1.size else nan,
    }


def calibrate_noise(noise_raw: float, calibration: dict, density: float = 0.0) -> float:
    """``sqrt(max(raw² - a² - c density⁴, 0)) / b`` (see :attr:`MeshFeatures.noise`)."""
    a, b = calibration["noise_floor"], calibration["noise_gain"]
    c = calibration.get("noise_density4", 0.0)
    return float(np.sqrt(max(noise_raw**2 - a**2 - c * density**4, 0.0)) / b)


def calibrate_irregularity(raw_deg: float, noise: float, calibration: dict) -> float:
    """``sqrt(max(raw² - (c noise_level)², 0))`` (see :attr:`MeshFeatures.irregularity_deg`)."""
    from ..variants import NOISE_FRACTION

    c = calibration["irregularity_noise_deg"]
    return float(np.sqrt(max(raw_deg**2 - (c * noise / NOISE_FRACTION) ** 2, 0.0)))


def measure_features(mesh: Mesh, *, normals=None, table: dict | None = None) -> MeshFeatures:
    """Measure the advisor's :class:`MeshFeatures` (calibrated with ``table``'s calibration)."""
    table = load_table() if table is None else table
    raw = raw_measures(mesh, normals=normals)
    cal = table["calibration"]
    noise = calibrate_noise(raw["noise_raw"], cal, raw["density"])
    irr = calibrate_irregularity(raw["irregularity_raw_deg"], noise, cal)
    return MeshFeatures(irregularity_deg=irr, noise=noise, **raw)


# ---------------------------------------------------------------------------- table and prediction
@functools.lru_cache(maxsize=1)
def _packaged_table() -> str:
    return resources.files("curv").joinpath(TABLE_RESOURCE).read_text()


def load_table(path=None) -> dict:
    """The advisor's table: the packaged one, or a JSON file written by :mod:`curv.advice.table`."""
    if path is None:
        return json.loads(_packaged_table())
    with open(path) as fh:
        return json.load(fh)


BASE_COLUMNS = ("density", "noise_level", "irregularity_deg")
"""The table's first three point columns, always kernel axes (log, square root or linear, linear)."""


def kernel_axes(table: dict) -> list:
    """The kernel's axes as ``[column, transform, scale]`` (transform ``"log"``, ``"sqrt"`` or
    ``"linear"``); a table without ``kernel["axes"]`` has the three base axes of its ``noise_axis``
    and ``scales``."""
    kernel = table["kernel"]
    if "axes" in kernel:
        return [list(a) for a in kernel["axes"]]
    scales = kernel["scales"]
    return [["density", "log", scales[0]], ["noise_level", kernel.get("noise_axis", "linear"), scales[1]],
            ["irregularity_deg", "linear", scales[2]]]


def _transform(values, how: str) -> np.ndarray:
    values = np.asarray(values, float)
    if how == "log":
        return np.log(np.maximum(values, 1e-12))
    if how == "sqrt":
        return np.sqrt(np.maximum(values, 0.0))
    return values


def table_coordinates(table: dict, *columns) -> np.ndarray:
    """Feature-space coordinates of the table's kernel.

    Parameters
    ----------
    table : dict
        Its ``kernel`` (:func:`kernel_axes`) and ``columns`` (the names of the point columns;
        default the three :data:`BASE_COLUMNS`).
    *columns : array_like
        One value or array per point column, in ``table["columns"]`` order (arrays broadcast).

    Returns
    -------
    (..., a) float64
        Each axis's column, transformed (log density; the noise level or its square root, as the
        errors change fastest near zero noise; the rest as they are or their square root) and
        divided by the axis's scale.
    """
    names = list(table.get("columns", BASE_COLUMNS))
    values = np.broadcast_arrays(*[np.asarray(c, float) for c in columns])
    axes = [_transform(values[names.index(col)], how) / scale for col, how, scale in kernel_axes(table)]
    return np.stack(axes, axis=-1)


def feature_values(features: MeshFeatures, columns) -> list:
    """The values of ``columns`` (the table's point columns) measured on a mesh: the calibrated
    base features and the raw shape and tessellation measures (:class:`MeshFeatures`)."""
    return [features.noise_level if c == "noise_level" else getattr(features, c) for c in columns]


def kernel_predict(points: np.ndarray, log_values: np.ndarray, query: np.ndarray, bandwidth: float) -> np.ndarray:
    """Gaussian-kernel weighted mean of ``log_values`` at ``query``, NaN entries left out per column.

    Parameters
    ----------
    points : (p, 3) float64
        Scaled coordinates of the table's meshes.
    log_values : (p, v) float64
        log median e_rel of each variant on each mesh (NaN where it has none).
    query : (3,) float64
    bandwidth : float
        Kernel width in scaled units.

    Returns
    -------
    (v,) float64
        Predicted median e_rel of every variant (NaN where no mesh has a value).
    """
    d2 = np.sum((points - query) ** 2, axis=1) / bandwidth**2
    have = np.isfinite(log_values)
    dist = np.where(have, d2[:, None], np.inf)
    nearest = dist.min(axis=0)
    # shifted per variant: far from every point the nearest meshes with a value still count
    with np.errstate(invalid="ignore"):
        w = np.where(have, np.exp(-0.5 * (dist - np.where(np.isfinite(nearest), nearest, 0.0))), 0.0)
    total = w.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.sum(w * np.where(have, log_values, 0.0), axis=0) / np.where(total > 0, total, np.nan)
    return np.exp(mean)


def log_erel(table: dict) -> np.ndarray:
    """(p, v) log of the table's median e_rel, floored at the table's ``kernel["erel_floor"]`` (NaN
    where missing). Below the floor an error is rounding (nc R1 on a noise-free sphere reads 1e-15):
    in a mean of logs one such mesh would outweigh every other neighbour, and all such calls are
    equally good."""
    erel = np.asarray(table["median_erel"], float)
    floor = table["kernel"].get("erel_floor", 0.0)
    return np.log(np.maximum(erel, floor) if floor > 0 else erel)


def predict(table: dict, features: MeshFeatures) -> dict:
    """Predicted median e_rel of every variant of the table at ``features`` (NaN where it has none)."""
    points = np.asarray(table["points"], float)
    q = table_coordinates(table, *feature_values(features, table.get("columns", BASE_COLUMNS)))
    pred = kernel_predict(table_coordinates(table, *points.T), log_erel(table), q, table["kernel"]["bandwidth"])
    return dict(zip(table["variants"], pred.tolist()))


def candidates(table: dict, features: MeshFeatures) -> list[str]:
    """Variant ids of the table the mesh admits: registered, with options the estimator accepts,
    and not refused for the mesh's faces (:func:`curv.estimators.refusal`: triangle-only estimators
    on polygons)."""
    from ..core.errors import EstimatorError
    from ..estimators import ESTIMATORS
    from ..estimators.registry import refusal
    from ..variants import Variant

    faces = _FaceKinds(features.polygon_kinds)
    out = []
    for vid in table["variants"]:
        v = Variant.from_id(vid)
        spec = ESTIMATORS.get(v.method)
        if spec is None or refusal(spec, faces) is not None:
            continue
        try:
            spec.check_options({k: x for k, x in v.options if k not in ("normals", "fit_range")})
        except EstimatorError:
            continue
        out.append(vid)
    return out


class _FaceKinds:
    """What :func:`curv.estimators.refusal` reads of a mesh, from the measured polygon kinds."""

    def __init__(self, kinds: dict):
        self.face_sizes = np.array(sorted(kinds), np.int64)
        self.is_triangular = set(kinds) <= {3}


def valid_shares(mesh: Mesh, variant_ids, *, sample: int = VALID_SAMPLE, within=None) -> dict:
    """Share of the vertices each variant can estimate on ``mesh``, from the supports' sizes.

    Counted on the same vertices for every variant (all of them up to ``sample``, else a fixed random
    sample of that many, seed 0) by :func:`valid_masks`.

    Parameters
    ----------
    mesh : Mesh
    variant_ids : iterable of str
    sample : int
    within : (m,) int array_like, optional
        Count among these vertices only (default all).

    Returns
    -------
    dict
        ``{variant id: share in [0, 1]}``.
    """
    centres, masks = valid_masks(mesh, variant_ids, sample=sample, within=within)
    return {vid: float(ok.mean()) if ok.size else 0.0 for vid, ok in masks.items()}


def valid_masks(mesh: Mesh, variant_ids, *, sample: int = VALID_SAMPLE, within=None) -> tuple[np.ndarray, dict]:
    """Which of some vertices each variant can estimate on ``mesh``, from the supports' sizes.

    The vertices are all of them up to ``sample``, else a fixed random sample of that many (seed 0),
    with one support search per distinct ball
    (:func:`curv.geometry.neighbourhood.support_sizes`, the radius from :func:`curv.core.ranges.ball_radii`), by the
    registry's facts: a vertex is lost when it is on a border or has no usable normal (every
    estimator), when its support holds fewer vertices than the fit needs
    (:meth:`EstimatorSpec.fewest_neighbours`: the fit's unknowns, the jet's by degree), when a
    closed-ring estimator's support reaches a border (``meyer``, ``ru``: the vertex or a 1-ring
    neighbour is on one), and
    everywhere for an estimator the mesh is refused by (:func:`curv.estimators.refusal`: triangle-only
    on polygons). ``normals="fit"`` also needs the degree-2 jet of ``fit_range`` to fit. Singular
    systems are not foreseen (rare on a mesh without degenerate faces).

    Parameters
    ----------
    mesh : Mesh
    variant_ids : iterable of str
    sample : int
    within : (m,) int array_like, optional
        Count among these vertices only (default all).

    Returns
    -------
    centres : (c,) int64
        The vertices counted on.
    masks : dict
        ``{variant id: (c,) bool}``.
    """
    from ..estimators import get_spec
    from ..estimators.registry import refusal
    from ..geometry.neighbourhood import support_sizes
    from ..geometry.normals import unusable_normal_vertices
    from ..core.ranges import ball_radii, resolve
    from ..variants import Variant

    pool = np.arange(mesh.n_vertices) if within is None else np.unique(np.asarray(within, np.int64))
    centres = pool if pool.size <= sample else np.sort(np.random.default_rng(0).choice(pool, size=sample, replace=False))
    border = mesh.border_vertices
    base = ~border[centres] & ~unusable_normal_vertices(mesh)[centres]
    balls: dict = {}

    def ball(spec, k) -> tuple[np.ndarray, np.ndarray]:
        """(support sizes, support reaches a border) of the centres in ``spec``'s ball at Rk."""
        rng = resolve(spec, k)
        key = (rng.k, spec.uses_normals, spec.has_support)
        if key not in balls:
            if spec.has_support:
                balls[key] = support_sizes(mesh, ball_radii(mesh, rng, uses_normals=spec.uses_normals), centres, border)
            else:  # a 1-ring formula: lost on or next to a border (its corners' rings are not closed)
                near = border | (mesh.adjacency @ border.astype(np.float64) > 0)
                balls[key] = (np.full(centres.size, np.iinfo(np.int64).max), near[centres])
        return balls[key]

    def can(spec, k, options) -> np.ndarray:
        if refusal(spec, mesh) is not None:
            return np.zeros(centres.size, bool)
        size, reaches_border = ball(spec, k)
        ok = base & (size >= spec.fewest_neighbours(options))
        return ok & ~reaches_border if spec.closed_ring else ok

    out = {}
    for vid in variant_ids:
        v = Variant.from_id(vid)
        opts = dict(v.options)
        fit = opts.pop("normals", None) == "fit"
        fit_range = opts.pop("fit_range", 2)
        ok = can(get_spec(v.method), v.range, opts)
        if fit:
            ok = ok & can(get_spec("jet"), fit_range, {})
        out[vid] = ok
    return centres, out


def rank(pred: dict, shares: dict) -> list[str]:
    """Variant ids best first: those within :data:`VALID_SHARE_SLACK` of the best share by predicted
    error, then the rest by predicted error; variants that estimate no vertex are left out."""
    ids = [v for v in pred if np.isfinite(pred[v]) and shares.get(v, 1.0) > 0]
    if not ids:
        return []
    top = max(shares.get(v, 1.0) for v in ids)
    return sorted(ids, key=lambda v: (shares.get(v, 1.0) < top - VALID_SHARE_SLACK, pred[v]))


def describe_mesh(features: MeshFeatures) -> str:
    """What was measured on a mesh, in words: ``noise about 0.3 of the paper's level, irregular (22
    degrees), density 0.093, polygons, 13 % border``."""
    level = features.noise_level
    noise = "no measurable noise" if level < 0.05 else f"noise about {level:.2g} of the paper's level"
    irr = features.irregularity_deg
    shape = "regular" if irr < 5 else ("mildly irregular" if irr < 12 else "irregular")
    polys = "" if features.triangular else ", polygons"
    border = f", {100 * features.border_share:.0f} % border" if features.border_share >= 0.05 else ""
    return f"{noise}, {shape} ({irr:.0f} degrees), density {features.density:.2g}{polys}{border}"


def table_ranking(mesh: Mesh, *, normals=None, table: dict | None = None, vertices=None) -> tuple:
    """The table's advice for a mesh: its features and every candidate in the table's order.

    Parameters
    ----------
    mesh : Mesh
    normals : (n, 3) array_like, optional
        Vertex normals for the measuring fit; default Max-weighted (the study's).
    table : dict, optional
        A table from :func:`load_table`; default the packaged one.
    vertices : (c,) int64, optional
        Count the valid shares on these vertices (the ones the estimate is wanted at).

    Returns
    -------
    features : MeshFeatures
    ranking : list of Candidate
        By :func:`rank`: coverage first, then the predicted error.
    sharp : float or None
        The ``features`` angle to suggest when the mesh has many sharp edges.

    Raises
    ------
    MeshError
        When the features cannot be measured (no valid fit anywhere) or no candidate applies.
    """
    from ..variants import Variant

    table = load_table() if table is None else table
    features = measure_features(mesh, normals=normals, table=table)
    pred = predict(table, features)
    ids = [v for v in candidates(table, features) if np.isfinite(pred[v])]
    shares = valid_shares(mesh, ids, within=vertices)
    ranking = []
    for vid in rank({v: pred[v] for v in ids}, shares):
        v = Variant.from_id(vid)
        ranking.append(Candidate(v.method, v.range, dict(v.options), float(pred[vid]), shares[vid]))
    if not ranking:
        raise MeshError("cannot advise: no estimator of the table applies to this mesh")
    return features, ranking, _sharp_edge_angle(mesh)


def advise(shape, *, normals=None, table: dict | None = None, check: bool | None = None, vertices=None,
           seed: int = 0) -> Advice:
    """Recommend a whole estimate call for a mesh or point cloud, checked on the input itself.

    See :func:`curv.advice.advising.iter_advise` (the same, step by step with progress and cancel).

    Parameters
    ----------
    shape : Mesh, PointCloud, trimesh.Trimesh, pyvista.PolyData or meshio.Mesh
        Other libraries' meshes are converted by :func:`curv.convert.as_mesh`.
    normals : (n, 3) array_like, optional
        A mesh's vertex normals for the measuring fit; default Max-weighted (the study's).
    table : dict, optional
        A table from :func:`load_table`; default the packaged one.
    check : bool, optional
        Run the self-check (:mod:`curv.advice.check`): True, False (the table's ranking alone), or
        None (default): check unless the input is larger than
        :data:`curv.advice.advising.CHECK_MAX_VERTICES`.
    vertices : (c,) int array_like, optional
        The vertices (points) the estimate is wanted at: the valid shares are counted and the
        check's centres drawn there. Default all.
    seed : int
        Seed of the check's centres and noise.

    Returns
    -------
    Advice

    Raises
    ------
    MeshError
        When the features cannot be measured (no valid fit anywhere).
    """
    from ..core.jit import run_to_end
    from .advising import iter_advise

    return run_to_end(iter_advise(shape, normals=normals, table=table, check=check, vertices=vertices, seed=seed))


def _sharp_edge_angle(mesh: Mesh) -> float | None:
    """The features angle to suggest when the mesh has many sharp edges, else None."""
    from ..core.features import has_many_sharp_edges, suggest_threshold

    return suggest_threshold(mesh) if has_many_sharp_edges(mesh) else None
