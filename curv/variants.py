"""What the study and the advisor both name: estimator variants and the paper's noise unit.

A *variant* is an estimator at a range with one of the paper's smoothing modes (``mru:R2``,
``mru:R2SM``), and optionally the documented options of :func:`curv.estimate` that change the
result (``jet:R4;degree=4``, ``mru:R3;normals=fit;fit_range=4``). The study evaluates variants and the advisor ranks them, so they live here, below
both, and the advisor (a library feature) does not depend on the study.
"""

from __future__ import annotations

from dataclasses import dataclass

from .api import Smoothing
from .core.ranges import canonical_k, parse_range, range_label

__all__ = ["NOISE_FRACTION", "SMOOTHING_SUFFIX", "Variant", "short_name", "OPTION_SEPARATOR"]

OPTION_SEPARATOR = ";"
"""Separates the options in a variant id: ``jet:R4;degree=4``."""

NOISE_FRACTION = 0.1
"""The paper's 100 % noise level: standard deviation per coordinate = 10 % of the mean edge length."""

SMOOTHING_SUFFIX = {Smoothing.NONE: "", Smoothing.MESH: "SM", Smoothing.VALUES: "SV"}
"""The paper's variant suffix of each smoothing (R2SM, R2SV); :class:`curv.api.Smoothing` is the one enum."""

_SHORT = {"meyer": "My"}
"""Display names that are not simply the upper-cased registry name (the paper's abbreviations)."""


def short_name(method: str) -> str:
    """The paper's abbreviation of an estimator: ``"mru" -> "MRU"``, ``"meyer" -> "My"``."""
    return _SHORT.get(method, method.upper())


@dataclass(frozen=True, order=True)
class Variant:
    """One evaluated estimator configuration: a registry name, a range and a smoothing mode.

    ``id`` (``"mru:R2"``, ``"mru:R2SM"``, ``"jet:R4;degree=4"``) is the key stored in the results;
    ``label`` (``"MRU (R2SM)"``, ``"JET (R4, degree 4)"``) is for tables and figures. The range is
    written and read by :mod:`curv.core.ranges`. ``options`` are keyword arguments of
    :func:`curv.estimate` as sorted ``(name, value)`` pairs: an estimator option
    (``("degree", 4)``) or the fitted normals (``("fit_range", 4), ("normals", "fit")``).
    """

    method: str
    range: int
    smooth: Smoothing = Smoothing.NONE
    options: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "options", tuple(sorted((str(k), v) for k, v in dict(self.options).items())))

    @property
    def kwargs(self) -> dict:
        """The whole call: ``curv.estimate(mesh, **variant.kwargs)``."""
        out = {"method": self.method, "range": self.range}
        if self.smooth is not Smoothing.NONE:
            out["smooth"] = self.smooth.value
        return {**out, **dict(self.options)}

    @property
    def options_label(self) -> str:
        """``degree 4``, ``normals fit R4``, or empty: the options for a person."""
        opts = dict(self.options)
        parts = [f"{k} {v}" for k, v in opts.items() if k not in ("normals", "fit_range")]
        if opts.get("normals") == "fit":
            parts.append(f"normals fit {range_label(opts.get('fit_range', 2))}")
        return ", ".join(parts)

    @property
    def range_label(self) -> str:
        return f"{range_label(self.range)}{SMOOTHING_SUFFIX[self.smooth]}"

    @property
    def id(self) -> str:
        opts = "".join(f"{OPTION_SEPARATOR}{k}={v}" for k, v in self.options)
        return f"{self.method}:{self.range_label}{opts}"

    @property
    def label(self) -> str:
        extra = f", {self.options_label}" if self.options else ""
        return f"{short_name(self.method)} ({self.range_label}{extra})"

    @classmethod
    def from_id(cls, text: str) -> "Variant":
        """Inverse of :attr:`id`."""
        method, _, rest = text.partition(":")
        rest, *opts = rest.split(OPTION_SEPARATOR)
        options = tuple((k.strip(), _option_value(v.strip())) for k, _, v in (o.partition("=") for o in opts))
        rest = rest.strip().upper()
        smooth = Smoothing.NONE
        for s in (Smoothing.MESH, Smoothing.VALUES):
            if rest.endswith(SMOOTHING_SUFFIX[s]):
                smooth, rest = s, rest[: -len(SMOOTHING_SUFFIX[s])]
        return cls(method, canonical_k(parse_range(rest)), smooth, options)


def _option_value(text: str):
    """An option value of a variant id: an int where it is one (``4``), else the text (``fit``)."""
    try:
        return int(text)
    except ValueError:
        return text
