"""Further axes: every table mesh measured again for the shape, tessellation and residual columns
(``refeature``), and the kernel's axes chosen again over them (``reselect``)."""

from __future__ import annotations

import json
import time

import numpy as np

from curv.advice.features import raw_measures
from curv.variants import NOISE_FRACTION

from .base import MEASURES, POINT_DIGITS, _round
from .extend import table_mesh
from .kernel import EXTRA_COLUMNS, key_text, noise_groups, select_axes, surface_groups

FEATURE_MEASURES = MEASURES + ", shape v1, residuals v1"
"""What the cached rows of ``refeature`` were measured with; a cache of other measures is measured
again (residuals v1: :mod:`curv.advice.residuals` at R3 on 1000 sampled vertices)."""


def feature_row(key) -> dict:
    """Every raw measure (:func:`curv.advice.features.raw_measures`) of the table mesh of ``key``."""
    mesh, _, _ = table_mesh(key)
    raw = raw_measures(mesh)
    raw.pop("polygon_kinds")
    return {"key": list(key), **raw}



def refeature_table(table: dict, rows: dict, *, command: str = "", progress=None) -> dict:
    """``table`` with the extra columns (:data:`EXTRA_COLUMNS`) measured on its meshes and the
    kernel chosen again (:func:`select_axes`). The base columns are recomputed from the same raw
    measures with the table's calibration (they equal the stored ones to their rounding)."""
    from curv.advice.features import calibrate_irregularity, calibrate_noise

    cal = table["calibration"]
    keys = table["truth"]["key"]
    columns = ["density", "noise_level", "irregularity_deg", *EXTRA_COLUMNS]
    pts = []
    for k in keys:
        r = rows[key_text(k)]
        noise = calibrate_noise(r["noise_raw"], cal, r["density"])
        pts.append([r["density"], noise / NOISE_FRACTION, calibrate_irregularity(r["irregularity_raw_deg"], noise, cal),
                    *(r[c] for c in EXTRA_COLUMNS)])
    pts = np.array(pts, float)
    meta = dict(table["metadata"])
    meta.update(refeature_command=command, created=time.strftime("%Y-%m-%d %H:%M:%S %Z"))
    return {**table, "kernel": _grouped_selection(table, pts, columns, progress), "metadata": meta,
            "columns": columns, "points": [[_round(x, POINT_DIGITS) for x in p] for p in pts]}


def _grouped_selection(table: dict, pts: np.ndarray, columns, progress) -> dict:
    """The kernel :func:`select_axes` chooses over ``table``'s meshes at ``pts`` (``(p, c)``, the
    point columns ``columns``), scored by the mean of the by-surface and by-noise-level groupings."""
    keys = table["truth"]["key"]
    return select_axes(pts, columns, np.array(table["median_erel"], float), [surface_groups(keys), noise_groups(keys)],
                       progress=progress,
                       note="the mean of two grouped leave-one-outs: each mesh advised from the other surfaces "
                            "(its random surface at every density, irregularity and noise level left out), and "
                            "from all but its twins at the other noise levels")


def reselect_table(table: dict, *, command: str = "", progress=None) -> dict:
    """``table`` with the kernel chosen again (:func:`select_axes`) over its stored point columns,
    nothing measured: for a change of the selection's rules (e.g. an axis transform,
    :data:`EXTRA_TRANSFORMS`). The points are the stored ones (:data:`POINT_DIGITS` significant digits)."""
    pts = np.array([[np.nan if x is None else x for x in p] for p in table["points"]], float)
    meta = dict(table["metadata"])
    meta.update(reselect_command=command, created=time.strftime("%Y-%m-%d %H:%M:%S %Z"))
    return {**table, "kernel": _grouped_selection(table, pts, table["columns"], progress), "metadata": meta}


def _write_selected(table: dict, path) -> int:
    """Write a table whose axes were just chosen and say which (the end of ``refeature`` and ``reselect``)."""
    with open(path, "w") as fh:
        json.dump(table, fh, separators=(",", ":"))
    k = table["kernel"]
    print(f"wrote {path}: axes {[a[0] for a in k['axes']]}, bandwidth {k['bandwidth']} "
          f"(grouped LOO mean regret {k['loo_mean_regret'][str(k['bandwidth'])]})", flush=True)
    return 0


