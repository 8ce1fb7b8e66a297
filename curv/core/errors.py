"""Exceptions raised by curv for bad input, and the warnings it gives about results."""

from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

__all__ = ["CurvError", "MeshError", "LoadError", "EstimatorError", "CurvWarning", "RadiusWarning", "warn"]


class CurvError(Exception):
    """Base class of every error curv raises on purpose."""


class MeshError(CurvError, ValueError):
    """The mesh data are malformed, or unfit for the requested operation.

    The message names what is wrong and where, e.g. ``"vertex 17 has a NaN coordinate"``.
    """


class LoadError(CurvError, OSError):
    """A file could not be read as a mesh; the message names the file and the problem."""


class EstimatorError(CurvError, ValueError):
    """Unknown estimator or range, or an option the estimator does not support."""


class CurvWarning(UserWarning):
    """Base class of the warnings curv gives: the call ran, but its result is probably not what was meant."""


class RadiusWarning(CurvWarning):
    """A ``radius=`` below the input's spacing, or one that leaves most points without an estimate
    (too few neighbours in the ball); the message names the radius and the median spacing."""


_PACKAGE = str(Path(__file__).resolve().parents[1]) + os.sep


def warn(message: str, category: type[CurvWarning]) -> None:
    """``warnings.warn`` attributed to the caller's own line: the first frame outside curv.

    curv's entry points are generators driven through several of its own frames, so a fixed
    ``stacklevel`` would name a different line for ``curv.estimate`` and for ``curv.iter_estimate``.
    """
    level, frame = 2, sys._getframe(1)  # stacklevel 2: warn's caller
    while frame is not None and str(Path(frame.f_code.co_filename).resolve()).startswith(_PACKAGE):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)
