"""Why a vertex has no trustworthy estimate: one reason code per vertex, and the one order of precedence.

The codes are :class:`Reason`; the kernels read them as the uint8 constants below (:data:`OK`,
:data:`BORDER`, ...), defined here once. When several causes apply to a vertex the most
fundamental one names it: NONMANIFOLD > DEGENERATE > BORDER > SINGULAR, else OK
(:func:`precedence`, the one owner of that order). It serves the 1-ring estimators
(:func:`curv.estimators._triangle_corners.ring_reason`), the ball supports
(:func:`curv.estimators._ball_clipping.support_reason`) and the flags an estimate's input carries
(:func:`mark_ok_rows`, :func:`curv.estimate_finish.finish`).

How the other codes compose with it:

- ``TOO_FEW_NEIGHBOURS`` is a fit's own outcome (:func:`curv.estimators._local_fit.finish_fit`,
  the jet): a fit checks it before ``SINGULAR`` (a system with too few rows is not solved), and it
  stands where the precedence's SINGULAR would; the input's flags mark only the rows a fit left OK.
- ``FEATURE`` (a crease) and the root causes an input forces (an isolated vertex DEGENERATE, an
  undecided orientation ``ORIENTATION``) override whatever the estimator found;
  ``NOT_COMPUTED`` is a region's outside.
"""

from __future__ import annotations

import enum

import numpy as np

from .jit import jit_inlined, jit_parallel, prange

__all__ = ["Reason", "describe_reasons", "reason_legend", "precedence", "mark_ok_rows", "PRECEDENCE",
           "OK", "BORDER", "TOO_FEW", "SINGULAR", "DEGENERATE", "NONMANIFOLD", "NOT_COMPUTED", "FEATURE",
           "ORIENTATION"]


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


OK = np.uint8(Reason.OK)
BORDER = np.uint8(Reason.BORDER)
TOO_FEW = np.uint8(Reason.TOO_FEW_NEIGHBOURS)
SINGULAR = np.uint8(Reason.SINGULAR)
DEGENERATE = np.uint8(Reason.DEGENERATE)
NONMANIFOLD = np.uint8(Reason.NONMANIFOLD)
NOT_COMPUTED = np.uint8(Reason.NOT_COMPUTED)
FEATURE = np.uint8(Reason.FEATURE)
ORIENTATION = np.uint8(Reason.ORIENTATION)
"""The codes as the kernels store them (uint8, :attr:`curv.Curvature.reason`'s type)."""

PRECEDENCE = (Reason.NONMANIFOLD, Reason.DEGENERATE, Reason.BORDER, Reason.SINGULAR)
"""The codes :func:`precedence` orders, the most fundamental first (the rows of :func:`mark_ok_rows`'s marks)."""


@jit_inlined
def precedence(nonmanifold, degenerate, border, singular):
    """The reason code of a vertex from the causes that apply to it, the most fundamental first:
    NONMANIFOLD, then DEGENERATE, BORDER, SINGULAR, else OK (uint8; the module notes)."""
    if nonmanifold:
        return NONMANIFOLD
    if degenerate:
        return DEGENERATE
    if border:
        return BORDER
    if singular:
        return SINGULAR
    return OK


@jit_parallel
def mark_ok_rows(reason, marks):
    """In place: every row still ``OK`` takes the :func:`precedence` of the causes ``marks`` flags there.

    Parameters
    ----------
    reason : (c,) uint8
    marks : (4, c) bool
        Rows in the order of :data:`PRECEDENCE`: non-manifold, degenerate, border, singular.
    """
    for i in prange(reason.size):
        if reason[i] == OK:
            reason[i] = precedence(marks[0, i], marks[1, i], marks[2, i], marks[3, i])


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
