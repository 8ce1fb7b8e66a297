"""What the study and the advisor both name: estimator variants and the paper's noise unit.

A *variant* is an estimator at a range with one of the paper's smoothing modes (``mru:R2``,
``mru:R2SM``). The study evaluates variants and the advisor ranks them, so they live here, below
both, and the advisor (a library feature) does not depend on the study.
"""

from __future__ import annotations

from dataclasses import dataclass

from .api import Smoothing
from .ranges import canonical_k, parse_range, range_label

__all__ = ["NOISE_FRACTION", "SMOOTHING_SUFFIX", "Variant", "short_name"]

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

    ``id`` (``"mru:R2"``, ``"mru:R2SM"``) is the key stored in the results; ``label``
    (``"MRU (R2SM)"``) is for tables and figures. The range is written and read by
    :mod:`curv.ranges`.
    """

    method: str
    range: int
    smooth: Smoothing = Smoothing.NONE

    @property
    def range_label(self) -> str:
        return f"{range_label(self.range)}{SMOOTHING_SUFFIX[self.smooth]}"

    @property
    def id(self) -> str:
        return f"{self.method}:{self.range_label}"

    @property
    def label(self) -> str:
        return f"{short_name(self.method)} ({self.range_label})"

    @classmethod
    def from_id(cls, text: str) -> "Variant":
        """Inverse of :attr:`id`."""
        method, _, rest = text.partition(":")
        rest = rest.strip().upper()
        smooth = Smoothing.NONE
        for s in (Smoothing.MESH, Smoothing.VALUES):
            if rest.endswith(SMOOTHING_SUFFIX[s]):
                smooth, rest = s, rest[: -len(SMOOTHING_SUFFIX[s])]
        return cls(method, canonical_k(parse_range(rest)), smooth)
