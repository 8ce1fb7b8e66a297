"""The results as dense arrays: one axis per grid parameter, so a setting's mean is a slice.

A study table has one row per (task, variant). Every reduction the report makes is a mean over
the rows of some setting; on a 400k-row N=100 table, filtering rows for each of the thousands of
means (and again for each bootstrap resample) is far too slow. :class:`Cube` places each measure
in an array of shape ``(variants, functions, densities, irregularities, noise levels, units)``
(NaN where a row is missing or its value is NaN), where a *unit* is one random surface draw
``(seed, sample)``; a mean over a setting is then a weighted mean over a slice, and a bootstrap
resample of the surfaces is just another weight vector over the unit axis.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .table import Table

__all__ = ["Cube", "AXES", "unit_weights"]

AXES: tuple[str, ...] = ("function", "density", "irregularity", "noise")
"""The grid parameters a mean can be restricted to (besides the variant)."""


class Cube:
    """Dense arrays of a results table's measures.

    Parameters
    ----------
    table : Table
        Results rows; duplicate (task, variant) rows keep the last one.

    Attributes
    ----------
    variants : list of str
        Variant ids along axis 0.
    levels : dict of str to list
        The sorted values of each axis of :data:`AXES`.
    units : list of tuple
        ``(seed, sample)`` of each position of the last axis.
    """

    def __init__(self, table: Table):
        self.table = table
        codes = []
        self.variants, vcode = _codes(table["variant"]) if len(table) else ([], np.zeros(0, np.int64))
        codes.append(vcode)
        self.levels: dict[str, list] = {}
        for name in AXES:
            values, code = _codes(table[name]) if len(table) else ([], np.zeros(0, np.int64))
            self.levels[name] = values
            codes.append(code)
        if len(table):
            pairs = table["seed"].astype(np.int64) * (1 << 32) + table["sample"].astype(np.int64)
            uniq, ucode = np.unique(pairs, return_inverse=True)
            self.units = [(int(p >> 32), int(p & 0xFFFFFFFF)) for p in uniq.tolist()]
        else:
            ucode, self.units = np.zeros(0, np.int64), []
        codes.append(ucode)
        self._codes = tuple(codes)
        self.shape = (len(self.variants), *(len(self.levels[a]) for a in AXES), len(self.units))
        self._arrays: dict[str, np.ndarray] = {}
        self._variant_index = {v: i for i, v in enumerate(self.variants)}

    @property
    def n_units(self) -> int:
        """Number of random surface draws (the bootstrap's resampling unit)."""
        return len(self.units)

    def array(self, measure: str) -> np.ndarray:
        """The measure as a float64 array of :attr:`shape` (built once, then cached)."""
        if measure not in self._arrays:
            out = np.full(self.shape, np.nan)
            if len(self.table):
                out[self._codes] = np.asarray(self.table[measure], float)
            self._arrays[measure] = out
        return self._arrays[measure]

    def index(self, axis: str, value) -> np.ndarray:
        """Positions on ``axis`` of a value or a collection of values (absent values are skipped)."""
        levels = self.levels[axis]
        wanted = value if isinstance(value, (list, tuple, set, frozenset, np.ndarray)) else [value]
        pos = {v: i for i, v in enumerate(levels)}
        return np.array(sorted(pos[w] for w in set(np.asarray(list(wanted)).tolist()) if w in pos), np.int64)

    def mean(self, variant: str, measure: str, weights: np.ndarray | None = None, **where) -> float:
        """Weighted mean of ``measure`` over the finite cells of ``variant`` matching ``where``.

        Parameters
        ----------
        variant : str
            Variant id.
        measure : str
            A numeric column of the results.
        weights : (units,) float64, optional
            Weight of each random surface draw (a bootstrap resample's counts); default all 1.
        **where
            Restrictions to values (or collections of values) of the axes in :data:`AXES`.

        Returns
        -------
        float
            NaN when no cell matches or every matching value is NaN.
        """
        unknown = set(where) - set(AXES)
        if unknown:
            raise KeyError(f"cannot restrict a mean to {sorted(unknown)}; axes are {', '.join(AXES)}")
        vi = self._variant_index.get(variant)
        if vi is None:
            return float("nan")
        idx = [self.index(a, where[a]) if a in where else slice(None) for a in AXES]
        sub = self.array(measure)[vi]
        for axis, ix in enumerate(idx):
            if not isinstance(ix, slice):
                sub = np.take(sub, ix, axis=axis)
        if sub.size == 0:
            return float("nan")
        finite = np.isfinite(sub)
        w = np.ones(self.n_units) if weights is None else np.asarray(weights, float)
        den = float(np.sum(finite * w))
        if den <= 0:
            return float("nan")
        return float(np.sum(np.where(finite, sub, 0.0) * w)) / den


def _codes(column: np.ndarray) -> tuple[list, np.ndarray]:
    values, code = np.unique(np.asarray(column), return_inverse=True)
    return [v.item() if hasattr(v, "item") else v for v in values], code.astype(np.int64)


def unit_weights(cube: Cube, samples: Sequence[int]) -> np.ndarray:
    """(units,) float64: weight 1 for the units whose sample index is in ``samples``, else 0."""
    keep = set(int(s) for s in samples)
    return np.array([1.0 if s in keep else 0.0 for _, s in cube.units])
