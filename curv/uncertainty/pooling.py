"""The noise level of the per-vertex fits, pooled over each vertex and its edge neighbours.

A fit's residuals estimate the noise variance as ``sigma² = RSS / (spare equations)``. Where the
support is small that rests on very few spare equations (nc and qs at R1 on a 6-ring: one, after
the frame's tilt), so ``sigma²`` is itself very uncertain and ``± 2 se`` covers the truth far less
often than 95 % (a Student t with one degree of freedom: 70 %). The noise level is a property of
the surface region, not of one vertex: the standard errors of vertex p use

``sigma²(p) = Σ RSS_q / Σ dof_q`` over q in {p} and p's edge neighbours

(the neighbours whose fit is valid and has a spare equation), with p's own propagation
``var(k_i) / sigma²`` and eigen-step bias (docs/UNCERTAINTY.md). A vertex whose own fit has no
spare equation keeps a NaN standard error. A point cloud has no edges: each point keeps its own
fit's noise level, and so does a vertex whose noise level is in other units than its neighbours'
(:attr:`~curv.uncertainty.parts.Errors.alone`).

An estimate over a region fits the region's neighbours as well (:func:`pool_members`), so that its
standard errors equal the whole mesh's.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit_parallel, launch, prange
from ..core.support import support_of
from ..core.validity import OK
from .parts import Errors
from .propagation import rad_bias

__all__ = ["pool_rings", "pool_members", "pool_standard_errors", "POOL_KERNEL"]


def pool_rings(mesh) -> tuple[np.ndarray, np.ndarray]:
    """The neighbours each vertex pools its noise level with, as CSR ``(indptr (n+1,), indices)``
    int64: a mesh's edge neighbours; none on a point cloud."""
    if support_of(mesh).has_faces:
        return mesh.neighbour_lists
    return np.zeros(mesh.n_vertices + 1, np.int64), np.zeros(0, np.int64)


def pool_members(mesh, centres: np.ndarray) -> np.ndarray:
    """(c',) int64 sorted: ``centres`` and their pooling neighbours (:func:`pool_rings`), the
    vertices a region's fits must run at. At the cost of the region, not of the mesh."""
    ptr, ring = pool_rings(mesh)
    centres = np.asarray(centres, dtype=np.int64)
    starts, stops = ptr[centres], ptr[centres + 1]
    counts = stops - starts
    # indices starts[i] .. stops[i]-1 of every centre, without a Python loop
    offsets = np.arange(int(counts.sum()), dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)
    return np.unique(np.concatenate([centres, ring[np.repeat(starts, counts) + offsets]]))


@jit_parallel
def _pool_kernel(centres, ring_ptr, ring, reason, errors):
    parts, alone, k1_se, k2_se = errors.parts, errors.alone, errors.k1_se, errors.k2_se
    for i in prange(centres.size):
        p = centres[i]
        rss, dof = parts[p, 0], parts[p, 1]
        if not (dof > 0.0 and math.isfinite(rss)):
            k1_se[p] = math.nan
            k2_se[p] = math.nan
            continue
        # a noise level in other units than its neighbours' is not pooled
        for j in range(ring_ptr[p], ring_ptr[p + 1] if not alone[p] else ring_ptr[p]):
            q = ring[j]
            if reason[q] == OK and not alone[q] and parts[q, 1] > 0.0 and math.isfinite(parts[q, 0]):
                rss += parts[q, 0]
                dof += parts[q, 1]
        sigma2 = max(rss, 0.0) / dof
        bias = rad_bias(parts[p, 3], sigma2 * parts[p, 2])
        k1_se[p] = math.sqrt(sigma2 * k1_se[p] + bias * bias)
        k2_se[p] = math.sqrt(sigma2 * k2_se[p] + bias * bias)


POOL_KERNEL = _pool_kernel
"""The pooling pass's kernel (the fits list it among their kernels: a first run compiles it too)."""


def pool_standard_errors(centres: np.ndarray, ring_ptr: np.ndarray, ring: np.ndarray, reason: np.ndarray,
                         errors: Errors) -> None:
    """Turn the fits' parts into the standard errors of the ``centres``, in place.

    Parameters
    ----------
    centres : (c,) int64
        The vertices whose standard errors are wanted; their neighbours' fits must have run.
    ring_ptr, ring : int64
        :func:`pool_rings`.
    reason : (n,) uint8
        The fits' reasons: only ``OK`` neighbours are pooled.
    errors : Errors
        The fits' parts (:class:`~curv.uncertainty.parts.Errors`): in ``k1_se``, ``k2_se``
        ``var(k_i) / sigma²``; out, at the centres, the standard errors. A vertex marked ``alone``
        (a noise level in other units than its neighbours': an's and mru's independent equations,
        or their fallback where the normals' model does not hold) is taken alone and never pooled
        into a neighbour's; ``noise_model="sampled"`` clears the marks, every vertex then in the
        same units (:func:`curv.uncertainty.noise_models.sampled_scales`).
    """
    launch(_pool_kernel, np.ascontiguousarray(centres, dtype=np.int64), ring_ptr, ring, reason, errors)
