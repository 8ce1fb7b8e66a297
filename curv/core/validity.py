"""Why a vertex has no trustworthy estimate: one reason code per vertex."""

from __future__ import annotations

import enum

import numpy as np

__all__ = ["Reason", "describe_reasons", "reason_legend"]


class Reason(enum.IntEnum):
    """Per-vertex reason codes stored in :attr:`curv.Curvature.reason` (uint8).

    ``OK`` is the only code with ``valid == True``. When several apply, the first one found wins
    in the order the estimator checks them; the code is for diagnosis, the mask is the contract.
    """

    OK = 0
    BORDER = 1
    """On a border, or the support reaches one, for an estimator that needs a closed 1-ring."""
    TOO_FEW_NEIGHBOURS = 2
    """Fewer neighbours in range than the fit has unknowns."""
    SINGULAR = 3
    """The least-squares system (or the tensor) is numerically singular, or ill-conditioned at the
    data's resolution (on a point cloud: a support along a line, or only a few steps of the grid
    its coordinates are stored on wide; :mod:`curv.point_normals`)."""
    DEGENERATE = 4
    """Isolated vertex, zero-area faces around it, or no usable normal."""
    NONMANIFOLD = 5
    """On a non-manifold edge or vertex, for an estimator that needs a disc-like 1-ring."""
    NOT_COMPUTED = 6
    """The estimate was not computed here (e.g. the values were smoothed from invalid neighbours,
    or the vertex lies outside the region asked for with ``vertices=``)."""
    FEATURE = 7
    """On a feature edge (a crease sharper than the ``features`` angle) or a corner of them: the
    smooth curvature is undefined there (:mod:`curv.core.features`)."""
    ORIENTATION = 8
    """A point-cloud normal whose orientation its neighbourhood cannot decide (a thin sheet, a fold,
    a sparse spot; :mod:`curv.point_normals`): no sign is guessed, so there is no estimate."""


def describe_reasons(reason: np.ndarray) -> dict[str, int]:
    """Count vertices per reason.

    Parameters
    ----------
    reason : (n,) uint8
        Reason codes.

    Returns
    -------
    dict
        ``{reason name: count}`` for every code that occurs, ``OK`` first.
    """
    codes, counts = np.unique(np.asarray(reason, dtype=np.uint8), return_counts=True)
    return {Reason(int(c)).name: int(k) for c, k in zip(codes, counts)}


def reason_legend() -> str:
    """``reason codes: 0 OK, 1 BORDER, ...``: what the uint8 ``reason`` field of an export means."""
    return "reason codes: " + ", ".join(f"{int(r)} {r.name}" for r in Reason)
