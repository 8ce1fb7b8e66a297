"""One study task: build its mesh, run every variant on it, summarise the errors as table rows.

:func:`run_task` is what executors call; it must stay a module-level function of picklable
arguments so that process pools and Dask workers can run it.
"""

from __future__ import annotations

import time

import numpy as np

from .metrics import METRIC_COLUMNS, summarize
from .protocol import Smoothing, Task, Variant
from .store import block_id
from .testmesh import build_test_mesh

__all__ = ["run_task"]


def _plain_groups(variants: tuple[Variant, ...]) -> list[list[int]]:
    """The variants' indices in groups estimated by one call: the plain-range variants of each
    method together, and of the methods that share a pass (csm and icc) together (first-seen
    order), every smoothing variant alone."""
    from ..estimators import get_spec

    groups: dict = {}
    for i, v in enumerate(variants):
        key = (get_spec(v.method).shared_pass or v.method) if v.smooth is Smoothing.NONE else ("alone", i)
        groups.setdefault(key, []).append(i)
    return list(groups.values())


def _estimate_group(mesh, variants: list[Variant], normals, region) -> list:
    """The results of ``variants`` (the plain ranges of one method or of the methods of one shared
    pass, or one smoothing variant), in their order: one :func:`curv.estimate_table` call for the
    ranges (csm and icc share one walk and one clip of the crossing faces, the fits nc, qs, an,
    mru, jet one walk over their ranges, the others the setup), without standard errors (the
    study reads none)."""
    from ..api import estimate, estimate_table

    v = variants[0]
    if v.smooth is not Smoothing.NONE:
        return [estimate(mesh, method=v.method, range=v.range, smooth=v.smooth,
                         normals=None if v.smooth is Smoothing.MESH else normals,
                         vertices=None if v.smooth is Smoothing.VALUES else region, standard_errors=False)]
    ranges: dict = {}
    for u in variants:
        ranges.setdefault(u.method, []).append(u.range)
    table = estimate_table(mesh, list(ranges), ranges, normals=normals, vertices=region, standard_errors=False)
    return [table[u.method][ranges[u.method].index(u.range)] for u in variants]


def run_task(task: Task, variants: tuple[Variant, ...]) -> list[dict]:
    """Evaluate ``variants`` on the mesh of ``task``.

    The mesh and its Max-weighted normals are computed once; each variant reuses the normals
    except R2SM, which estimates (and takes normals) on the smoothed mesh. Only the evaluated
    vertices are estimated (a region, ``vertices=``, whose values equal the whole mesh's there):
    the others are never measured, and on the paper's coarse meshes they are most of the mesh.
    R2SV, which smooths the estimated values over the neighbours, still estimates everywhere.
    The plain ranges of one estimator, or of the estimators that share a pass (csm and icc), are
    estimated by one call (:func:`curv.estimate_table`: the same values as one call per range, to
    rounding for csm, icc, nc, qs, an, mru and jet, which share one walk over the ranges), and no
    estimate computes standard errors (the study reads none). The ``seconds`` of such a group's
    rows are the group's time shared equally among them (csm's and icc's rows share their pass's).
    An estimator that raises does not stop the study: its row carries the error text and NaN
    measures, and the report lists it (a group that raises is run again one variant at a time, so
    that each row carries its own error).

    Parameters
    ----------
    task : Task
    variants : tuple of Variant

    Returns
    -------
    list of dict
        One row per variant with the columns of :data:`curv.study.table.COLUMNS`, in the order of
        ``variants``.
    """
    from ..geometry.normals import cached_max_normals

    tm = build_test_mesh(task)
    normals = cached_max_normals(tm.mesh)  # the mesh's own corner pass: no second walk
    base = dict(zip(("seed", "function", "density", "irregularity", "noise", "sample"), task.key))
    base.update(
        n_vertices=tm.mesh.n_vertices, irregularity_achieved=tm.irregularity,
        mean_edge=float(tm.mesh.mean_edge_length), noise_sigma=tm.noise_sigma,
        block=block_id(task.key, [v.id for v in variants]), block_rows=len(variants),
    )
    region = np.flatnonzero(tm.evaluated)
    rows: list = [None] * len(variants)

    def measured(res) -> tuple[dict, str]:
        return summarize(tm.truth, res, tm.evaluated), ""

    def failed(exc) -> tuple[dict, str]:
        measures = {name: float("nan") for name in METRIC_COLUMNS}
        measures.update(n_evaluated=int(tm.evaluated.sum()), n_invalid=-1, n_kept=-1)
        return measures, f"{type(exc).__name__}: {exc}".replace("\n", " ")

    for group in _plain_groups(variants):
        members = [variants[i] for i in group]
        t0 = time.perf_counter()
        try:
            outcomes = [measured(res) for res in _estimate_group(tm.mesh, members, normals, region)]
            seconds = [(time.perf_counter() - t0) / len(group)] * len(group)
        except Exception:  # recorded in the rows and reported; one bad estimator must not end a study
            outcomes, seconds = [], []
            for v in members:
                t1 = time.perf_counter()
                try:
                    outcomes.append(measured(_estimate_group(tm.mesh, [v], normals, region)[0]))
                except Exception as exc:
                    outcomes.append(failed(exc))
                seconds.append(time.perf_counter() - t1)
        for i, v, (measures, error), sec in zip(group, members, outcomes, seconds):
            rows[i] = {**base, "variant": v.id, "method": v.method, "range": v.range,
                       "smooth": v.smooth.value, **measures, "seconds": sec, "error": error}
    return rows
