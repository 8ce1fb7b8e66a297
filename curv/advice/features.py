"""The advisor's measures of a mesh: noise, irregularity, density, and its shape and tessellation.

Every measure is taken the same way on the user's mesh and on every mesh of the table
(:mod:`curv.advice.prediction`), so a bias of a measure cancels instead of misplacing the mesh;
the noise and irregularity are calibrated with the table's ``calibration``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.errors import MeshError
from ..core.mesh import Mesh

__all__ = ["MeshFeatures", "FIT_METHOD", "FIT_RANGE", "SHAPE_MEASURES", "RESIDUAL_MEASURES", "polygon_kinds",
           "fan_triangles", "angle_deviation_deg", "raw_measures", "residual_measures", "shape_measures",
           "calibrate_noise", "calibrate_irregularity", "measure_features", "describe_mesh"]

FIT_METHOD = "qs"
FIT_RANGE = 3
"""The local fit the noise and density measures use: the quadratic height fit at R3 (it works on
polygons and at borders, and over R3 its curvature is not yet dominated by the noise it measures)."""

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
    if table is None:
        from .prediction import load_table

        table = load_table()
    raw = raw_measures(mesh, normals=normals)
    cal = table["calibration"]
    noise = calibrate_noise(raw["noise_raw"], cal, raw["density"])
    irr = calibrate_irregularity(raw["irregularity_raw_deg"], noise, cal)
    return MeshFeatures(irregularity_deg=irr, noise=noise, **raw)



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
