"""Which calls of the table apply to a mesh, the share of its vertices each can estimate, and the
table's ranking by coverage, then predicted error."""

from __future__ import annotations

import numpy as np

from ..core.mesh import Mesh

__all__ = ["VALID_SHARE_SLACK", "VALID_SAMPLE", "candidates", "valid_shares", "valid_masks", "rank"]

VALID_SHARE_SLACK = 0.02
"""A candidate that leaves more than this share of the vertices invalid beyond the candidate that
leaves the fewest ranks after every candidate that does not (whatever its predicted error)."""

VALID_SAMPLE = 2000
"""Vertices the valid shares are counted on (all of them on smaller meshes; a fixed random sample,
seed 0, on larger ones: the share then has a standard error of at most 1.1 %)."""


def candidates(table: dict, features) -> list[str]:
    """Variant ids of the table the mesh admits: registered, with options the estimator accepts,
    and not refused for the mesh's faces (:func:`curv.estimators.refusal`: triangle-only estimators
    on polygons)."""
    from ..core.errors import EstimatorError
    from ..estimators import ESTIMATORS
    from ..estimators.registry import refusal
    from ..variants import Variant

    faces = _FaceKinds(features.polygon_kinds)
    out = []
    for vid in table["variants"]:
        v = Variant.from_id(vid)
        spec = ESTIMATORS.get(v.method)
        if spec is None or refusal(spec, faces) is not None:
            continue
        try:
            spec.check_options({k: x for k, x in v.options if k not in ("normals", "fit_range")})
        except EstimatorError:
            continue
        out.append(vid)
    return out


class _FaceKinds:
    """What :func:`curv.estimators.refusal` reads of a mesh, from the measured polygon kinds."""

    def __init__(self, kinds: dict):
        self.face_sizes = np.array(sorted(kinds), np.int64)
        self.is_triangular = set(kinds) <= {3}


def valid_shares(mesh: Mesh, variant_ids, *, sample: int = VALID_SAMPLE, within=None) -> dict:
    """``{variant id: share in [0, 1]}`` of the vertices each variant can estimate on ``mesh``: the
    masks of :func:`valid_masks` (the same parameters and vertices) averaged."""
    centres, masks = valid_masks(mesh, variant_ids, sample=sample, within=within)
    return {vid: float(ok.mean()) if ok.size else 0.0 for vid, ok in masks.items()}


def valid_masks(mesh: Mesh, variant_ids, *, sample: int = VALID_SAMPLE, within=None) -> tuple[np.ndarray, dict]:
    """Which of some vertices each variant can estimate on ``mesh``, from the supports' sizes.

    The vertices are all of them up to ``sample``, else a fixed random sample of that many (seed 0),
    with one support search per distinct ball
    (:func:`curv.geometry.neighbourhood.support_sizes`, the radius from :func:`curv.core.ranges.ball_radii`), by the
    registry's facts: a vertex is lost when it is on a border or has no usable normal (every
    estimator), when its support holds fewer vertices than the fit needs
    (:meth:`EstimatorSpec.fewest_neighbours`: the fit's unknowns, the jet's by degree), when a
    closed-ring estimator's support reaches a border (``meyer``, ``ru``: the vertex or a 1-ring
    neighbour is on one), and
    everywhere for an estimator the mesh is refused by (:func:`curv.estimators.refusal`: triangle-only
    on polygons). ``normals="fit"`` also needs the degree-2 jet of ``fit_range`` to fit. Singular
    systems are not foreseen (rare on a mesh without degenerate faces).

    Parameters
    ----------
    mesh : Mesh
    variant_ids : iterable of str
    sample : int
    within : (m,) int array_like, optional
        Count among these vertices only (default all).

    Returns
    -------
    centres : (c,) int64
        The vertices counted on.
    masks : dict
        ``{variant id: (c,) bool}``.
    """
    from ..estimators import get_spec
    from ..estimators.registry import refusal
    from ..geometry.neighbourhood import support_sizes
    from ..geometry.normals import unusable_normal_vertices
    from ..core.ranges import ball_radii, resolve
    from ..variants import Variant

    pool = np.arange(mesh.n_vertices) if within is None else np.unique(np.asarray(within, np.int64))
    centres = pool if pool.size <= sample else np.sort(np.random.default_rng(0).choice(pool, size=sample, replace=False))
    border = mesh.border_vertices
    base = ~border[centres] & ~unusable_normal_vertices(mesh)[centres]
    balls: dict = {}

    def ball(spec, k) -> tuple[np.ndarray, np.ndarray]:
        """(support sizes, support reaches a border) of the centres in ``spec``'s ball at Rk."""
        rng = resolve(spec, k)
        key = (rng.k, spec.uses_normals, spec.has_support)
        if key not in balls:
            if spec.has_support:
                balls[key] = support_sizes(mesh, ball_radii(mesh, rng, uses_normals=spec.uses_normals), centres, border)
            else:  # a 1-ring formula: lost on or next to a border (its corners' rings are not closed)
                near = border | (mesh.adjacency @ border.astype(np.float64) > 0)
                balls[key] = (np.full(centres.size, np.iinfo(np.int64).max), near[centres])
        return balls[key]

    def can(spec, k, options) -> np.ndarray:
        if refusal(spec, mesh) is not None:
            return np.zeros(centres.size, bool)
        size, reaches_border = ball(spec, k)
        ok = base & (size >= spec.fewest_neighbours(options))
        return ok & ~reaches_border if spec.closed_ring else ok

    out = {}
    for vid in variant_ids:
        v = Variant.from_id(vid)
        opts = dict(v.options)
        fit = opts.pop("normals", None) == "fit"
        fit_range = opts.pop("fit_range", 2)
        ok = can(get_spec(v.method), v.range, opts)
        if fit:
            ok = ok & can(get_spec("jet"), fit_range, {})
        out[vid] = ok
    return centres, out


def rank(pred: dict, shares: dict) -> list[str]:
    """Variant ids best first: those within :data:`VALID_SHARE_SLACK` of the best share by predicted
    error, then the rest by predicted error; variants that estimate no vertex are left out."""
    ids = [v for v in pred if np.isfinite(pred[v]) and shares.get(v, 1.0) > 0]
    if not ids:
        return []
    top = max(shares.get(v, 1.0) for v in ids)
    return sorted(ids, key=lambda v: (shares.get(v, 1.0) < top - VALID_SHARE_SLACK, pred[v]))
