"""The vocabulary of the paper's claims checked against measured data (:mod:`curv.study.claims`):
a :class:`Claim`, its :class:`Verdict` and :class:`Status`, and the small helpers every check
uses to word its numbers.
"""

from __future__ import annotations

import enum
import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .analysis import Analysis

__all__ = ["Status", "Verdict", "Claim", "share_verdict", "percent", "number", "not_tested", "at_highest_noise"]


class Status(str, enum.Enum):
    AGREES = "agrees"
    PARTLY = "partly"
    DISAGREES = "disagrees"
    NOT_TESTED = "not tested"


@dataclass
class Verdict:
    status: Status
    measured: str
    """The numbers that decided the verdict (Markdown)."""


@dataclass(frozen=True)
class Claim:
    id: str
    source: str
    statement: str
    test: str
    check: Callable[[Analysis], Verdict]


def share_verdict(hits: int, total: int, *, agree: float = 2 / 3, partly: float = 1 / 3) -> Status:
    """AGREES when at least ``agree`` of ``total`` cases hit, PARTLY from ``partly``, else DISAGREES
    (NOT_TESTED without cases)."""
    if total == 0:
        return Status.NOT_TESTED
    share = hits / total
    return Status.AGREES if share >= agree else Status.PARTLY if share >= partly else Status.DISAGREES


def percent(x: float) -> str:
    """``x`` as a whole percentage, ``n/a`` when not finite."""
    return "n/a" if not np.isfinite(x) else f"{100 * x:.0f}%"


def number(x: float) -> str:
    """``x`` to three significant digits, ``n/a`` when not finite."""
    return "n/a" if not np.isfinite(x) else f"{x:.3g}"


def not_tested(reason: str) -> Verdict:
    """The verdict of a claim the data cannot decide, and why."""
    return Verdict(Status.NOT_TESTED, reason)


def at_highest_noise(claim: Callable[[Analysis, float], Verdict]) -> Callable[[Analysis], Verdict]:
    """A claim about the study's highest noise level: ``claim(an, hi)``, not tested unless ``hi > 0``."""
    @functools.wraps(claim)
    def check(an: Analysis) -> Verdict:
        return claim(an, an.noise_max) if an.noise_max > 0.0 else not_tested("needs noisy meshes")
    return check
