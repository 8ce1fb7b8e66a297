"""The rows an estimator writes: its outputs before the kernel runs, and the one NaN-row writer.

Every estimator writes, for each vertex it estimates, ``k1``, ``k2``, ``d1``, ``d2`` and a reason
code. The outputs start uninitialised (:func:`unset_principal`, :class:`LevelOutputs`): a kernel
writes every row it estimates, so an estimate over a small region touches only the region's pages.
Where a vertex has no estimate the row is NaN (:func:`nan_row`), never a number that looks real;
its reason code says why (:mod:`curv.core.validity`).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit
from ..core.result import Principal

__all__ = ["nan_row", "flat_levels", "unset_principal", "LevelOutputs"]


@jit
def nan_row(p, k1, k2, d1, d2):
    """Row p of the principal outputs as NaN: ``k1[p]``, ``k2[p]`` and the directions ``d1[p]``, ``d2[p]``.

    Parameters
    ----------
    p : int
    k1, k2 : (n,) float64
    d1, d2 : (n, 3) float64
    """
    k1[p] = math.nan
    k2[p] = math.nan
    for c in range(3):
        d1[p, c] = math.nan
        d2[p, c] = math.nan


def flat_levels(rows) -> tuple:
    """Each (levels, n, ...) array of ``rows`` as a (levels n, ...) view."""
    return tuple(a.reshape(a.shape[0] * a.shape[1], *a.shape[2:]) for a in rows)


def unset_principal(n: int) -> Principal:
    """Uninitialised (n,) and (n, 3) outputs of a kernel that writes every row it estimates.

    Unlike a NaN-filled result, allocating them costs nothing until a row is written, so an estimate
    over a small region of a large mesh touches only the region's rows.
    """
    return Principal(k1=np.empty(n), k2=np.empty(n), d1=np.empty((n, 3)), d2=np.empty((n, 3)),
                     reason=np.empty(n, np.uint8))


class LevelOutputs:
    """A kernel's outputs for ``levels`` radii: ``k1, k2`` (levels, n), ``d1, d2`` (levels, n, 3),
    ``reason`` (levels, n) uint8, uninitialised (the kernel writes every centre's rows);
    :attr:`rows` the five arrays as a kernel takes them, :meth:`principal` one level's
    :class:`~curv.core.result.Principal` (views)."""

    def __init__(self, levels: int, n: int):
        self.k1, self.k2 = np.empty((levels, n)), np.empty((levels, n))
        self.d1, self.d2 = np.empty((levels, n, 3)), np.empty((levels, n, 3))
        self.reason = np.empty((levels, n), np.uint8)

    @property
    def rows(self) -> tuple:
        """``(k1, k2, d1, d2, reason)``."""
        return self.k1, self.k2, self.d1, self.d2, self.reason

    @property
    def flat_rows(self) -> tuple:
        """:attr:`rows` with the levels' rows one after another, (levels n,) and (levels n, 3) views:
        row ``level * n + p`` is vertex p's at ``level``, written without a view per level."""
        return flat_levels(self.rows)

    def principal(self, level: int) -> Principal:
        return Principal(k1=self.k1[level], k2=self.k2[level], d1=self.d1[level], d2=self.d2[level],
                         reason=self.reason[level])
