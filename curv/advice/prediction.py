"""The advisor's table and its prediction: the Gaussian-kernel weighted mean of ``log(e_rel)`` over
the table's meshes near the input's measured features (:mod:`curv.advice.features`)."""

from __future__ import annotations

import functools
import json
from importlib import resources

import numpy as np

__all__ = ["TABLE_RESOURCE", "BASE_COLUMNS", "load_table", "kernel_axes", "table_coordinates", "feature_values",
           "kernel_predict", "log_erel", "predict"]

TABLE_RESOURCE = "data/advisor_table.json"
"""The table inside the ``curv`` package (see the table builder ``tools/advice_table`` (docs/ADVISOR.md))."""


@functools.lru_cache(maxsize=1)
def _packaged_table() -> str:
    return resources.files("curv").joinpath(TABLE_RESOURCE).read_text()


def load_table(path=None) -> dict:
    """The advisor's table: the packaged one, or a JSON file written by the table builder ``tools/advice_table`` (docs/ADVISOR.md)."""
    if path is None:
        return json.loads(_packaged_table())
    with open(path) as fh:
        return json.load(fh)


BASE_COLUMNS = ("density", "noise_level", "irregularity_deg")
"""The table's first three point columns, always kernel axes (log, square root or linear, linear)."""


def kernel_axes(table: dict) -> list:
    """The kernel's axes as ``[column, transform, scale]`` (transform ``"log"``, ``"sqrt"`` or
    ``"linear"``); a table without ``kernel["axes"]`` has the three base axes of its ``noise_axis``
    and ``scales``."""
    kernel = table["kernel"]
    if "axes" in kernel:
        return [list(a) for a in kernel["axes"]]
    scales = kernel["scales"]
    return [["density", "log", scales[0]], ["noise_level", kernel.get("noise_axis", "linear"), scales[1]],
            ["irregularity_deg", "linear", scales[2]]]


def _transform(values, how: str) -> np.ndarray:
    values = np.asarray(values, float)
    if how == "log":
        return np.log(np.maximum(values, 1e-12))
    if how == "sqrt":
        return np.sqrt(np.maximum(values, 0.0))
    return values


def table_coordinates(table: dict, *columns) -> np.ndarray:
    """Feature-space coordinates of the table's kernel.

    Parameters
    ----------
    table : dict
        Its ``kernel`` (:func:`kernel_axes`) and ``columns`` (the names of the point columns;
        default the three :data:`BASE_COLUMNS`).
    *columns : array_like
        One value or array per point column, in ``table["columns"]`` order (arrays broadcast).

    Returns
    -------
    (..., a) float64
        Each axis's column, transformed (log density; the noise level or its square root, as the
        errors change fastest near zero noise; the rest as they are or their square root) and
        divided by the axis's scale.
    """
    names = list(table.get("columns", BASE_COLUMNS))
    values = np.broadcast_arrays(*[np.asarray(c, float) for c in columns])
    axes = [_transform(values[names.index(col)], how) / scale for col, how, scale in kernel_axes(table)]
    return np.stack(axes, axis=-1)


def feature_values(features, columns) -> list:
    """The values of ``columns`` (the table's point columns) measured on a mesh: the calibrated
    base features and the raw shape and tessellation measures (:class:`MeshFeatures`)."""
    return [features.noise_level if c == "noise_level" else getattr(features, c) for c in columns]


def kernel_predict(points: np.ndarray, log_values: np.ndarray, query: np.ndarray, bandwidth: float) -> np.ndarray:
    """Gaussian-kernel weighted mean of ``log_values`` at ``query``, NaN entries left out per column.

    Parameters
    ----------
    points : (p, 3) float64
        Scaled coordinates of the table's meshes.
    log_values : (p, v) float64
        log median e_rel of each variant on each mesh (NaN where it has none).
    query : (3,) float64
    bandwidth : float
        Kernel width in scaled units.

    Returns
    -------
    (v,) float64
        Predicted median e_rel of every variant (NaN where no mesh has a value).
    """
    d2 = np.sum((points - query) ** 2, axis=1) / bandwidth**2
    have = np.isfinite(log_values)
    dist = np.where(have, d2[:, None], np.inf)
    nearest = dist.min(axis=0)
    # shifted per variant: far from every point the nearest meshes with a value still count
    with np.errstate(invalid="ignore"):
        w = np.where(have, np.exp(-0.5 * (dist - np.where(np.isfinite(nearest), nearest, 0.0))), 0.0)
    total = w.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.sum(w * np.where(have, log_values, 0.0), axis=0) / np.where(total > 0, total, np.nan)
    return np.exp(mean)


def log_erel(table: dict) -> np.ndarray:
    """(p, v) log of the table's median e_rel, floored at the table's ``kernel["erel_floor"]`` (NaN
    where missing). Below the floor an error is rounding (nc R1 on a noise-free sphere reads 1e-15):
    in a mean of logs one such mesh would outweigh every other neighbour, and all such calls are
    equally good."""
    erel = np.asarray(table["median_erel"], float)
    floor = table["kernel"].get("erel_floor", 0.0)
    return np.log(np.maximum(erel, floor) if floor > 0 else erel)


def predict(table: dict, features) -> dict:
    """Predicted median e_rel of every variant of the table at ``features`` (NaN where it has none)."""
    points = np.asarray(table["points"], float)
    q = table_coordinates(table, *feature_values(features, table.get("columns", BASE_COLUMNS)))
    pred = kernel_predict(table_coordinates(table, *points.T), log_erel(table), q, table["kernel"]["bandwidth"])
    return dict(zip(table["variants"], pred.tolist()))
