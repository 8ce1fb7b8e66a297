"""The advisor's answer for the document's mesh or point cloud, and its features and ranking as text.

``curv.advise`` measures a mesh (noise, irregularity, density, ...), ranks the candidate calls by the
median relative error the paper's study predicts for such a mesh, then checks the first of them on
noisy copies of the mesh's own smooth twin and ranks them by the error measured there (a point
cloud: every candidate is checked). An :class:`AdviceRecord` ties that answer (or the reason there
is none) to the input it was computed for, so that the views never show advice for another input as
current.
"""

from __future__ import annotations

from dataclasses import dataclass

from curv.core import ranges

__all__ = ["AdviceRecord", "FeatureRow", "RankingRow", "feature_rows", "ranking_rows", "polygon_text",
           "percent_text", "check_text", "measured_text", "CLOUD_FEATURE_LABELS"]


@dataclass(frozen=True)
class AdviceRecord:
    """``curv.advise`` run on one mesh of the document: its :class:`curv.Advice` or why it failed.

    Attributes
    ----------
    mesh_serial : int
        :attr:`Document.mesh_serial` of the mesh it was computed for.
    source_label : str
        What that mesh was (``saddle (817 vertices)``, ``part.ply``), to say whose advice it is.
    advice : curv.Advice or None
        None when the advisor could not measure the mesh (see ``error``).
    error : str
        One-line reason when ``advice`` is None, else empty.
    seconds : float
        How long the advisor took.
    """

    mesh_serial: int
    source_label: str
    advice: object = None
    error: str = ""
    seconds: float = float("nan")


@dataclass(frozen=True)
class FeatureRow:
    """One measured feature: its label, its value as text and what it means."""

    label: str
    text: str
    tooltip: str


@dataclass(frozen=True)
class RankingRow:
    """One ranked candidate as shown: estimator, range label, options, valid share, predicted and
    measured median e_rel and their texts.

    ``range`` is None where the call gives a ``radius`` or ``knn`` instead (a point cloud's); the
    measured error is NaN where the check did not measure the call, and ``within_noise`` marks the
    calls the check's copies could not tell from the recommendation.
    """

    method: str
    range: object
    range_label: str
    expected_erel: float
    erel_text: str
    recommended: bool
    options: tuple = ()
    options_text: str = ""
    valid_share: float = 1.0
    valid_text: str = "100 %"
    radius: float | None = None
    knn: int | None = None
    measured_erel: float = float("nan")
    measured_text: str = ""
    within_noise: bool = False

    @property
    def options_short(self) -> str:
        """The options for a narrow table cell: ``deg 4``, ``fit R4`` (normals fitted at R4)."""
        opts = dict(self.options)
        parts = [f"deg {v}" if k == "degree" else f"{k} {v}" for k, v in opts.items()
                 if k not in ("normals", "fit_range")]
        if opts.get("normals") == "fit":
            parts.append(f"fit {ranges.range_label(opts.get('fit_range', 2))}")
        return ", ".join(parts)

    @property
    def label(self) -> str:
        """``jet R4 degree 4``: the whole call for a person."""
        return f"{self.method} {self.range_label}" + (f" {self.options_text}" if self.options_text else "")


def percent_text(fraction: float) -> str:
    """``0.52`` -> ``52 %``, ``0.013`` -> ``1.3 %``: whole percent from 10 % up, one decimal below."""
    value = 100.0 * fraction
    return f"{value:.0f} %" if abs(value) >= 10 else f"{value:.1f} %"


def polygon_text(kinds: dict) -> str:
    """``{3: 1536}`` -> ``1536 triangles``; ``{3: 10, 4: 5000}`` -> ``10 triangles, 5000 quads``."""
    names = {3: "triangles", 4: "quads"}
    parts = [f"{count} {names.get(size, f'{size}-gons')}" for size, count in sorted(kinds.items())]
    return ", ".join(parts) or "no faces"


FEATURE_LABELS = ("Irregularity", "Noise", "Density", "Model residual", "Valence spread", "Curvature spread",
                  "Anisotropy", "Border", "Polygons", "Vertices")
"""The rows of :func:`feature_rows`, in order (the Advice panel lays its form out from them)."""


CLOUD_FEATURE_LABELS = ("Points", "Spacing", "Noise", "Normals", "Rim")
"""The rows of :func:`feature_rows` for a point cloud."""


def _cloud_rows(f) -> list[FeatureRow]:
    noise = ("not measured (no check)" if f.noise != f.noise else
             "below what the twin resolves" if f.noise == 0 else f"{f.noise:.2g} × spacing along the normal")
    return [
        FeatureRow("Points", f"{f.n_points:,}", "Number of points."),
        FeatureRow("Spacing", f"{f.spacing:.3g} (median)",
                   "Median distance to the sixth nearest point: the unit of a point cloud's range Rk, and of the "
                   "candidates' radius (13 spacings is radius = 13 × this)."),
        FeatureRow("Noise", noise,
                   "Noise along the normal measured about the cloud's smooth twin (the leverage-corrected residual "
                   "of its wide polynomial fits), in spacings; the check's noisy copies are given this noise."),
        FeatureRow("Normals", "from the file" if f.has_normals else f"none (jet fits, oriented {f.orientation_words})",
                   "Where the normals come from: the file's, or fitted (jet at R2, oriented up on a georeferenced "
                   "scan, else from each part's top). With the file's "
                   "normals the candidates run with them and with fitted ones."),
        FeatureRow("Rim", f"{percent_text(f.border_share)} of the points",
                   "Share of the points on the rim of an open scan (or repeats of a point): no value there."),
    ]


def feature_rows(features) -> list[FeatureRow]:
    """The measured features of a :class:`curv.advice.advisor.MeshFeatures`, in the order a person reads them.

    Parameters
    ----------
    features : curv.advice.advisor.MeshFeatures or curv.advice.clouds.CloudFeatures

    Returns
    -------
    list of FeatureRow
        A point cloud's: :data:`CLOUD_FEATURE_LABELS`. A mesh's: irregularity, noise, density, model residual, valence spread, curvature spread, anisotropy,
        border, polygons, vertices. A measure's tooltip says whether the packaged table predicts
        with it (:func:`curv.advice.advisor.kernel_axes`).
    """
    from curv.advice.advisor import FIT_METHOD, FIT_RANGE, kernel_axes, load_table
    from curv.estimators import ESTIMATORS
    from curv.variants import NOISE_FRACTION

    if not hasattr(features, "irregularity_deg"):  # a point cloud's (curv.advice.clouds.CloudFeatures)
        return _cloud_rows(features)
    f = features
    axes = {column for column, _how, _scale in kernel_axes(load_table())}

    def axis(column: str) -> str:
        return (" One of the table's axes: the prediction weighs it." if column in axes
                else " Measured, not one of the table's axes.")

    fit = f"{FIT_METHOD} {ranges.range_label(FIT_RANGE)}"
    closed = ", ".join(name for name, spec in ESTIMATORS.items() if spec.closed_ring)
    return [
        FeatureRow("Irregularity", f"{f.irregularity_deg:.1f}° RMS from 60°",
                   "The paper's irregularity (§5.1): RMS deviation of every triangle angle from 60°, measured in "
                   "3D on the mesh as given (polygons fan-triangulated) and corrected for the jitter noise adds. "
                   "0° is a regular tessellation; the study goes up to 25°."),
        FeatureRow("Noise", f"{f.noise:.2g} × mean edge ({percent_text(f.noise_level)} of the paper's level)",
                   "Estimated standard deviation of the vertex noise per coordinate, in mean edge lengths "
                   f"(the robust spread of the residuals of a local quadric fit, {fit}). In brackets as a share "
                   f"of the paper's 100 % noise level, {NOISE_FRACTION:g} × the mean edge."),
        FeatureRow("Density", f"{f.density:.2g} (mean edge × |k1|+|k2|)",
                   "Dimensionless resolution: the mean edge length times the median of |k1| + |k2| of a local "
                   f"quadratic fit ({fit}). Small: finely sampled for its curvature; a sphere of radius r meshed "
                   "with edges h gives about 2 h / r. Noise inflates it."),
        FeatureRow("Model residual", f"{f.residual_ratio:.2g} (quartic / quadric fit residual)",
                   "Median ratio of what a quartic and a quadric height fit over the R3 ball leave over, at up "
                   "to 1000 sampled vertices: about 1 where noise dominates the residuals, near 0 where the "
                   "surface's own shape (coarse sampling, strong curvature) does. It tells a noise-free coarse "
                   "mesh from a noisy one, which the noise measure alone confuses." + axis("residual_ratio")),
        FeatureRow("Valence spread", f"{f.valence_sd:.2f}",
                   "Standard deviation of the vertex valence off the border: 0 on a regular grid, a little above "
                   "on a geodesic sphere, larger on a scan." + axis("valence_sd")),
        FeatureRow("Curvature spread", f"{f.curvature_spread:.2f}",
                   f"Interquartile range of log(|k1| + |k2|) of the same fit ({fit}): 0 on a sphere, larger where "
                   "the surface bends unevenly." + axis("curvature_spread")),
        FeatureRow("Anisotropy", f"{f.anisotropy:.2f}",
                   f"Median of (k1 - k2) / (|k1| + |k2|) of the same fit ({fit}): 0 where the surface is umbilic "
                   "(a sphere), up to 1 where it bends one way only (a cylinder)." + axis("anisotropy")),
        FeatureRow("Border", f"{percent_text(f.border_share)} of the vertices",
                   "Share of the vertices on a border. Border vertices are invalid for every estimator; the "
                   f"closed-ring estimators ({closed}) also lose every vertex whose support reaches one."
                   + axis("border_share")),
        FeatureRow("Polygons", polygon_text(f.polygon_kinds),
                   "Face sizes. On a mesh with other polygons than triangles the triangle-only estimators "
                   "are left out of the ranking."),
        FeatureRow("Vertices", f"{f.n_vertices} (mean edge {f.mean_edge:.3g})",
                   "Vertex count, and the mean edge length in mesh units (the unit of the noise)."),
    ]


def measured_text(candidate) -> str:
    """``0.036 ×1.24`` (the measured median e_rel and its spread over the copies), ``0.036`` with one
    copy, or empty where the check did not measure the call."""
    m = candidate.measured
    if m is None or not m.ok:
        return ""
    spread = f" ×{m.spread:.2f}" if m.spread == m.spread else ""
    return f"{m.erel:.3g}{spread}"


def ranking_rows(advice) -> list[RankingRow]:
    """The ranking of a :class:`curv.Advice`, best first, the recommendation marked.

    Parameters
    ----------
    advice : curv.Advice

    Returns
    -------
    list of RankingRow
        In the advisor's order (the candidates that leave the fewest vertices invalid first; the
        checked ones by their measured error, then the others by the predicted one); exactly the
        first row is ``recommended``.
    """
    rows = []
    for i, c in enumerate(advice.ranking):
        opts = dict(c.options)
        radius, knn = opts.pop("radius", None), opts.pop("knn", None)
        if knn is not None:
            label = ranges.Range(knn=int(knn)).label
        elif radius is not None:
            label = ranges.Range(radius=float(radius)).label
        else:
            label = ranges.range_label(c.range)
        from curv.variants import Variant

        options_text = Variant(c.method, 2, options=opts).options_label if opts else ""
        expected = float(c.expected_erel)
        rows.append(RankingRow(c.method, c.range, label, expected, "" if expected != expected else f"{expected:.3g}",
                               i == 0, tuple(sorted(opts.items())), options_text, float(c.valid_share),
                               valid_percent_text(c.valid_share), radius=radius, knn=knn,
                               measured_erel=c.measured_erel if c.measured is not None and c.measured.ok
                               else float("nan"), measured_text=measured_text(c), within_noise=c.within_noise))
    return rows


def check_text(advice) -> str:
    """What the self-check did, in one line: ``checked 6 calls on 3 noisy copies of the mesh's smooth twin
    (64 centres each, noise 0.0021 along the normal) in 1.2 s``, or why it did not run."""
    report = advice.check
    if report is None:
        return advice.note or "not checked"
    noise = (f"noise {report.noise:.2g} along the normal" if report.noise > 0 else
             f"noise below what the twin resolves (< {report.noise_bound:.2g})")
    what = "point cloud" if advice.is_cloud else "mesh"
    return (f"checked {len(report.measured)} calls on {report.copies} noisy copies of the {what}'s smooth twin "
            f"({report.centres} centres each, {noise}) in {report.seconds:.1f} s")


def valid_percent_text(share: float) -> str:
    """``1.0`` -> ``100 %``, ``0.871`` -> ``87 %``, ``0.996`` -> ``99.6 %`` (never rounds up to 100)."""
    value = 100.0 * share
    if value >= 100.0:
        return "100 %"
    return f"{value:.0f} %" if value < 99.5 else f"{min(value, 99.9):.1f} %"
