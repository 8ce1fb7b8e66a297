"""The self-check: every short-listed call run on noisy copies of the input's smooth twin.

A copy is a smooth twin (:mod:`curv.advice.twin`) around a fresh random set of centres, each twin
vertex moved along the twin's normal by Gaussian noise of the level measured on the input
(:mod:`curv.advice.copies`). Each call runs on the copy at its centres only (``vertices=``: the cost
follows the centres, not the input) and is scored by the median e_rel over the centres it gives a
value at, against the twin's exact curvature. Over the copies a call's measured error is the
geometric mean of its medians and its spread their geometric standard deviation; the copies are
independent (new centres, new noise), so the spread is an honest standard error of the measure.

On a mesh each call also runs on the input itself at each twin's centres (:func:`_realized_steps`),
scored against the same twin's curvature: its *realized* error, the one judge that sees the input's
own noise draw (the copies draw it afresh), which :mod:`curv.advice.ranking` weighs against the
table's prediction.
"""

from __future__ import annotations

import inspect
import time
from collections.abc import Generator
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import CurvError
from ..core.jit import Progress, monotone, rescaled
from ..core.support import support_of

__all__ = ["Measured", "CheckReport", "iter_check", "call_reach", "CHECK_COPIES", "CHECK_CENTRES",
           "REACH_MARGIN", "MIN_MEASURED"]

CHECK_COPIES = 3
"""Noisy copies of the twin per check: each its own centres and noise draw."""

CHECK_CENTRES = 64
"""Centres per copy (fewer where the input has fewer eligible vertices)."""

REACH_MARGIN = 1.5
"""Range units added to a patch's radius beyond the farthest any call reads."""

NOISE_REACH = 8.0
"""Radius, in range units, of the narrower patch a twin patch is measured again on where its own
residuals reached no noise floor (:func:`_patch_noise`)."""

MIN_MEASURED = 0.5
"""A call measured at fewer than this share of the centres (over all copies) is not ranked by
its measured error (its twin patches cannot hold its support: a coarse closed surface's cap)."""


@dataclass(frozen=True)
class Measured:
    """One call's measured error on the copies.

    Attributes
    ----------
    erel : float
        Geometric mean over the copies of the median e_rel over each copy's centres.
    copies : tuple of float
        The median e_rel on each copy (NaN where the call gave no value at any centre).
    spread : float
        Geometric standard deviation of :attr:`copies` (a factor, 1 when they agree; NaN with one copy).
    measured : float
        Share of the centres (over all copies) the call gave a value at.
    seconds : float
        Time the call took over all copies (and on the input, for :attr:`realized`).
    realized : tuple of float
        On a mesh, the median e_rel of the call run on the input itself at each copy's centres
        against that copy's twin (NaN where it gave no value there); empty where not run (a point
        cloud). :func:`curv.advice.ranking.realized_score` makes the ranking's score of them.
    """

    erel: float
    copies: tuple
    spread: float
    measured: float
    seconds: float
    realized: tuple = ()

    @property
    def ok(self) -> bool:
        """Whether the measure is complete enough to rank by (:data:`MIN_MEASURED`)."""
        return bool(np.isfinite(self.erel) and self.measured >= MIN_MEASURED)

    def as_dict(self) -> dict:
        return {"erel": self.erel, "copies": list(self.copies), "spread": self.spread,
                "measured": self.measured, "seconds": self.seconds, "realized": list(self.realized)}

    @property
    def realized_spread(self) -> float:
        """Geometric standard deviation of the positive :attr:`realized` errors (a factor; NaN with
        fewer than two)."""
        r = np.asarray(self.realized, float)
        logs = np.log(r[np.isfinite(r) & (r > 0)])
        return float(np.exp(logs.std(ddof=1))) if logs.size > 1 else float("nan")


@dataclass(frozen=True)
class CheckReport:
    """What the self-check did and found.

    Attributes
    ----------
    measured : dict
        Call key -> :class:`Measured`.
    noise : float
        Noise along the normal the copies were given, in input units (0 where the input's noise
        is below what the twin's fits resolve).
    noise_bound : float
        The twin's median residual spread: the input's noise is at most about this.
    noise_resolved : bool
        Whether most patches' residuals reached a noise floor (then :attr:`noise` is measured).
    copies : int
    centres : int
        Centres scored per copy (the smallest over the copies).
    degrees : dict
        Polynomial degree -> number of twin patches fitted at it.
    seconds : float
        Wall time of the whole check.
    cpu_seconds : float
        Processor time of the whole check, every thread of the process together.
    """

    measured: dict
    noise: float
    noise_bound: float
    noise_resolved: bool
    copies: int
    centres: int
    degrees: dict = field(default_factory=dict)
    seconds: float = 0.0
    cpu_seconds: float = 0.0

    def as_dict(self) -> dict:
        return {"measured": {k: m.as_dict() for k, m in self.measured.items()}, "noise": self.noise,
                "noise_bound": self.noise_bound, "noise_resolved": self.noise_resolved, "copies": self.copies,
                "centres": self.centres, "degrees": {str(k): v for k, v in self.degrees.items()},
                "seconds": self.seconds, "cpu_seconds": self.cpu_seconds}


def call_reach(shape, kwargs: dict, units: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """(c,) float64 how far a call reads around each centre, in input units: its support (range in
    each centre's units, an absolute radius, or the knn-th neighbour's distance on the input), and the
    normals it reads there (their own fit's range, or one ring for the default normals).

    Parameters
    ----------
    shape : Mesh or PointCloud
        The input.
    kwargs : dict
        The call's keyword arguments of :func:`curv.estimate` (``range``, ``radius`` or ``knn``).
    units : (c,) float64
        The centres' range units (:func:`curv.advice.twin.range_units`).
    centres : (c,) int64
    """
    if kwargs.get("normals") in ("fit", "pca") or (kwargs.get("normals") is None
                                                    and support_of(shape).fits_normals(None)):
        extra = float(kwargs.get("fit_range", 2))
    else:
        extra = 1.0
    if kwargs.get("radius") is not None:
        support = np.full(units.size, float(kwargs["radius"]))
    elif kwargs.get("knn") is not None:
        from scipy.spatial import cKDTree

        k = int(kwargs["knn"])
        d, _ = cKDTree(shape.vertices).query(shape.vertices[centres], k=k + 1)
        support = d[:, -1] * 1.05
    else:
        support = float(kwargs.get("range", 2)) * units
    return support + (extra + REACH_MARGIN) * units


def _centre_sets(pool: np.ndarray, copies: int, per_copy: int, rng) -> list[np.ndarray]:
    """``copies`` sets of centres from ``pool``: disjoint while the pool lasts, then drawn afresh."""
    out, order = [], rng.permutation(pool)
    take = min(per_copy, pool.size)
    for _ in range(copies):
        if order.size < take:
            order = np.concatenate([order, rng.permutation(pool)])
        out.append(np.sort(order[:take]))
        order = order[take:]
    return out


def _estimate_keywords():
    from .. import iter_estimate

    accepts = "standard_errors" in inspect.signature(iter_estimate).parameters
    return iter_estimate, ({"standard_errors": False} if accepts else {})


def _normals_group(copy, kwargs: dict):
    """Which fitted normals a call reads (calls of one group share them on a copy), or None where its
    normals cost nothing to make (a mesh's default ones, a cloud's own)."""
    normals = kwargs.get("normals")
    if isinstance(normals, str):
        return (normals, float(kwargs.get("fit_range", 2)), str(kwargs.get("orient", "up")))
    if normals is None and support_of(copy).fits_normals(None):
        return ("fit", float(kwargs.get("fit_range", 2)), str(kwargs.get("orient", "up")))
    return None


def _on_copy(copy, rows: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A part's ``normals`` at its ``rows`` of ``copy``: (n, 3) normals (NaN elsewhere), (n,) bool rows held."""
    full = np.full((copy.n_vertices, 3), np.nan)
    have = np.zeros(copy.n_vertices, bool)
    full[rows], have[rows] = normals, True
    return full, have


def _score(twin, res, centres: np.ndarray, flip: bool) -> np.ndarray:
    """(c,) e_rel of a result at the twin's centres (their rows ``centres`` in the result) against the
    twin's curvature (NaN where invalid)."""
    from ..metrics import relative_error

    k1, k2 = res.k1[centres], res.k2[centres]
    t1, t2 = twin.k1, twin.k2
    if flip:  # a cloud's normals are oriented by the call: compare on its side of the surface
        side = np.einsum("ij,ij->i", res.normals[centres], twin.normals) < 0
        t1, t2 = np.where(side, -twin.k2, t1), np.where(side, -twin.k1, t2)
    return relative_error(t1, t2, k1, k2)


def iter_check(shape, calls: dict, pool, *, copies: int = CHECK_COPIES, centres: int = CHECK_CENTRES, seed: int = 0,
               noise: float | None = None, twin_options: dict | None = None,
               noise_policy: str = "share") -> Generator[Progress, None, CheckReport]:
    """Run ``calls`` on noisy copies of ``shape``'s smooth twin; yields progress, returns the report.

    Parameters
    ----------
    shape : Mesh or PointCloud
        The input.
    calls : dict
        Key -> keyword arguments of :func:`curv.estimate` (no ``vertices``).
    pool : (p,) int array_like
        The vertices (points) the centres are drawn from: where every call gives a value on the input.
    copies, centres : int
        Copies, and centres per copy.
    seed : int
        Seed of the centres and the noise.
    noise : float, optional
        The copies' noise along the normal in input units; default measured on the twin (the
        median over its patches of the share of their residuals that is noise,
        :attr:`~curv.advice.twin.Twin.noise`; a patch whose residuals reached no noise floor is
        measured again on a narrower patch, :func:`_patch_noise`).
    twin_options : dict, optional
        Keyword arguments of :func:`curv.advice.twin.build_twin` (the fairness study of
        docs/ADVISOR.md builds twins with each candidate's own model).

    Yields
    ------
    curv.core.jit.Progress
        Fraction done; every yield is a point where the caller may stop.

    Returns
    -------
    CheckReport
    """
    # the fractions below are sums of shares: rounding may put one a few ulps below the one before
    return (yield from monotone(_check_steps(shape, calls, pool, copies, centres, seed, noise, twin_options,
                                              noise_policy)))


def _check_steps(shape, calls, pool, copies, centres, seed, noise, twin_options, noise_policy):
    """:func:`iter_check`'s work (its parameters in order)."""
    from .copies import noisy_copy, part_normals, within_reach
    from .twin import build_twin, range_units

    t0, cpu0 = time.perf_counter(), time.process_time()
    pool = np.asarray(pool, np.int64)
    if pool.size == 0:
        raise CurvError("cannot check: no vertex where every candidate gives a value")
    rng = np.random.default_rng([seed, 35])
    sets = _centre_sets(pool, copies, centres, rng)
    twins, reaches, measures = [], [], []
    for j, chosen in enumerate(sets):
        units = range_units(shape, chosen)
        reach = {key: call_reach(shape, kw, units, chosen) for key, kw in calls.items()}
        twins.append(build_twin(shape, chosen, np.max(list(reach.values()), axis=0), **(twin_options or {})))
        # each kept centre's reach per call (a centre whose patch could not be fitted is not in the twin)
        reaches.append({key: r[np.searchsorted(chosen, twins[-1].source)] for key, r in reach.items()})
        measures.append(_patch_noise(shape, twins[-1]))
        yield Progress(0.2 * (j + 1) / len(sets), "building the smooth twin")
    sigma = np.concatenate([m[1] for m in measures])
    resolved = np.concatenate([m[2] for m in measures])
    finite = np.isfinite(sigma)
    noise_resolved = bool(2 * np.sum(resolved & finite) > sigma.size)
    if noise is None and noise_policy == "share":
        noise = float(np.median(np.concatenate([m[0] for m in measures])[finite])) if finite.any() else 0.0
    elif noise is None and noise_policy == "residual":
        noise = float(np.median(sigma[finite])) if finite.any() else 0.0
    elif noise is None:
        noise = float(np.median(sigma[resolved & finite])) if noise_resolved else 0.0
    bound = float(np.median(sigma[finite])) if finite.any() else float("nan")
    estimate, quiet = _estimate_keywords()
    scores = {key: [] for key in calls}
    seconds = {key: 0.0 for key in calls}
    realize = support_of(shape).has_faces
    steps = (len(twins) + realize) * len(calls)
    realized = {key: () for key in calls}
    if realize:
        realized = yield from rescaled(_realized_steps(shape, twins, calls, seconds), 0.2, 0.2 + 0.8 * len(calls) / steps)
        yield Progress(0.2 + 0.8 * len(calls) / steps, "scoring the candidates on the input itself")
    step = len(calls) if realize else 0
    for j, twin in enumerate(twins):
        copy = noisy_copy(shape, twin, noise, rng)
        # the calls that read the same normals share them and one part of the copy (what the widest of
        # them reads), so what an estimate caches on its input is made once per part; a knn call finds
        # its neighbours over all of its input and gets a part of its own reach
        group = {key: _normals_group(copy, kw) for key, kw in calls.items()}
        widest = {g: np.max([reaches[j][k] for k in calls if group[k] == g], axis=0) for g in set(group.values())}
        parts: dict = {}
        shared: dict = {}
        for key in sorted(calls, key=lambda k: (str(group[k]), "knn" in calls[k])):
            start = 0.2 + 0.8 * step / steps
            t1 = time.perf_counter()
            own = calls[key].get("knn") is not None
            where = key if own else group[key]
            if where not in parts:
                parts[where] = within_reach(copy, twin, reaches[j][key] if own else widest[group[key]])
            part, rows, centres_in_part = parts[where]
            if group[key] is not None and group[key] not in shared and support_of(part).has_faces:
                # a mesh's fitted normals: made once for the group, only where its calls read them
                same = [calls[k] for k in calls if group[k] == group[key]]
                made = part_normals(part, same, centres_in_part, twin.patch[rows])
                shared[group[key]] = _on_copy(copy, rows, made)
            run = dict(calls[key])
            if group[key] in shared and shared[group[key]][1][rows].all():
                run.pop("fit_range", None)
                run["normals"] = shared[group[key]][0][rows]
            try:
                res = yield from rescaled(estimate(part, vertices=centres_in_part, **quiet, **run), start,
                                          start + 0.8 / steps)
                if group[key] is not None and group[key] not in shared:
                    shared[group[key]] = _on_copy(copy, rows, res.normals)
                scores[key].append(_score(twin, res, centres_in_part, flip=not twin.oriented))
            except CurvError:
                scores[key].append(np.full(twin.centres.size, np.nan))
            seconds[key] += time.perf_counter() - t1
            step += 1
            yield Progress(0.2 + 0.8 * step / steps, "checking the candidates on noisy copies")
    measured = {key: _measure(scores[key], seconds[key], realized[key]) for key in calls}
    degrees = np.concatenate([t.degree for t in twins])
    return CheckReport(measured=measured, noise=float(noise), noise_bound=bound, noise_resolved=noise_resolved,
                       copies=len(twins), centres=int(min(t.centres.size for t in twins)),
                       degrees={int(d): int(n) for d, n in zip(*np.unique(degrees, return_counts=True))},
                       seconds=time.perf_counter() - t0, cpu_seconds=time.process_time() - cpu0)


def _patch_noise(shape, twin) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(c,) noise, residual spread and resolved flag of each of ``twin``'s patches (its
    :attr:`~curv.advice.twin.Twin.noise`, ``sigma``, ``resolved``), a patch wider than
    :data:`NOISE_REACH` range units whose residuals reached no noise floor measured again on a patch of
    that radius around its centre where that one reaches it.

    A patch as wide as the widest call reads may hold more of the surface than its fit can follow (a
    steep patch at 16 spacings: its residuals still fall at degree 6), so its residual is mostly the
    surface's own and its noise share near 0, and the copies would be noise-free while the input is
    not; a narrower patch of the same centre tells the noise from the surface. Where the narrower one
    reaches no floor either (a clean input), the patch's own measure stands.
    """
    from .twin import build_twin, range_units

    noise, sigma, resolved = twin.noise.copy(), twin.sigma.copy(), twin.resolved.copy()
    again = np.flatnonzero(~resolved & (twin.radius > NOISE_REACH * range_units(shape, twin.source)))
    if again.size:
        narrow = build_twin(shape, twin.source[again], NOISE_REACH)
        order = np.argsort(twin.source[again])
        rows = again[order[np.searchsorted(twin.source[again], narrow.source, sorter=order)]]  # the ones it fitted
        floor = narrow.resolved
        noise[rows[floor]], sigma[rows[floor]] = narrow.noise[floor], narrow.sigma[floor]
        resolved[rows[floor]] = True
    return noise, sigma, resolved


def _realized_steps(shape, twins: list, calls: dict, seconds: dict):
    """Each call run on the input mesh ``shape`` itself at every twin's centres (their source vertices)
    and scored against each twin's curvature there: call key -> (median e_rel per twin, NaN where the
    call gave no value at its centres).

    The calls run on the whole input (as a user would run them, with ``vertices=``), once for the
    centres of all twins together (an estimate at a vertex does not depend on which others are asked
    for); a call's fitted normals are fitted only where its group's calls read them
    (:func:`input_normals`: the same normals bit for bit, which the estimate normalises again as it
    does any normals it is given, so the score is the whole call's to about 1e-15), so the cost follows
    the centres. ``seconds`` gets each call's time added. A generator: yields progress, returns the scores.
    """
    estimate, quiet = _estimate_keywords()
    centres = np.unique(np.concatenate([t.source for t in twins]))
    group = {key: _normals_group(shape, kw) for key, kw in calls.items()}
    made: dict = {}
    out = {}
    for i, key in enumerate(calls):
        t1 = time.perf_counter()
        run = dict(calls[key])
        if group[key] is not None:
            if group[key] not in made:
                made[group[key]] = input_normals(shape, [calls[k] for k in calls if group[k] == group[key]], centres)
            run.pop("fit_range", None)
            run["normals"] = made[group[key]]
        try:
            res = yield from rescaled(estimate(shape, vertices=centres, **quiet, **run), i / len(calls),
                                      (i + 1) / len(calls))
            errs = [_score(twin, res, twin.source, flip=False) for twin in twins]
        except CurvError:
            errs = [np.full(twin.source.size, np.nan) for twin in twins]
        out[key] = tuple(float(np.nanmedian(e)) if np.isfinite(e).any() else float("nan") for e in errs)
        seconds[key] += time.perf_counter() - t1
    return out


def input_normals(mesh, calls: list, centres: np.ndarray) -> np.ndarray:
    """(n, 3) the fitted normals (``normals="fit"`` at the calls' ``fit_range``) that ``calls`` read at
    ``centres`` of ``mesh``, NaN elsewhere (:func:`curv.fitted_normals.fitted_normals` with ``vertices=``:
    those of the whole call there, bit for bit).

    They are fitted at the vertices a walk through the mesh reaches within each centre's reach
    (:func:`curv.advice.copies.widest_reach`): a support is connected within its ball and every vertex
    whose normal it reads is an edge from it, so the walk reaches them all, without a search of the
    whole input's space.
    """
    from ..fitted_normals import fitted_normals
    from ..geometry.neighbourhood import supports
    from .copies import widest_reach

    reach = np.full(mesh.n_vertices, np.nan)
    reach[centres] = widest_reach(mesh, calls, centres)
    _, indices = supports(mesh, reach, centres)
    return fitted_normals(mesh, range=calls[0].get("fit_range", 2), vertices=np.union1d(centres, indices))


def _measure(per_copy: list, seconds: float, realized: tuple) -> Measured:
    """A call's :class:`Measured` from its per-centre e_rel on each copy, and its realized medians."""
    medians = np.array([np.nanmedian(e) if np.isfinite(e).any() else np.nan for e in per_copy])
    share = float(np.mean(np.concatenate([np.isfinite(e) for e in per_copy]))) if per_copy else 0.0
    ok = np.isfinite(medians) & (medians > 0)
    logs = np.log(medians[ok])
    erel = float(np.exp(logs.mean())) if ok.any() else (0.0 if np.any(medians == 0) else float("nan"))
    spread = float(np.exp(logs.std(ddof=1))) if ok.sum() > 1 else float("nan")
    return Measured(erel=erel, copies=tuple(float(m) for m in medians), spread=spread, measured=share,
                    seconds=seconds, realized=tuple(realized))
