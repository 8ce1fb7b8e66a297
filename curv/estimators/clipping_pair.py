"""The ball-clipping pass: ``csm``, ``icc`` or both, one search and one clip of the sphere per vertex and range.

The two estimators sum different terms over the same ball: csm the edges' dihedral terms and the
area (:mod:`curv.estimators.csm`), icc the faces' corrected measures, each face weighted by the
fraction of its area inside (:mod:`curv.estimators.icc`). What costs is the same for both: the
support walk and the faces that cross the sphere, with their exits and exact areas
(:func:`~curv.estimators._ball_mesh.crossing_faces`). :func:`_clip_chunk` does those once per
centre and level and feeds each estimator asked for:

1. widen the support to the level's radius (one walk serves every level:
   :func:`~curv.geometry.neighbourhood.widen_ball_support`);
2. add the new support vertices' star rows (:func:`~curv.estimators._ball_sums.add_star_rows`);
3. clip the faces leaving the ball from the rim and correct each estimator's sums
   (``csm.add_crossings``, ``icc.add_crossings``), or walk a support whose star rows are not exact
   element by element (``csm.walk_sums``, ``icc.walk_sums``);
4. finish each estimator's row (``csm.finish``, ``icc.finish``).

Each estimator's sums are added in the order of a run of it alone, so running both together gives
each the same bits. An estimator not asked for is passed as None: numba compiles the kernel for
that case without its branches (one machine code per choice, each loaded from the cache). The
pass is registered under :data:`~curv.estimators._ball_sums.CLIPPING_PASS`; ``iter_csm`` and
``iter_icc`` run it for themselves alone, :func:`curv.estimate_table` for both.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..core.jit import iter_chunks, jit, jit_parallel, launch, prange, slice_bounds, threads
from ..core.mesh import Mesh
from ..geometry.neighbourhood import new_queues, new_scratch, start_ball_support, widen_ball_support
from . import csm, icc
from ._ball_mesh import KERNELS as BALL_MESH_KERNELS, ball_mesh, corner_width, crossing_faces, may_leave, new_crossings
from ._ball_sums import CLIPPING_PASS, add_star_rows, ball_inputs, level_mark, support_bits
from ._output_rows import LevelOutputs
from .registry import register_pass

__all__ = ["iter_csm_icc", "CsmPass", "IccPass"]


class Scratch(NamedTuple):
    """Per-thread scratch of :func:`_clip_chunk`, one row per thread slice."""

    vstamps: np.ndarray
    """(parts, n) int64 zeroed support stamps (:func:`~curv.geometry.neighbourhood.new_scratch`)."""
    queues: np.ndarray
    """(parts, n) int64 support queues (:func:`~curv.geometry.neighbourhood.new_queues`)."""
    rims: np.ndarray
    """(parts, n) int64: the support vertices whose edges may leave the last level's ball."""
    outside: np.ndarray
    """(parts, n) int64 and (parts, n) float64 with several levels (else (parts, 0)): the vertices
    met beyond a level's radius, and their squared distances."""
    outside_d2: np.ndarray
    width: int
    """The most corners at one vertex (:func:`~curv.estimators._ball_clipping.corner_width`)."""


def _flat_bundle(name: str, terms: type, *fields: str) -> type:
    """A NamedTuple class ``name`` with the fields of the NamedTuple class ``terms``, then ``fields``: an
    estimator's per-mesh terms, the walk's stamps and its outputs in one flat bundle (numba's parallel
    kernels take tuples of arrays, not tuples of tuples)."""
    bundle = NamedTuple(name, [*((field, object) for field in terms._fields),
                               *((field, np.ndarray) for field in fields)])
    bundle.__module__ = __name__
    return bundle


CsmPass = _flat_bundle("CsmPass", csm.CsmTerms, "fstamps", "estamps", "k1", "k2", "d1", "d2", "reason")
"""csm in the pass: :class:`~curv.estimators.csm.CsmTerms`' fields; ``fstamps`` (parts, m) and ``estamps``
(parts, e), zeroed face and edge stamps of :func:`curv.estimators.csm.walk_sums` (int32 or int64, a row per
thread); the outputs ``k1``, ``k2``, ``d1``, ``d2``, ``reason`` with the levels' rows one after another
((levels n,) and (levels n, 3): :attr:`~curv.estimators._output_rows.LevelOutputs.flat_rows`; row
``level * n + p``)."""

IccPass = _flat_bundle("IccPass", icc.IccTerms, "fstamps", "k1", "k2", "d1", "d2", "mean", "gaussian", "reason")
"""icc in the pass: :class:`~curv.estimators.icc.IccTerms`' fields, ``fstamps`` (parts, m) as csm's, and the
outputs of :class:`~curv.estimators.icc.IccOutputs` (its ``flat_rows``, as csm's)."""


@jit
def _csm_rows(csm_pass):
    """csm's outputs ``(k1, k2, d1, d2, reason)`` from its bundle (None when not asked for)."""
    if csm_pass is None:
        return None
    return csm_pass.k1, csm_pass.k2, csm_pass.d1, csm_pass.d2, csm_pass.reason


@jit
def _icc_rows(icc_pass):
    """icc's outputs ``(k1, k2, d1, d2, mean, gaussian, reason)`` from its bundle (None when not asked for)."""
    if icc_pass is None:
        return None
    return icc_pass.k1, icc_pass.k2, icc_pass.d1, icc_pass.d2, icc_pass.mean, icc_pass.gaussian, icc_pass.reason


@jit_parallel
def _clip_chunk(centres, lo, hi, radii, mesh, walk, scratch, normals, csm_pass, icc_pass):
    """csm and icc (:class:`CsmPass`, :class:`IccPass`, or
    None when not asked for) at every level of ``radii`` (levels, n) around ``centres[lo:hi]``."""
    parts = scratch.vstamps.shape[0]
    levels, n = radii.shape
    for t in prange(parts):
        # what the centres read of the estimators' bundles, taken out once per thread: an array taken
        # out of a bundle for a call (or a row view made) per centre costs an atomic reference
        # count on a record every thread shares
        c_rows, i_rows = _csm_rows(csm_pass), _icc_rows(icc_pass)
        if csm_pass is not None:
            c_star = csm_pass.star
            c_clean = csm_pass.clean
            c_half = csm_pass.half_scale
        if icc_pass is not None:
            i_star = icc_pass.star
            i_clean = icc_pass.clean
            i_measures = icc_pass.measures
        work = (np.empty((3, 3)), np.empty((4, 3)), np.empty(8))  # csm's tensor and its eigenpairs
        c_acc = np.empty(csm.SUMS)  # csm: the support's star sums so far
        c_sums = np.empty(csm.SUMS)  # T = sum_e beta(e) |e ∩ B| ê êᵀ (upper triangle), area(B ∩ mesh)
        i_acc = np.empty(icc.MEASURES)  # icc: the same for its nine measures
        i_sums = np.empty(icc.MEASURES)
        crossings = new_crossings(scratch.width)
        queue, vstamp, rim = scratch.queues[t], scratch.vstamps[t], scratch.rims[t]
        waiting, waiting_d2 = scratch.outside[t], scratch.outside_d2[t]
        start, stop = slice_bounds(lo, hi, t, parts)
        for k in range(start, stop):
            p = centres[k]
            at = (mesh.x[p], mesh.y[p], mesh.z[p])
            # one walk for every level: each level's support is the single search's at its radius,
            # its star sums the last level's plus the rows it added
            count = start_ball_support(p, vstamp, queue)
            head = pending = done = rim_count = 0
            hit = 0
            c_exact, i_exact = csm_pass is not None, icc_pass is not None
            c_acc[:] = 0.0
            i_acc[:] = 0.0
            for level in range(levels):
                r = radii[level, p]
                count, head, pending = widen_ball_support(p, r ** 2, level + 1 < levels, (walk.indptr, walk.indices),
                                                          (mesh.x, mesh.y, mesh.z), vstamp, queue,
                                                          (count, head, pending), (waiting, waiting_d2))
                hit = support_bits(mesh, queue, done, count, hit)  # the flags are the vertices', the same for both
                if csm_pass is not None:
                    c_exact = add_star_rows(queue, done, count, c_star, c_clean, c_exact, c_acc)
                if icc_pass is not None:
                    i_exact = add_star_rows(queue, done, count, i_star, i_clean, i_exact, i_acc)
                if c_exact or i_exact:
                    # every element inside the ball whole is in the star sums; only the last level's rim
                    # and the new vertices may have edges leaving it: their crossing faces are clipped
                    # once and corrected in each estimator's sums
                    c_sums[:] = c_acc
                    i_sums[:] = i_acc
                    kept = 0
                    for i in range(rim_count + count - done):
                        v = rim[i] if i < rim_count else queue[done + i - rim_count]
                        if not may_leave(mesh, v, at, r):
                            continue
                        rim[kept] = v
                        kept += 1
                        leaving = crossing_faces(mesh, v, at, r, crossings)
                        if csm_pass is not None and c_exact:
                            csm.add_crossings(c_sums, v, at, crossings, leaving, mesh, c_half)
                        if icc_pass is not None and i_exact:
                            icc.add_crossings(i_sums, crossings, leaving, mesh, i_measures)
                    rim_count = kept
                centre = (p, r ** 2, level_mark(p, level, levels))
                row = level * n + p  # the outputs' row of (level, p)
                if csm_pass is not None:
                    level_hit = hit
                    if not c_exact:
                        c_sums[:] = 0.0
                        level_hit |= csm.walk_sums(centre, (queue, count), mesh, walk, csm_pass,
                                                   (csm_pass.estamps[t], csm_pass.fstamps[t]), c_sums)
                    csm.finish((p, row), c_sums, level_hit, normals, work, c_rows)
                if icc_pass is not None:
                    level_hit = hit
                    if not i_exact:
                        i_sums[:] = 0.0
                        level_hit |= icc.walk_sums(centre, (queue, count), mesh, walk, icc_pass.measures,
                                                   icc_pass.fstamps[t], i_sums)
                    icc.finish((p, row), i_sums, level_hit, normals, icc_pass.from_measures, i_rows)
                done = count


def _stamps(parts: int, count: int, levels: int, n: int) -> np.ndarray:
    """(parts, count) zeroed stamps of a face-by-face (or edge-by-edge) walk; int32 where every
    :func:`~curv.estimators._ball_sums.level_mark` fits (half the cache lines)."""
    return np.zeros((parts, count), np.int32 if (n + 1) * levels < 2**31 else np.int64)


def _run(mesh: Mesh, centres: np.ndarray, radii: np.ndarray, walk, touched: np.ndarray | None,
         normals: np.ndarray, csm_terms: csm.CsmTerms | None, icc_terms: icc.IccTerms | None, chunk: int | None):
    """Run :func:`_clip_chunk` over ``centres`` (a generator of the fraction done); returns
    ``{name: outputs}`` (:class:`~curv.estimators._output_rows.LevelOutputs`,
    :class:`~curv.estimators.icc.IccOutputs`)."""
    ball = ball_mesh(mesh, touched)
    n = mesh.n_vertices
    levels = radii.shape[0]
    parts = max(1, min(threads(), centres.size))
    wide = n if levels > 1 else 0  # widen_ball_support's waiting vertices
    scratch = Scratch(new_scratch(n, parts), new_queues(n, parts), new_queues(n, parts), new_queues(wide, parts),
                      np.empty((parts, wide)), corner_width(mesh))
    outputs = {}
    csm_pass = icc_pass = None
    if csm_terms is not None:
        outputs["csm"] = LevelOutputs(levels, n)
        csm_pass = CsmPass(*csm_terms, _stamps(parts, mesh.n_faces if csm_terms.walk else 0, levels, n),
                           _stamps(parts, csm_terms.beta_scale.size, levels, n), *outputs["csm"].flat_rows)
    if icc_terms is not None:
        outputs["icc"] = icc.IccOutputs(levels, n)
        icc_pass = IccPass(*icc_terms, _stamps(parts, mesh.n_faces if icc_terms.walk else 0, levels, n),
                           *outputs["icc"].flat_rows)
    yield 0.0

    def run(lo: int, hi: int) -> None:
        launch(_clip_chunk, centres, lo, hi, radii, ball, walk, scratch, normals, csm_pass, icc_pass)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return outputs


def iter_csm_icc(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, methods=("csm", "icc"), *,
                 chunk: int | None = None, centres: np.ndarray | None = None, features=None,
                 options: dict | None = None):
    """csm and icc over the balls of every level of ``radii`` around every vertex, in one pass.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    normals : (n, 3) float64
        Unit vertex normals (csm picks its normal eigenvector with them, icc interpolates them).
    radii : (levels, n) or (n,) float64
        Ball radii, ascending per vertex (:func:`curv.estimators.csm.iter_csm`).
    methods : sequence of str
        ``"csm"``, ``"icc"`` or both.
    chunk, centres, features :
        As in :func:`~curv.estimators.csm.iter_csm`.
    options : dict, optional
        ``{name: estimator options}``: icc's ``from_measures``.

    It yields the fraction done and returns ``{name: [Principal per level]}`` for each of ``methods``.
    """
    options = options or {}
    centres, radii, walk, touched = yield from ball_inputs(mesh, centres, radii, features)
    normals = np.asarray(normals, dtype=np.float64)  # the cached normals are column-major: read as they are
    csm_terms = (yield from csm.csm_terms(mesh, centres, radii, walk, touched[0])) if "csm" in methods else None
    icc_terms = (icc.icc_terms(mesh, normals, touched, walk.crease, **options.get("icc", {})) if "icc" in methods
                 else None)
    outputs = yield from _run(mesh, centres, radii, walk, touched[0], normals, csm_terms, icc_terms, chunk)
    return {name: [out.principal(level) for level in range(radii.shape[0])] for name, out in outputs.items()}


register_pass(CLIPPING_PASS, iter_csm_icc, kernels=(*BALL_MESH_KERNELS, _clip_chunk))
