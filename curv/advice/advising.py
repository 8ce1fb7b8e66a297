"""The advice, step by step: measure the input, propose, check the proposals on the input's twin, rank.

On a mesh the study's table proposes (:func:`curv.advice.advisor.table_ranking`): every candidate
call ranked by the error the table predicts for a mesh like this one. Its first
:data:`SHORT_LIST` calls (among those that cover the mesh) are then checked on the mesh itself
(:mod:`curv.advice.check`: noisy copies of its smooth twin, whose curvature is exact) and ranked by
the error measured there (:mod:`curv.advice.ranking`). On a point cloud no table applies: every
candidate of :mod:`curv.advice.clouds` is checked.

The check costs a fixed amount of work (its centres, not the input, set it), so it runs on inputs
of any size up to :data:`CHECK_MAX_VERTICES`; ``check=False`` (or a larger input) gives the table's
ranking alone, and :attr:`~curv.advice.answer.Advice.note` says so.
"""

from __future__ import annotations

from collections.abc import Generator

import numpy as np

from ..core.errors import MeshError
from ..core.jit import Progress, rescaled
from ..core.pointcloud import PointCloud
from ..core.support import support_of
from .answer import Advice

__all__ = ["iter_advise", "SHORT_LIST", "CHECK_MAX_VERTICES"]

SHORT_LIST = 6
"""Calls of the table's ranking the check measures on a mesh (the first that cover the mesh)."""

CHECK_MAX_VERTICES = 5_000_000
"""Above this many vertices (points) the check is skipped unless asked for (``check=True``): the
input is then far larger than the few hundred vertices the check can look at."""


def iter_advise(shape, *, normals=None, table: dict | None = None, check: bool | None = None, vertices=None,
                seed: int = 0, short_list: int = SHORT_LIST, copies: int | None = None,
                centres: int | None = None) -> Generator[Progress, None, Advice]:
    """Advise step by step: yields the fraction done, returns the :class:`~curv.advice.answer.Advice`.

    Every ``yield`` is a point where a caller may stop (cancel). Parameters as in
    :func:`curv.advise`, and:

    Parameters
    ----------
    short_list : int
        Calls of a mesh's table ranking to check.
    copies, centres : int, optional
        The check's noisy copies and centres per copy (:data:`curv.advice.check.CHECK_COPIES`,
        :data:`curv.advice.check.CHECK_CENTRES`).
    """
    from ..convert import as_mesh
    from .check import CHECK_CENTRES, CHECK_COPIES, iter_check

    cloud = support_of(shape).kind == "points"
    shape = shape if cloud else as_mesh(shape)
    n = shape.n_vertices
    region = None if vertices is None else np.unique(np.asarray(vertices, np.int64).reshape(-1))
    if region is not None and (region.size == 0 or region[0] < 0 or region[-1] >= n):
        raise MeshError(f"vertices must be indices 0..{n - 1} of the input")
    run_check = check if check is not None else n <= CHECK_MAX_VERTICES
    note = ""
    if check is False:
        note = "the table's ranking alone (check=False)" if not cloud else "the prior order alone (check=False)"
    elif not run_check:
        note = (f"the check was skipped: {n:,} vertices, more than {CHECK_MAX_VERTICES:,} (check=True runs it); "
                + ("the table's ranking alone" if not cloud else "the prior order alone"))
    yield Progress(0.0, "measuring the input")
    if cloud:
        features, ranking, sharp, usable = _cloud_proposal(shape, region)
    else:
        from .advisor import table_ranking

        features, ranking, sharp = table_ranking(shape, normals=normals, table=table, vertices=region)
    yield Progress(0.1, "measuring the input")
    report = None
    if run_check:
        from .shares import VALID_SHARE_SLACK

        top = max(c.valid_share for c in ranking)
        admitted = [c for c in ranking if c.valid_share >= top - VALID_SHARE_SLACK]
        proposed = admitted if cloud else admitted[:short_list]
        pool = _cloud_pool(usable, region) if cloud else _mesh_pool(shape, proposed, region)
        if pool.size:
            calls = {c.key: c.kwargs for c in proposed}
            report = yield from rescaled(iter_check(shape, calls, pool, seed=seed, copies=copies or CHECK_COPIES,
                                                    centres=centres or CHECK_CENTRES), 0.1, 1.0)
        else:
            note = "no vertex where every proposed call gives a value: nothing to check at"
    return _answer(shape, features, ranking, sharp, report, note)


def _mesh_pool(mesh, proposed: list, region) -> np.ndarray:
    """The vertices (of a sample) where every proposed call gives a value: the check's centres."""
    from .shares import valid_masks

    counted, masks = valid_masks(mesh, [c.key for c in proposed], within=region)
    return counted[np.all([masks[c.key] for c in proposed], axis=0)] if proposed else counted[:0]


def _cloud_pool(usable: np.ndarray, region) -> np.ndarray:
    pool = np.flatnonzero(usable)
    return pool if region is None else np.intersect1d(pool, region)


def _cloud_proposal(cloud: PointCloud, region):
    """A cloud's features, its candidates in the prior order, no sharp-edge angle, its usable points."""
    from .clouds import cloud_candidates, cloud_features, usable_points

    usable = usable_points(cloud)
    features = cloud_features(cloud, usable)
    share = float(np.mean(usable if region is None else usable[region])) if cloud.n_points else 0.0
    return features, cloud_candidates(cloud, features, share), None, usable


def _answer(shape, features, ranking, sharp, report, note) -> Advice:
    """The :class:`Advice`: the ranking with the check's measures, and the words for a person."""
    import dataclasses

    from .clouds import describe_cloud
    from .features import describe_mesh
    from .ranking import rank_candidates, ranked_by, realized_score
    from .shares import VALID_SHARE_SLACK

    cloud = support_of(shape).kind == "points"
    if cloud and report is not None:
        features = dataclasses.replace(features, noise=report.noise / features.spacing)
    ranking = rank_candidates(ranking, None if report is None else report.measured, VALID_SHARE_SLACK)
    best = ranking[0]
    what = describe_cloud(features) if cloud else describe_mesh(features)
    why = f"{what}: {best.label}"
    if best.measured is not None and best.measured.ok:
        spread = best.measured.spread
        why += (f", measured median e_rel {best.measured.erel:.2g}"
                + (f" (x{spread:.2f} over {report.copies} noisy copies of its smooth twin)" if np.isfinite(spread)
                   else f" (on {report.copies} noisy copy of its smooth twin)"))
        if np.isfinite(best.expected_erel):
            why += f"; the table predicted {best.expected_erel:.2g}"
        ties = [c.label for c in ranking if c.within_noise]
        if ties:
            why += "; within noise: " + ", ".join(ties[:3]) + (f" and {len(ties) - 3} more" if len(ties) > 3 else "")
    elif np.isfinite(best.expected_erel):
        why += f", expected median e_rel {best.expected_erel:.2g}"
    if np.isfinite(realized_score(best.measured)):
        why += f"; realized {realized_score(best.measured):.2g} on the input itself"
    if best.valid_share < 0.995:
        why += f"; valid at {100 * best.valid_share:.0f} % of the {'points' if cloud else 'vertices'}"
    rule = ranked_by(ranking)
    if report is not None:
        why += f"; ranked by {rule}"
    if note:
        why += f" [{note}]"
    if sharp is not None:
        why += f"; many sharp edges: estimate with features={sharp:g} so the creases are not smoothed over"
    return Advice(features=features, ranking=ranking, method=best.method, range=best.range,
                  expected_erel=best.expected_erel, why=why, suggested_features=sharp, options=dict(best.options),
                  valid_share=best.valid_share, check=report, note=note, ranked_by=rule)
