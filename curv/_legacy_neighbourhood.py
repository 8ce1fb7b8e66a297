"""Range neighbourhoods: the support of an estimate at every vertex (paper §4.1).

The support of vertex p at range factor k is every vertex reachable from p along mesh edges while
staying inside the ball of radius ``k * mesh.longest_edge[p]`` around p: a breadth-first search that
does not leave the ball. It is computed for a block of vertices at once with sparse matrix products
(one product per BFS step), so memory is bounded by the block size, not the mesh size.
"""

from __future__ import annotations

import itertools
import os
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import cached_property
from typing import Callable, Iterator, TypeVar

import numpy as np
import scipy.sparse as sp

from .mesh import Mesh

T = TypeVar("T")

__all__ = ["Neighbourhood", "iter_neighbourhoods", "map_neighbourhoods", "default_workers", "segment_sum", "segment_ids", "neighbourhood_matrix", "DEFAULT_BLOCK_PAIRS", "block_size_for"]

TIE_TOLERANCE = 1e-9
"""Relative tolerance on the radius, so that vertices exactly at k edge lengths (regular meshes) are in."""

DEFAULT_BLOCK_PAIRS = 1_000_000
"""Target number of (vertex, neighbour) pairs per block: bounds the temporaries of the estimators
(about 40 float64 arrays of this length for the 7-unknown fit, 300 MB)."""


@dataclass
class Neighbourhood:
    """The supports of a block of vertices as CSR rows.

    Attributes
    ----------
    vertices : (c,) int64
        The centre vertices of this block.
    indptr : (c + 1,) int64
        Row pointers into ``indices``.
    indices : (nnz,) int64
        Support vertices of each centre, the centre itself excluded, in no particular order.
    radius : (c,) float64
        The radius of the ball used for each centre.
    """

    vertices: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    radius: np.ndarray

    @property
    def size(self) -> int:
        """Number of centre vertices in the block."""
        return self.vertices.size

    @property
    def counts(self) -> np.ndarray:
        """(c,) int64 number of support vertices of each centre."""
        return np.diff(self.indptr)

    @cached_property
    def rows(self) -> np.ndarray:
        """(nnz,) int64 local row (0..c-1) of every pair."""
        return segment_ids(self.indptr)

    def expand(self, values: np.ndarray) -> np.ndarray:
        """Per-centre ``values`` (c, ...) repeated for every pair of the centre: (nnz, ...)."""
        return np.take(values, self.rows, axis=0)

    @property
    def centres(self) -> np.ndarray:
        """(nnz,) int64 centre vertex of every pair (``vertices[rows]``)."""
        return self.expand(self.vertices)

    def row_sum(self, values: np.ndarray) -> np.ndarray:
        """Sum per-pair ``values`` (nnz, ...) over each row; returns (c, ...)."""
        return segment_sum(values, self.indptr)

    def any(self, flags: np.ndarray) -> np.ndarray:
        """(c,) bool: whether any support vertex has ``flags[vertex]`` set; ``flags`` is (n,) bool."""
        return self.row_sum(flags[self.indices].astype(np.float64)) > 0


def segment_ids(indptr: np.ndarray) -> np.ndarray:
    """Segment (row) of every entry of CSR-like segments: ``out[j] = i`` for ``indptr[i] <= j < indptr[i+1]``.

    Parameters
    ----------
    indptr : (c + 1,) int
        Non-decreasing segment bounds starting at 0.

    Returns
    -------
    (indptr[-1],) int64

    Notes
    -----
    Same as ``np.repeat(np.arange(c), np.diff(indptr))``, but built from a cumulative sum:
    ``np.repeat`` holds the GIL, which serialises the threads that work on blocks in parallel. For
    the same reason the hot loops expand per-row values with ``np.take(values, segment_ids(...))``
    rather than ``np.repeat``.
    """
    nnz = int(indptr[-1])
    starts = np.zeros(nnz + 1, np.int64)
    inner = indptr[1:-1]
    # each segment boundary bumps the row counter; empty segments bump it more than once
    np.add.at(starts, inner, 1)
    return np.cumsum(starts[:nnz])


def segment_sum(values: np.ndarray, indptr: np.ndarray) -> np.ndarray:
    """Sum contiguous segments: ``out[i] = values[indptr[i]:indptr[i + 1]].sum(axis=0)``.

    Parameters
    ----------
    values : (k, ...) array
    indptr : (c + 1,) int
        Non-decreasing segment bounds with ``indptr[-1] == k``.

    Returns
    -------
    (c, ...) array
        Zero for empty segments. One ``np.add.reduceat`` pass (several times faster than
        ``np.bincount`` with weights).
    """
    starts = indptr[:-1]
    nonempty = indptr[1:] > starts
    out = np.zeros((starts.size,) + values.shape[1:], dtype=values.dtype)
    if values.shape[0]:
        # reducing at the starts of non-empty segments only: each runs to the next such start,
        # which is exactly its own end since empty segments hold nothing in between
        out[nonempty] = np.add.reduceat(values, starts[nonempty], axis=0)
    return out


def _ball_filter(c: sp.csr_matrix, centre_xyz: tuple, xyz: tuple, radius2: np.ndarray) -> sp.csr_matrix:
    """Keep the entries (i, j) of ``c`` with ``|x_j - centre_i|^2 <= radius2[i]``.

    Coordinates come as separate contiguous 1-D arrays: 1-D gathers are several times faster than
    gathering rows of an (n, 3) array.
    """
    rows = segment_ids(c.indptr)
    d2 = np.zeros(c.indices.size)
    for coord, centre in zip(xyz, centre_xyz):
        d = np.take(coord, c.indices)
        d -= np.take(centre, rows)
        d2 += d * d
    keep = d2 <= np.take(radius2, rows)
    # kept entries before each row start: the new row pointers
    kept_before = np.zeros(keep.size + 1, dtype=np.int64)
    np.cumsum(keep, out=kept_before[1:])
    indptr = kept_before[c.indptr]
    return sp.csr_matrix((np.ones(indptr[-1], bool), c.indices[keep], indptr), shape=c.shape)


def _block_supports(mesh: Mesh, ids: np.ndarray, factor: float, adjacency: sp.csr_matrix,
                    xyz: tuple) -> Neighbourhood:
    n = mesh.n_vertices
    c = ids.size
    radius = factor * mesh.longest_edge[ids] * (1.0 + TIE_TOLERANCE)
    radius2 = radius**2
    centre_xyz = tuple(np.take(coord, ids) for coord in xyz)
    layer = sp.csr_matrix((np.ones(c, bool), (np.arange(c), ids)), shape=(c, n))
    previous = sp.csr_matrix((c, n), dtype=bool)
    layers = []
    if factor >= 1.0:
        # every 1-ring neighbour lies within the longest 1-ring edge: the first layer is the
        # adjacency row itself, no product or distance test needed
        first = adjacency[ids]
        first.sort_indices()
        previous, layer = layer, first
        layers.append(layer)
    while layer.nnz:
        # BFS layering: a neighbour of layer t lies in layer t-1, t or t+1, so only those two
        # layers need subtracting (not everything reached so far)
        candidates = (layer @ adjacency) > (layer + previous)
        previous, layer = layer, _ball_filter(candidates.tocsr(), centre_xyz, xyz, radius2)
        layers.append(layer)
    # merge the layers row by row without sorting: every entry goes to its row's slot, after the
    # entries of the same row in earlier layers
    per_layer = np.stack([np.diff(l.indptr) for l in layers])
    counts = per_layer.sum(axis=0)
    indptr = np.zeros(c + 1, dtype=np.int64)
    np.cumsum(counts, out=indptr[1:])
    before = indptr[:-1] + np.cumsum(per_layer, axis=0) - per_layer
    cols = np.empty(indptr[-1], dtype=np.int64)
    for layer, start in zip(layers, before):
        shift = np.take(start - layer.indptr[:-1], segment_ids(layer.indptr))
        cols[shift + np.arange(layer.nnz)] = layer.indices
    return Neighbourhood(ids, indptr, cols, radius)


def expansion_adjacency(mesh: Mesh) -> sp.csr_matrix:
    """(n, n) bool adjacency the search expands along: rows of non-manifold vertices are empty.

    A bow-tie vertex or the end of a fin joins surface sheets that are not one disc; a support may
    contain such a vertex but must not continue through it onto the other sheet.
    """
    adjacency = mesh.adjacency.astype(bool)
    bad = mesh.nonmanifold_vertices
    if bad.any():
        rows = np.repeat(np.arange(mesh.n_vertices), np.diff(adjacency.indptr))
        adjacency.data[bad[rows]] = False
        adjacency.eliminate_zeros()
    return adjacency


def block_size_for(mesh: Mesh, factor: float, *, pairs: int = DEFAULT_BLOCK_PAIRS, sample: int = 512) -> int:
    """Number of vertices per block so that a block holds about ``pairs`` neighbour pairs.

    The support size is measured on an evenly spaced sample of vertices (supports grow with the
    square of the range and with the spread of edge lengths, so a formula would misjudge it).
    """
    n = mesh.n_vertices
    if n <= sample:
        return n
    ids = np.linspace(0, n - 1, sample).astype(np.int64)
    xyz = tuple(np.ascontiguousarray(mesh.vertices[:, k]) for k in range(3))
    nb = _block_supports(mesh, ids, factor, expansion_adjacency(mesh), xyz)
    per_vertex = 1.25 * max(float(nb.counts.mean()), 1.0)  # margin for denser regions
    return int(max(64, min(n, pairs // per_vertex)))


def iter_neighbourhoods(
    mesh: Mesh, factor: float, *, block_size: int | None = None, vertices: np.ndarray | None = None
) -> Iterator[Neighbourhood]:
    """Yield the range supports of all (or the given) vertices, one block at a time.

    Parameters
    ----------
    mesh : Mesh
    factor : float
        Radius of the ball in units of each vertex's longest 1-ring edge (k of Rk, or k-1 for the
        estimators that use neighbour normals). Must be positive.
    block_size : int, optional
        Vertices per block; default from :func:`block_size_for`.
    vertices : (c,) int array, optional
        Centre vertices; default all.

    Yields
    ------
    Neighbourhood
        Blocks in order of ``vertices``.
    """
    if factor <= 0:
        raise ValueError(f"range factor must be positive, got {factor}")
    ids_all = np.arange(mesh.n_vertices) if vertices is None else np.asarray(vertices, dtype=np.int64)
    block = block_size or block_size_for(mesh, factor)
    adjacency = expansion_adjacency(mesh)
    xyz = tuple(np.ascontiguousarray(mesh.vertices[:, k]) for k in range(3))
    for start in range(0, ids_all.size, block):
        yield _block_supports(mesh, ids_all[start:start + block], factor, adjacency, xyz)


def default_workers() -> int:
    """Threads for block-parallel work: ``CURV_THREADS`` if set, else the usable cores (at most 8)."""
    env = os.environ.get("CURV_THREADS", "").strip()
    if env.isdigit() and int(env) > 0:
        return int(env)
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, 8))


def map_neighbourhoods(
    mesh: Mesh, factor: float, work: Callable[[Neighbourhood], T], *, block_size: int | None = None,
    workers: int | None = None,
) -> Iterator[tuple[Neighbourhood, T]]:
    """Compute the supports block by block and apply ``work`` to each, on a pool of threads.

    numpy's array kernels and scipy's sparse products release the GIL, so blocks run in parallel.
    Results come back in block order; at most ``workers + 1`` blocks are in flight, which bounds
    memory. Closing the generator (cancel) drops the queued blocks and waits for the running ones.

    Parameters
    ----------
    mesh : Mesh
    factor : float
        As in :func:`iter_neighbourhoods`.
    work : callable
        ``work(neighbourhood) -> result`` for one block; must not touch shared state.
    block_size : int, optional
    workers : int, optional
        Threads; default :func:`default_workers`.

    Yields
    ------
    (Neighbourhood, result)
    """
    if factor <= 0:
        raise ValueError(f"range factor must be positive, got {factor}")
    block = block_size or block_size_for(mesh, factor)
    adjacency = expansion_adjacency(mesh)
    xyz = tuple(np.ascontiguousarray(mesh.vertices[:, k]) for k in range(3))
    starts = range(0, mesh.n_vertices, block)

    def task(start: int):
        ids = np.arange(start, min(start + block, mesh.n_vertices), dtype=np.int64)
        nb = _block_supports(mesh, ids, factor, adjacency, xyz)
        return nb, work(nb)

    workers = workers or default_workers()
    if workers == 1 or len(starts) == 1:
        for start in starts:
            yield task(start)
        return
    pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="curv")
    pending: deque = deque()
    todo = iter(starts)
    try:
        for start in itertools.islice(todo, workers + 1):
            pending.append(pool.submit(task, start))
        while pending:
            result = pending.popleft().result()
            nxt = next(todo, None)
            if nxt is not None:
                pending.append(pool.submit(task, nxt))
            yield result
    finally:
        for fut in pending:
            fut.cancel()
        pool.shutdown(wait=True)


def neighbourhood_matrix(mesh: Mesh, factor: float) -> sp.csr_matrix:
    """(n, n) boolean CSR matrix of all supports (centre excluded); for tests and small meshes."""
    parts = list(iter_neighbourhoods(mesh, factor))
    indptr = [np.zeros(1, np.int64)]
    offset = 0
    for p in parts:
        indptr.append(p.indptr[1:] + offset)
        offset += p.indices.size
    ind = np.concatenate([p.indices for p in parts])
    return sp.csr_matrix(
        (np.ones(ind.size, bool), ind, np.concatenate(indptr)), shape=(mesh.n_vertices, mesh.n_vertices)
    )
