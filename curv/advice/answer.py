"""The advisor's answer: ranked candidate calls, what was predicted and what was measured.

A :class:`Candidate` is one whole :func:`curv.estimate` call. On a mesh it carries the error the
study's table predicts for it; where the self-check ran (:mod:`curv.advice.check`) it also carries
the error measured on noisy copies of the input's smooth twin, with the spread over the copies.
An :class:`Advice` is the ranking and the recommendation, with what was measured on the input and
a report of the check (or why it did not run).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

__all__ = ["Advice", "Candidate", "call_text"]


def _range_words(key: str, value) -> str:
    if key == "radius":
        return f"radius {value:.4g}"
    if key == "knn":
        return f"knn {value}"
    return f"R{value:g}" if isinstance(value, (int, float)) else f"R{value}"


def call_text(kwargs: dict, name: str = "mesh") -> str:
    """``curv.estimate(mesh, method='jet', range=4, degree=4)``: a call's keyword arguments as Python."""
    return f"curv.estimate({name}, " + ", ".join(f"{k}={v!r}" for k, v in kwargs.items()) + ")"


@dataclass(frozen=True)
class Candidate:
    """One ranked candidate: a whole :func:`curv.estimate` call and what the advisor knows of it.

    Attributes
    ----------
    method : str
        Registry name.
    range : int, float or None
        k of Rk; None where the call gives ``radius`` or ``knn`` (in :attr:`options`).
    options : dict
        The other keyword arguments of the call: an estimator option (``{"degree": 4}``), the
        fitted normals (``{"normals": "fit", "fit_range": 4}``), a point cloud's ``radius`` or
        ``knn``; empty for the defaults.
    expected_erel : float
        Median e_rel the study's table predicts on the vertices it estimates (NaN where no table
        applies: point clouds).
    valid_share : float
        Share of the input's vertices (points) it gives a value at.
    measured : curv.advice.check.Measured or None
        What the self-check measured (None where the call was not checked).
    within_noise : bool
        Measured and not clearly worse than the recommendation: on at least one of the noisy copies
        its median error was at or below the recommendation's (always False for the recommendation).
    """

    method: str
    range: object
    options: dict
    expected_erel: float
    valid_share: float = 1.0
    measured: object = None
    within_noise: bool = False

    @property
    def variant(self):
        """The :class:`curv.variants.Variant` of a call at a range (a mesh's candidates)."""
        from ..variants import Variant

        return Variant(self.method, self.range, options=self.options)

    @property
    def key(self) -> str:
        """A stable id: the variant id (``jet:R4;degree=4``) or, for a radius or knn call, the same
        form with its support first (``jet:radius=0.013;degree=4``)."""
        if self.range is not None:
            return self.variant.id
        opts = sorted(self.options.items(), key=lambda kv: (kv[0] not in ("radius", "knn"), kv[0]))
        return self.method + ":" + ";".join(f"{k}={v:.6g}" if isinstance(v, float) else f"{k}={v}"
                                            for k, v in opts)

    @property
    def kwargs(self) -> dict:
        """``curv.estimate(shape, **candidate.kwargs)``."""
        if self.range is not None:
            return self.variant.kwargs
        return {"method": self.method, **self.options}

    @property
    def label(self) -> str:
        """``jet R4 degree 4``, ``mru R3 normals fit R4``, ``jet radius 0.013 degree 4 width adaptive``."""
        if self.range is not None:
            extra = self.variant.options_label
            if self.options.get("normals") == "pca":
                extra = ", ".join(w for w in (extra.replace("normals pca", "").strip(", "), "normals pca") if w)
            return f"{self.method} R{self.range:g}" + (f" {extra}" if extra else "")
        support = [_range_words(k, v) for k, v in self.options.items() if k in ("radius", "knn")]
        rest = {k: v for k, v in self.options.items() if k not in ("radius", "knn")}
        words = [f"{k} {v}" for k, v in rest.items() if k not in ("normals", "fit_range")]
        if rest.get("normals") == "fit":
            words.append(f"normals fit R{rest.get('fit_range', 2)}")
        elif rest.get("normals") == "pca":
            words.append("normals pca")
        return " ".join([self.method, *support, *words])

    @property
    def call(self) -> str:
        """The call as Python text: ``curv.estimate(mesh, method='jet', range=4, degree=4)``."""
        return call_text(self.kwargs)

    @property
    def measured_erel(self) -> float:
        """The measured median e_rel (NaN where not checked)."""
        return float(self.measured.erel) if self.measured is not None else math.nan

    @property
    def realized_erel(self) -> float:
        """The realized score: the call's error on the input itself against its smooth twin (NaN where
        not scored; :func:`curv.advice.ranking.realized_score`)."""
        from .ranking import realized_score

        return realized_score(self.measured)

    @property
    def measured_spread(self) -> float:
        """The measure's spread over the copies, a factor (NaN where not checked)."""
        return float(self.measured.spread) if self.measured is not None else math.nan

    def as_dict(self) -> dict:
        return {"method": self.method, "range": self.range, "options": dict(self.options),
                "expected_erel": self.expected_erel, "valid_share": self.valid_share, "label": self.label,
                "kwargs": self.kwargs, "key": self.key,
                "measured": None if self.measured is None else self.measured.as_dict(),
                "realized_erel": self.realized_erel,
                "within_noise": self.within_noise}


@dataclass(frozen=True)
class Advice:
    """The advisor's answer for one mesh or point cloud.

    Attributes
    ----------
    features : MeshFeatures or CloudFeatures
        What was measured on the input.
    ranking : list of Candidate
        Every candidate, best first: those that leave at most
        :data:`curv.advice.shares.VALID_SHARE_SLACK` more of the input invalid than the
        best-covering one, then the others; within each, the checked calls by their measured error
        (:mod:`curv.advice.ranking`), then the others by predicted error.
    method : str
        Recommended estimator (registry name).
    range : int, float or None
        Its range k of Rk (None for a radius or knn call).
    expected_erel : float
        Predicted median e_rel of the recommendation (NaN on point clouds).
    why : str
        One line for a person.
    suggested_features : float or None
        When the mesh has many sharp edges (:func:`curv.core.features.has_many_sharp_edges`), a
        ``features`` angle that separates its creases from its smooth edges
        (:func:`curv.core.features.suggest_threshold`); the study's meshes are smooth, so the ranking
        assumes the creases are handled that way.
    options : dict
        The recommendation's other keyword arguments (see :class:`Candidate`).
    valid_share : float
        Share of the vertices the recommendation estimates.
    check : curv.advice.check.CheckReport or None
        The self-check's report; None where it did not run (see :attr:`note`).
    note : str
        Why the ranking is the table's alone, when it is (``check=False``, a large input, no vertex
        to check at), else empty.
    ranked_by : str
        What decided the recommendation, in words (:func:`curv.advice.ranking.ranked_by`).
    """

    features: object
    ranking: list
    method: str
    range: object
    expected_erel: float
    why: str
    suggested_features: float | None = None
    options: dict = field(default_factory=dict)
    valid_share: float = 1.0
    check: object = None
    note: str = ""
    ranked_by: str = ""

    @property
    def best(self) -> Candidate:
        """The recommendation (the first of :attr:`ranking`)."""
        return self.ranking[0]

    @property
    def checked(self) -> bool:
        """Whether the ranking was checked on the input's twin."""
        return self.check is not None

    @property
    def kwargs(self) -> dict:
        """The whole recommended call: ``curv.estimate(mesh, **advice.kwargs)`` (method, range,
        options, and ``features=`` when the mesh has many sharp edges)."""
        out = dict(self.best.kwargs)
        if self.suggested_features is not None:
            out["features"] = self.suggested_features
        return out

    @property
    def call(self) -> str:
        """The recommended call as Python text (see :attr:`kwargs`)."""
        return call_text(self.kwargs, "cloud" if self.is_cloud else "mesh")

    @property
    def is_cloud(self) -> bool:
        return type(self.features).__name__ == "CloudFeatures"

    @property
    def label(self) -> str:
        """The recommendation for a person: ``jet R4 degree 4``."""
        return self.best.label

    @property
    def ties(self) -> list:
        """The candidates measured within noise of the recommendation."""
        return [c for c in self.ranking if c.within_noise]

    def as_dict(self) -> dict:
        """A JSON-ready dict (``features``, ``ranking`` as a list of dicts, the recommendation and its
        whole call as ``kwargs``, the check's report)."""
        f = asdict(self.features)
        if "polygon_kinds" in f:
            f["polygon_kinds"] = {str(k): v for k, v in self.features.polygon_kinds.items()}
        if hasattr(self.features, "noise_level"):
            f["noise_level"] = self.features.noise_level
        return {
            "method": self.method, "range": self.range, "options": dict(self.options), "kwargs": self.kwargs,
            "call": self.call, "label": self.label, "expected_erel": self.expected_erel,
            "valid_share": self.valid_share, "why": self.why, "suggested_features": self.suggested_features,
            "features": f, "checked": self.checked, "note": self.note, "ranked_by": self.ranked_by,
            "check": None if self.check is None else self.check.as_dict(),
            "ranking": [c.as_dict() for c in self.ranking],
        }
