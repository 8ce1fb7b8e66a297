"""The neighbour graph of a point cloud: its kNN lists made symmetric (along which normals are
oriented), and the coordinate step those lists reveal (a LAS file's scale).
"""

from __future__ import annotations

import numpy as np

from .jit import jit, jit_parallel, launch, prange

__all__ = ["GRAPH_NEIGHBOURS", "symmetric_graph", "neighbour_steps"]

GRAPH_NEIGHBOURS = 10
"""Neighbours per point of a point cloud's neighbour graph (made symmetric: about 13 edges a
point), along which normals are oriented. Supports are not searched along it: a search through
the graph inside the ball missed 0.03 % of the ball's points on uniform random samples and 5-10 %
on scan rows 5:1 apart (the rows' kNN lists stay in their row), so supports come from the grid
(:func:`curv.core.grid_balls.grid_ball`), exactly."""


@jit
def _lists(indices, q, p):
    """Whether point q's list ``indices[q]`` names p."""
    for j in range(indices.shape[1]):
        if indices[q, j] == p:
            return True
    return False


@jit_parallel
def _one_way(indices, one_way, own):
    """``one_way[p, j]``: p's j-th neighbour q does not list p (the edge q -> p is p's alone to
    give q's row); ``own[p]``: p's listed neighbours (not -1)."""
    n, k = indices.shape
    for p in prange(n):
        m = 0
        for j in range(k):
            q = indices[p, j]
            one_way[p, j] = q >= 0 and not _lists(indices, q, p)
            if q >= 0:
                m += 1
        own[p] = m


@jit
def _reverse_counts(indices, one_way, counts):
    """Add to ``counts[q]`` the points that list q where q does not list them (one pass, serial:
    rows of other points are written)."""
    n, k = indices.shape
    for p in range(n):
        for j in range(k):
            if one_way[p, j]:
                counts[indices[p, j]] += 1


@jit
def _reverse_fill(indices, one_way, fill, out):
    """Write those points into their rows, from ``fill[q]`` on (the place after q's own list)."""
    n, k = indices.shape
    for p in range(n):
        for j in range(k):
            if one_way[p, j]:
                q = indices[p, j]
                out[fill[q]] = p
                fill[q] += 1


@jit_parallel
def _own_rows(indices, indptr, out):
    """Row p: its own listed neighbours ahead of the reverse ones already written, then sorted."""
    n, k = indices.shape
    for p in prange(n):
        at = indptr[p]
        for j in range(k):
            q = indices[p, j]
            if q >= 0:
                out[at] = q
                at += 1
        out[indptr[p]:indptr[p + 1]].sort()


def symmetric_graph(indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The symmetric neighbour graph of kNN lists: q is a neighbour of p if either lists the other.

    Parameters
    ----------
    indices : (n, k) int64
        :func:`curv.core.knn.nearest_neighbours` indices (-1 entries ignored; a list names a point
        at most once, never its own).

    Returns
    -------
    indptr : (n+1,) int64
    neighbours : (a,) int64
        Row p is ``neighbours[indptr[p]:indptr[p+1]]``, sorted, without repeats or p itself.
    """
    indices = np.ascontiguousarray(indices, dtype=np.int64)
    n = indices.shape[0]
    # row p: p's own list, and the points that list p where p does not list them (no repeats, so
    # no row needs deduplicating); only those reverse edges are written one by one
    one_way = np.empty(indices.shape, np.bool_)
    own = np.empty(n, np.int64)
    launch(_one_way, indices, one_way, own)
    counts = own.copy()
    _reverse_counts(indices, one_way, counts)
    indptr = np.zeros(n + 1, np.int64)
    np.cumsum(counts, out=indptr[1:])
    neighbours = np.empty(indptr[-1], np.int64)
    _reverse_fill(indices, one_way, indptr[:-1] + own, neighbours)
    launch(_own_rows, indices, indptr, neighbours)
    return indptr, neighbours


@jit_parallel
def _steps_kernel(points, indices, parts, out):
    n, k = indices.shape
    for t in prange(parts):
        lo, hi = t * n // parts, (t + 1) * n // parts
        for a in range(3):
            out[t, a] = np.inf
        for p in range(lo, hi):
            for j in range(k):
                q = indices[p, j]
                if q >= 0:
                    for a in range(3):
                        d = abs(points[q, a] - points[p, a])
                        if 0.0 < d < out[t, a]:
                            out[t, a] = d


def neighbour_steps(points: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """(3,) float64: per axis, the smallest non-zero coordinate difference between a point and one of
    its nearest (``indices`` (n, k), -1 entries skipped); 0 where every difference is 0.

    On coordinates stored on a grid (a LAS file's scale, rounding) no two points differ by less than
    the grid's step, and near neighbours differ by one step somewhere, so this is the step; on
    coordinates of full precision it is tiny (n k differences of spread values)."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    indices = np.ascontiguousarray(indices, dtype=np.int64)
    parts = max(1, min(64, indices.shape[0]))
    out = np.empty((parts, 3))
    launch(_steps_kernel, points, indices, parts, out)
    least = out.min(axis=0)
    return np.where(np.isfinite(least), least, 0.0)
