"""Exceptions raised by curv for bad input."""

from __future__ import annotations

__all__ = ["CurvError", "MeshError", "LoadError", "EstimatorError"]


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
