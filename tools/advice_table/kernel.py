"""The table's kernel: leave-one-out regret, the bandwidth and noise axis of the base table, and the
forward selection of further axes (grouped by surface and by noise level)."""

from __future__ import annotations

import json

import numpy as np

from curv.advice.prediction import table_coordinates

BANDWIDTHS = (0.15, 0.25, 0.35, 0.5, 0.7, 1.0, 1.5)
"""Candidate kernel widths in scaled units, tried by leave-one-out."""
NOISE_AXES = ("linear", "sqrt")
"""Candidate transforms of the noise axis, tried by leave-one-out with every bandwidth."""


# ---------------------------------------------------------------------------- further axes: shape and tessellation
EXTRA_COLUMNS = ("border_share", "edge_cv", "valence_sd", "anisotropy", "curvature_spread", "hyperbolic_share",
                 "noise_raw", "noise_raw4", "residual_ratio")
"""Point columns beyond the base three: the open/closed distinction, the shape and tessellation
measures of :class:`curv.advice.features.MeshFeatures`, the uncalibrated noise measure and the
residual measures that tell model error from noise, candidates for further kernel axes."""
EXTRA_TRANSFORMS = {"border_share": "sqrt", "noise_raw": "log", "noise_raw4": "log", "anisotropy": "log"}
"""Axis transforms of the extra columns (default linear): a border share spans 0 (closed) to a
fifth (the coarsest patch), and its square root separates the small shares of dense patches from
a closed surface; the raw noise measure spans five decades (a noise-free dense patch's quadric
misses its neighbours by a few millionths of an edge, a noisy coarse one by a tenth), and its
logarithm keeps what the calibrated noise level clips to zero: a thousandth of the paper's level
on a dense mesh, or the noise a coarse mesh's density term swallows. The anisotropy's logarithm
tells a noise-free ellipsoid (0.07 and up) from a noise-free sphere (0.001): on a linear axis the
two stood within one bandwidth and the spheres' exact calls were advised on ellipsoids."""
AXIS_WEIGHTS = (0.5, 1.0, 2.0)
"""Weights tried for an extra axis (its scale is its standard deviation over the table divided by
the weight: 2 makes it count twice as much as a base axis)."""
SELECTION_BANDWIDTHS = (0.25, 0.35, 0.5)
"""Bandwidths tried for each set of axes during the selection. Not below 0.25: the table's meshes
sit on a grid whose steps are 0.3-0.7 scaled units along the noise axis (and come in families of
one surface at every noise level), so a narrower kernel turns into the nearest grid point, which
leave-one-out over the grid rewards and a mesh between the grid's points does not."""
EREL_FLOOR = 1e-6
"""Median e_rel below this counts as this (rounding: nc R1 on a noise-free sphere reads 1e-15), in
the prediction (:func:`curv.advice.prediction.log_erel`) and in the regret the selection scores."""
MIN_GAIN = 0.02
"""A further axis is taken only when it lowers the grouped leave-one-out mean regret by more (each
axis thins the table around a mesh: an axis must pay for it)."""



def key_text(key) -> str:
    """A table key as text (a dictionary key of the caches and groups)."""
    return json.dumps(list(key))


def _regret(log_values: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """Median e_rel of the chosen variant over the best one, per mesh."""
    best = np.nanmin(log_values, axis=1)
    return np.exp(log_values[np.arange(len(chosen)), chosen] - best)


def loo_regret(coords: np.ndarray, log_values: np.ndarray, bandwidth: float, groups=None) -> np.ndarray:
    """(p,) regret of advising each mesh from the other meshes of the table.

    Parameters
    ----------
    coords : (p, a) float64
        Scaled kernel coordinates of the table's meshes.
    log_values : (p, v) float64
        log median e_rel (NaN where missing).
    bandwidth : float
    groups : (p,) array_like, optional
        Meshes of one group are left out together (e.g. one surface at every noise level: its
        twins would otherwise stand next to it on every axis but noise); default each mesh alone.

    Returns
    -------
    (p,) float64
        The chosen variant's median e_rel over the best one's, per mesh: the same prediction as
        :func:`curv.advice.prediction.kernel_predict` (weights shifted per row by the nearest other mesh, and
        exactly per variant where that leaves a variant no weight).
    """
    d2 = np.sum((coords[:, None, :] - coords[None, :, :]) ** 2, axis=2) / bandwidth**2
    np.fill_diagonal(d2, np.inf)
    if groups is not None:
        g = np.asarray(groups)
        d2[g[:, None] == g[None, :]] = np.inf
    have = np.isfinite(log_values)
    values = np.where(have, log_values, 0.0)
    w = np.exp(-0.5 * (d2 - d2.min(axis=1, keepdims=True)))
    total = w @ have.astype(np.float64)
    pred = (w @ values) / np.where(total > 0, total, 1.0)
    for i, j in zip(*np.nonzero(~(total > 1e-200) & have.any(axis=0)[None, :])):  # a few (row, variant) pairs
        dist = np.where(have[:, j], d2[i], np.inf)
        if np.isfinite(dist.min()):
            wij = np.exp(-0.5 * (dist - dist.min()))
            pred[i, j] = wij @ values[:, j] / wij.sum()
        else:
            pred[i, j] = np.inf
    pred = np.where(have & np.isfinite(pred), pred, np.inf)  # a mesh is advised among the variants it has
    chosen = np.argmin(pred, axis=1)
    return _regret(log_values, chosen)


def choose_bandwidth(coords: np.ndarray, log_values: np.ndarray) -> tuple[float, dict]:
    """The candidate of :data:`BANDWIDTHS` with the lowest leave-one-out mean regret, and all scores."""
    scores = {h: float(np.mean(loo_regret(coords, log_values, h))) for h in BANDWIDTHS}
    return min(scores, key=scores.get), scores



def fit_kernel(points: np.ndarray, erel: np.ndarray) -> dict:
    """The kernel (noise axis, scales, bandwidth) with the lowest leave-one-out mean regret.

    Parameters
    ----------
    points : (p, 3) float64
        ``(density, noise level, irregularity)`` of the table's meshes.
    erel : (p, v) float64
        Median e_rel (NaN where missing).

    Returns
    -------
    dict
        ``noise_axis``, ``scales`` (standard deviation of each transformed coordinate),
        ``bandwidth`` and ``loo_mean_regret`` (every bandwidth of the chosen axis).
    """
    best = None
    for axis in NOISE_AXES:
        noise_coord = np.sqrt(points[:, 1]) if axis == "sqrt" else points[:, 1]
        scales = np.std(np.stack([np.log(points[:, 0]), noise_coord, points[:, 2]], axis=1), axis=0)
        kernel = {"noise_axis": axis, "scales": np.where(scales > 0, scales, 1.0).tolist()}
        coords = table_coordinates({"kernel": kernel}, *points.T)
        bandwidth, scores = choose_bandwidth(coords, np.log(erel))
        kernel.update(bandwidth=bandwidth, loo_mean_regret={str(h): round(s, 4) for h, s in scores.items()})
        if best is None or scores[bandwidth] < best["loo_mean_regret"][str(best["bandwidth"])]:
            best = kernel
    return best



def surface_groups(keys) -> np.ndarray:
    """(p,) int64: one group per random surface (a key's seed, function or closed shape, and sample:
    the same surface at every density, irregularity and noise level), so that the selection's
    leave-one-out advises a mesh only from other surfaces, as a user's mesh is. Left out by noise
    level only (:func:`noise_groups`), the same surface at a neighbouring density or irregularity
    still stood next to it, and an axis that names the surface (its anisotropy: each Monge function
    has its own) won the selection and lost on new surfaces."""
    index: dict = {}
    return np.array([index.setdefault(key_text([k[0], k[1], k[5]]), len(index)) for k in keys], np.int64)


def noise_groups(keys) -> np.ndarray:
    """(p,) int64: one group per table surface (its key without the noise level), so that a mesh is
    left out with its twins at the other noise levels."""
    index: dict = {}
    return np.array([index.setdefault(key_text(list(k[:4]) + list(k[5:])), len(index)) for k in keys], np.int64)


def select_axes(points: np.ndarray, columns, erel: np.ndarray, groups, *, progress=None,
                note: str = "grouped leave-one-out") -> dict:
    """The kernel: the base axes of :func:`fit_kernel`'s noise transform and, by forward selection,
    the extra columns that lower the grouped leave-one-out mean regret by more than :data:`MIN_GAIN`.

    With several groupings the score is the mean of their leave-one-out mean regrets: the shipped
    table is scored left out by surface (:func:`surface_groups`: how a new surface is advised) and by
    noise level (:func:`noise_groups`: how a known surface is advised between the grid's settings),
    so an axis must pay on both; each alone misled the selection on the development meshes (by
    surface only it could not see that the curvature spread places a mesh between settings, by noise
    level only it took an axis that names the surface).

    Parameters
    ----------
    points : (p, c) float64
        The table's point columns (``columns`` order; the first three the base ones).
    columns : sequence of str
    erel : (p, v) float64
        Median e_rel (NaN where missing).
    groups : (p,) array_like, or a sequence of them
        Meshes left out together (:func:`surface_groups`, :func:`noise_groups`); several: one
        leave-one-out per grouping, scored by the mean.
    progress : callable, optional
    note : str
        What the groupings are (stored as ``loo_note``).

    Returns
    -------
    dict
        ``axes`` (``[column, transform, scale]``), ``bandwidth``, ``loo_mean_regret`` (per
        bandwidth of the chosen axes, the score), ``loo_p90_regret`` (per bandwidth and grouping),
        ``selection`` (each step: the axes added and the score) and ``loo_note``.
    """
    say = progress or (lambda text: None)
    log_values = np.log(np.maximum(erel, EREL_FLOOR))
    columns = list(columns)

    def axis(col, how, weight=1.0):
        x = points[:, columns.index(col)]
        x = np.log(np.maximum(x, 1e-12)) if how == "log" else (np.sqrt(np.maximum(x, 0)) if how == "sqrt" else x)
        sd = float(np.std(x))
        return [col, how, (sd if sd > 0 else 1.0) / weight]

    groupings = [np.asarray(groups)] if np.ndim(groups[0]) == 0 else [np.asarray(g) for g in groups]

    def score(axes):
        coords = table_coordinates({"kernel": {"axes": axes}, "columns": columns}, *points.T)
        per = {h: [loo_regret(coords, log_values, h, g) for g in groupings] for h in SELECTION_BANDWIDTHS}
        mean = {h: float(np.mean([r.mean() for r in rs])) for h, rs in per.items()}
        h = min(mean, key=mean.get)
        return mean[h], h, per

    best_axes, best = None, None
    for noise_axis in NOISE_AXES:
        axes = [axis("density", "log"), axis("noise_level", noise_axis), axis("irregularity_deg", "linear")]
        sc = score(axes)
        if best is None or sc[0] < best[0]:
            best_axes, best = axes, sc
    steps = [{"axes": [a[0] for a in best_axes], "loo_mean_regret": round(best[0], 4), "bandwidth": best[1]}]
    say(f"base axes: grouped LOO mean regret {best[0]:.4f} (bandwidth {best[1]})")
    while True:
        used = {a[0] for a in best_axes}
        trials = []
        for col in columns[3:]:
            if col in used or not np.isfinite(points[:, columns.index(col)]).all():
                continue
            for weight in AXIS_WEIGHTS:
                axes = best_axes + [axis(col, EXTRA_TRANSFORMS.get(col, "linear"), weight)]
                trials.append((score(axes), axes, weight))
        if not trials:
            break
        sc, axes, weight = min(trials, key=lambda t: t[0][0])
        say(f"+ {axes[-1][0]} (weight {weight}): {sc[0]:.4f} (bandwidth {sc[1]})")
        if sc[0] > best[0] - MIN_GAIN:
            break
        best_axes, best = axes, sc
        steps.append({"added": axes[-1][0], "weight": weight, "loo_mean_regret": round(sc[0], 4),
                      "bandwidth": sc[1]})
    _, h, per = best
    return {"axes": best_axes, "bandwidth": h, "erel_floor": EREL_FLOOR,
            "loo_mean_regret": {str(b): round(float(np.mean([r.mean() for r in rs])), 4) for b, rs in per.items()},
            "loo_mean_regret_per_grouping": {str(b): [round(float(r.mean()), 4) for r in rs] for b, rs in per.items()},
            "loo_p90_regret": {str(b): [round(float(np.percentile(r, 90)), 4) for r in rs] for b, rs in per.items()},
            "selection": steps,
            "loo_note": note}


