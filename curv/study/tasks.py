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


def _cheapest_errors(method: str) -> dict:
    """The study measures k1, k2 and validity, never the standard errors: an estimator with a
    choice of noise model for them (which the curvatures do not depend on) takes the cheapest."""
    from ..estimators import get_spec

    return {"noise_model": "independent"} if "independent" in get_spec(method).options.get("noise_model", ()) else {}


def run_task(task: Task, variants: tuple[Variant, ...]) -> list[dict]:
    """Evaluate ``variants`` on the mesh of ``task``.

    The mesh and its Max-weighted normals are computed once; each variant reuses the normals
    except R2SM, which estimates (and takes normals) on the smoothed mesh. Only the evaluated
    vertices are estimated (a region, ``vertices=``, whose values equal the whole mesh's there):
    the others are never measured, and on the paper's coarse meshes they are most of the mesh.
    R2SV, which smooths the estimated values over the neighbours, still estimates everywhere.
    An estimator that raises does not stop the study: its row carries the error text and NaN
    measures, and the report lists it.

    Parameters
    ----------
    task : Task
    variants : tuple of Variant

    Returns
    -------
    list of dict
        One row per variant with the columns of :data:`curv.study.table.COLUMNS`.
    """
    from ..api import estimate
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
    rows = []
    for v in variants:
        t0 = time.perf_counter()
        try:
            res = estimate(tm.mesh, method=v.method, range=v.range, smooth=v.smooth,
                           normals=None if v.smooth is Smoothing.MESH else normals,
                           vertices=None if v.smooth is Smoothing.VALUES else region,
                           **_cheapest_errors(v.method))
            measures, error = summarize(tm.truth, res, tm.evaluated), ""
        except Exception as exc:  # recorded in the row and reported; one bad estimator must not end a study
            measures = {name: float("nan") for name in METRIC_COLUMNS}
            measures.update(n_evaluated=int(tm.evaluated.sum()), n_invalid=-1, n_kept=-1)
            error = f"{type(exc).__name__}: {exc}".replace("\n", " ")
        rows.append({**base, "variant": v.id, "method": v.method, "range": v.range,
                     "smooth": v.smooth.value, **measures,
                     "seconds": time.perf_counter() - t0, "error": error})
    return rows
