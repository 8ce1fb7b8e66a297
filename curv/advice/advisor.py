"""Which estimator for this mesh? Measured mesh features -> ranked estimator variants (from the study).

>>> adv = curv.advise(mesh)                        # doctest: +SKIP
>>> adv.method, adv.range, adv.expected_erel, adv.why
('mru', 4, 0.12, 'noise about 0.6 of the paper's level, irregular (22 degrees): mru R4, expected median e_rel 0.12')

The advisor measures the three features the paper's study varies (density, noise, irregularity)
and the mesh's shape and tessellation (valence and edge spread, curvature spread, anisotropy, saddle
share, border share; see :class:`MeshFeatures`) and predicts the median e_rel of every candidate variant from a table
of study results (``curv/data/advisor_table.json``, built by the table builder ``tools/advice_table`` (docs/ADVISOR.md); the module is not named ``advise`` so that importing it cannot shadow the function ``curv.advise``). The
table holds one point per mesh of a study run (the paper's Monge patches on the hexagon, plus
noisy closed analytic surfaces, which widen the range of densities and tessellations): the
advisor's own features measured on that mesh, and the median e_rel every variant reached on it
against the exact curvature. A prediction is the
Gaussian-kernel weighted mean of ``log(e_rel)`` (floored at the table's ``erel_floor``) over the
table's meshes in the scaled feature space ``(log density, noise level or its square root,
irregularity)`` and the further axes the table chose (``kernel["axes"]``); axes, transforms, scales
and bandwidth are the table's (chosen by grouped leave-one-out regret when the table is built). Because the table's coordinates are
measured exactly as on the user's mesh, a bias of a measure cancels instead of misplacing the
mesh; far outside the table the nearest meshes decide (the grid's edge acts as a clip). There is
no hand-written rule: a different table gives different advice.

The jobs live in their own modules: the measures in :mod:`curv.advice.features`, the table and
its prediction in :mod:`curv.advice.prediction`, the calls a mesh admits and the share of it each
can estimate in :mod:`curv.advice.shares`; this module ranks the table's calls for a mesh
(:func:`table_ranking`) and holds :func:`advise` (the self-checked advice:
:mod:`curv.advice.advising`).
"""

from __future__ import annotations

import numpy as np

from ..core.errors import MeshError
from ..core.mesh import Mesh
from .answer import Advice, Candidate
from .features import (FIT_METHOD, FIT_RANGE, RESIDUAL_MEASURES, SHAPE_MEASURES, MeshFeatures, describe_mesh,
                       measure_features, residual_measures, shape_measures)
from .prediction import BASE_COLUMNS, TABLE_RESOURCE, feature_values, kernel_axes, load_table, predict, table_coordinates
from .shares import VALID_SAMPLE, VALID_SHARE_SLACK, candidates, rank, valid_masks, valid_shares

__all__ = ["Advice", "Candidate", "MeshFeatures", "advise", "measure_features", "load_table", "valid_shares", "valid_masks",
           "TABLE_RESOURCE", "FIT_METHOD", "FIT_RANGE", "VALID_SHARE_SLACK", "VALID_SAMPLE", "SHAPE_MEASURES",
           "RESIDUAL_MEASURES", "residual_measures",
           "BASE_COLUMNS", "kernel_axes", "table_coordinates", "feature_values", "shape_measures", "table_ranking",
           "describe_mesh"]
"""The public names of the advice (re-exported from the modules that own them)."""


def table_ranking(mesh: Mesh, *, normals=None, table: dict | None = None, vertices=None) -> tuple:
    """The table's advice for a mesh: its features and every candidate in the table's order.

    Parameters
    ----------
    mesh : Mesh
    normals : (n, 3) array_like, optional
        Vertex normals for the measuring fit; default Max-weighted (the study's).
    table : dict, optional
        A table from :func:`load_table`; default the packaged one.
    vertices : (c,) int64, optional
        Count the valid shares on these vertices (the ones the estimate is wanted at).

    Returns
    -------
    features : MeshFeatures
    ranking : list of Candidate
        By :func:`rank`: coverage first, then the predicted error.
    sharp : float or None
        The ``features`` angle to suggest when the mesh has many sharp edges.

    Raises
    ------
    MeshError
        When the features cannot be measured (no valid fit anywhere) or no candidate applies.
    """
    from ..variants import Variant

    table = load_table() if table is None else table
    features = measure_features(mesh, normals=normals, table=table)
    pred = predict(table, features)
    ids = [v for v in candidates(table, features) if np.isfinite(pred[v])]
    shares = valid_shares(mesh, ids, within=vertices)
    ranking = []
    for vid in rank({v: pred[v] for v in ids}, shares):
        v = Variant.from_id(vid)
        ranking.append(Candidate(v.method, v.range, dict(v.options), float(pred[vid]), shares[vid]))
    if not ranking:
        raise MeshError("cannot advise: no estimator of the table applies to this mesh")
    return features, ranking, _sharp_edge_angle(mesh)


def advise(shape, *, normals=None, table: dict | None = None, check: bool | None = None, vertices=None,
           seed: int = 0) -> Advice:
    """Recommend a whole estimate call for a mesh or point cloud, checked on the input itself.

    See :func:`curv.advice.advising.iter_advise` (the same, step by step with progress and cancel).

    Parameters
    ----------
    shape : Mesh, PointCloud, trimesh.Trimesh, pyvista.PolyData or meshio.Mesh
        Other libraries' meshes are converted by :func:`curv.convert.as_mesh`.
    normals : (n, 3) array_like, optional
        A mesh's vertex normals for the measuring fit; default Max-weighted (the study's).
    table : dict, optional
        A table from :func:`load_table`; default the packaged one.
    check : bool, optional
        Run the self-check (:mod:`curv.advice.check`): True, False (the table's ranking alone), or
        None (default): check unless the input is larger than
        :data:`curv.advice.advising.CHECK_MAX_VERTICES`.
    vertices : (c,) int array_like, optional
        The vertices (points) the estimate is wanted at: the valid shares are counted and the
        check's centres drawn there. Default all.
    seed : int
        Seed of the check's centres and noise.

    Returns
    -------
    Advice

    Raises
    ------
    MeshError
        When the features cannot be measured (no valid fit anywhere).
    """
    from ..core.jit import run_to_end
    from .advising import iter_advise

    return run_to_end(iter_advise(shape, normals=normals, table=table, check=check, vertices=vertices, seed=seed))


def _sharp_edge_angle(mesh: Mesh) -> float | None:
    """The features angle to suggest when the mesh has many sharp edges, else None."""
    from ..core.features import has_many_sharp_edges, suggest_threshold

    return suggest_threshold(mesh) if has_many_sharp_edges(mesh) else None
