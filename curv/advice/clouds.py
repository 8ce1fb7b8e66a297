"""Advice on point clouds: the candidate calls, what is measured on the cloud, where a call gives a value.

No study table covers point clouds, so every candidate is checked on the cloud's own twin
(:mod:`curv.advice.check`); without the check (``check=False``) the candidates keep the prior order
below, from the point-cloud accuracy benchmark (docs/ACCURACY.md): the degree-4 jet with the
adaptive width over 13 spacings first (it chooses its own width per point, the best choice there
when the noise is not known), then the calls that win on clean clouds, then the others.

The candidates cover what a user of point clouds chooses (issue 35): the range in each point's
spacings (``range=``), a ball of one radius for every point (``radius=``, in multiples of the
cloud's median spacing), the k nearest points (``knn=``), the jet's degree, its weights and its
adaptive width, and the source of the normals (the file's, jet fits at R2 or R4, or PCA).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.pointcloud import PointCloud
from .answer import Candidate

__all__ = ["CloudFeatures", "CLOUD_CALLS", "cloud_candidates", "cloud_features", "usable_points", "describe_cloud"]

CLOUD_CALLS = (
    ("jet", {"radius": 13.0, "degree": 4, "width": "adaptive"}),
    ("jet", {"range": 3, "degree": 4}),
    ("jet", {"range": 4, "degree": 4}),
    ("jet", {"range": 2}),
    ("mru", {"range": 2}),
    ("qs", {"range": 3}),
    ("jet", {"range": 6, "degree": 3}),
    ("jet", {"range": 8, "weights": "smooth"}),
    ("jet", {"radius": 13.0, "degree": 4}),
    ("jet", {"radius": 13.0, "weights": "smooth"}),
    ("jet", {"knn": 40}),
    ("mru", {"range": 4, "normals": "fit", "fit_range": 4}),
    ("qs", {"range": 4, "normals": "fit", "fit_range": 4}),
    ("jet", {"range": 3, "degree": 4, "normals": "pca"}),
)
"""The candidate calls on a point cloud, in their prior order: a ``radius`` is in multiples of the
cloud's median spacing (made absolute for each cloud); calls without ``normals`` use the file's
normals where the cloud has them, else jet fits at R2 (the library's default)."""


@dataclass(frozen=True)
class CloudFeatures:
    """What the advisor measured on a point cloud.

    Attributes
    ----------
    n_points : int
    spacing : float
        Median point spacing (the distance to the sixth nearest point: the range unit).
    border_share : float
        Share of the points on the rim of an open scan.
    has_normals : bool
        Whether the cloud brought its own normals.
    noise : float
        Noise along the normal measured about the cloud's smooth twin, in spacings (NaN where the
        check did not run; 0 where it is below what the twin resolves).
    orientation : str
        The rule that orients the normals fitted to a cloud without its own
        (:func:`curv.point_normals.default_orientation`: ``"up"`` on a georeferenced scan, else ``"top"``).
    """

    n_points: int
    spacing: float
    border_share: float
    has_normals: bool
    noise: float = float("nan")
    orientation: str = "top"

    @property
    def orientation_words(self) -> str:
        """The orientation rule in the summaries' words."""
        from ..point_normals.orientation import describe_orientation

        return describe_orientation(self.orientation)

    @property
    def n_vertices(self) -> int:
        return self.n_points


def usable_points(cloud: PointCloud) -> np.ndarray:
    """(n,) bool: points a call can give a value at: not on the rim of an open scan, not a repeat of
    an earlier point (the library's own rules, :func:`curv.point_normals.border_points`)."""
    from ..point_normals import border_points

    return ~border_points(cloud) & ~cloud.coincident_points & ~cloud.isolated_vertices


def cloud_features(cloud: PointCloud, usable: np.ndarray) -> CloudFeatures:
    """:class:`CloudFeatures` without the noise (the check measures it)."""
    from ..core.ranges import point_spacing
    from ..point_normals.orientation import default_orientation

    spacing = point_spacing(cloud)
    finite = spacing[np.isfinite(spacing)]
    return CloudFeatures(n_points=cloud.n_points, spacing=float(np.median(finite)) if finite.size else float("nan"),
                         border_share=float(np.mean(~usable)) if usable.size else 0.0,
                         has_normals=cloud.normals is not None, orientation=default_orientation(cloud))


def cloud_candidates(cloud: PointCloud, features: CloudFeatures, share: float) -> list:
    """Every candidate call on ``cloud`` in the prior order, a radius made absolute.

    Where the cloud has its own normals, the calls that fit theirs run with the file's too.
    """
    out = []
    for method, options in CLOUD_CALLS:
        opts = dict(options)
        if "radius" in opts:
            opts["radius"] = float(opts["radius"] * features.spacing)
        rng = opts.pop("range", None)
        out.append(Candidate(method, rng, opts, float("nan"), share))
        if features.has_normals and "normals" not in opts:
            out.append(Candidate(method, rng, {**opts, "normals": "fit"}, float("nan"), share))
    return out


def describe_cloud(features: CloudFeatures) -> str:
    """What was measured on a cloud, in words."""
    noise = ("noise not measured" if not np.isfinite(features.noise) else
             "no measurable noise" if features.noise == 0 else
             f"noise {features.noise:.2g} spacings")
    normals = "normals from the file" if features.has_normals else "no normals (fitted)"
    border = f", {100 * features.border_share:.0f} % on the rim" if features.border_share >= 0.005 else ""
    return f"{features.n_points:,} points, spacing {features.spacing:.3g}, {noise}, {normals}{border}"
