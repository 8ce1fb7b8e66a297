"""A tidy results table: one row per (task, variant), stored column-wise as numpy arrays.

The study needs only selection and grouped means, so this is a few lines of numpy instead of a
pandas dependency.
"""

from __future__ import annotations

from typing import Callable, Iterable, Sequence

import numpy as np

from .metrics import METRIC_COLUMNS

__all__ = ["COLUMNS", "KEY_COLUMNS", "Table"]

KEY_COLUMNS: tuple[str, ...] = ("seed", "function", "density", "irregularity", "noise", "sample")
"""The columns that identify a task."""

COLUMNS: dict[str, type] = {
    **{"seed": int, "function": str, "density": int, "irregularity": float, "noise": float, "sample": int},
    "variant": str, "method": str, "range": int, "smooth": str,
    "n_vertices": int, "irregularity_achieved": float, "mean_edge": float, "noise_sigma": float,
    **{name: (int if name.startswith("n_") else float) for name in METRIC_COLUMNS},
    "seconds": float, "error": str, "block": str, "block_rows": int,
}
"""Every column of the results, in file order, with its type."""

_DTYPES = {int: np.int64, float: np.float64, str: object}


class Table:
    """Columns of equal length; ``table["rms_erel"]`` is an (r,) array.

    Parameters
    ----------
    columns : dict of str to array_like
        Column name -> values; all of the same length.
    """

    def __init__(self, columns: dict[str, np.ndarray]):
        self.columns = {k: np.asarray(v) for k, v in columns.items()}
        lengths = {v.shape[0] for v in self.columns.values()}
        if len(lengths) > 1:
            raise ValueError(f"columns have different lengths: {sorted(lengths)}")

    @classmethod
    def from_rows(cls, rows: Iterable[dict], columns: dict[str, type] = COLUMNS) -> "Table":
        """Build from row dicts; missing values become NaN, -1 or ''."""
        rows = list(rows)
        fill = {int: -1, float: np.nan, str: ""}
        out = {}
        for name, typ in columns.items():
            values = [r.get(name, fill[typ]) for r in rows]
            out[name] = np.array(values, dtype=_DTYPES[typ]) if rows else np.zeros(0, _DTYPES[typ])
        return cls(out)

    def __len__(self) -> int:
        return next(iter(self.columns.values())).shape[0] if self.columns else 0

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def __contains__(self, name: str) -> bool:
        return name in self.columns

    def take(self, index) -> "Table":
        """Rows by boolean mask or integer index."""
        return Table({k: v[index] for k, v in self.columns.items()})

    def where(self, **conditions) -> "Table":
        """Rows where every column matches: a value, a collection of values, or a predicate.

        >>> t.where(noise=0.0, density=(217, 817), rms_erel=np.isfinite)   # doctest: +SKIP
        """
        mask = np.ones(len(self), bool)
        for name, cond in conditions.items():
            col = self.columns[name]
            if callable(cond):
                mask &= np.asarray(cond(col), bool)
            elif isinstance(cond, (list, tuple, set, frozenset, np.ndarray)):
                mask &= np.isin(col, list(cond))
            else:
                mask &= col == cond
        return self.take(mask)

    def unique(self, name: str) -> list:
        """Sorted distinct values of a column."""
        return sorted(set(self.columns[name].tolist()))

    def rows(self) -> list[dict]:
        """The rows as dicts (for writing and tests)."""
        names = list(self.columns)
        return [dict(zip(names, vals)) for vals in zip(*(self.columns[n].tolist() for n in names))]

    def sorted(self, keys: Sequence[str]) -> "Table":
        """Rows ordered by the given columns (first key most significant)."""
        order = np.lexsort([np.asarray(self.columns[k]).astype(str) if self.columns[k].dtype == object
                            else self.columns[k] for k in reversed(list(keys))])
        return self.take(order)

    def group(self, keys: Sequence[str], value: str, reduce: Callable[[np.ndarray], float] = np.nanmean
              ) -> dict[tuple, float]:
        """Reduce ``value`` over the rows of each combination of ``keys``.

        Returns
        -------
        dict
            ``{(key values...): reduce(values)}``; NaN values are ignored by the default
            ``nanmean``; a group whose values are all NaN gives NaN.
        """
        keys = list(keys)
        if not len(self):
            return {}
        codes = np.zeros(len(self), np.int64)
        uniques = []
        for k in keys:
            u, inv = np.unique(self.columns[k], return_inverse=True)
            codes = codes * len(u) + inv
            uniques.append(u)
        order = np.argsort(codes, kind="stable")
        sc = codes[order]
        cuts = np.flatnonzero(np.diff(sc)) + 1
        vals = np.asarray(self.columns[value], float)[order]
        out = {}
        for start, stop in zip(np.r_[0, cuts], np.r_[cuts, len(sc)]):
            first = order[start]
            key = tuple(self.columns[k][first].item() if hasattr(self.columns[k][first], "item")
                        else self.columns[k][first] for k in keys)
            chunk = vals[start:stop]
            with np.errstate(all="ignore"):
                out[key] = float(reduce(chunk)) if np.isfinite(chunk).any() else float("nan")
        return out
