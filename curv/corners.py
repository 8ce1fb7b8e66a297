"""Work on the corners around each vertex, one cache-sized chunk of vertices at a time, on threads.

A per-vertex sum over the faces around each vertex (normals, Meyer's operators, Rusinkiewicz's
tensor averaging) is naturally written as "for every corner, compute a value; add it to the
corner's vertex". Done over the whole mesh at once, every intermediate is an array of millions of
entries: each pass streams it from main memory and the first touch of every fresh temporary costs
page faults. Here the corners are grouped by vertex (:attr:`Mesh.vertex_corners`), and a chunk of
consecutive vertices owns a contiguous run of corners: its values are computed in arrays small
enough for the caches, summed per vertex with one ``reduceat``, and written to the chunk's own
rows of the output. Chunks share nothing, so they run on a thread pool (numpy releases the GIL in
its array kernels).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .mesh import Mesh
from ._legacy_neighbourhood import default_workers, segment_ids, segment_sum

__all__ = ["CornerChunk", "corner_chunks", "map_vertex_chunks", "CHUNK_VERTICES"]

CHUNK_VERTICES = 8192
"""Vertices per chunk: about 50k corners on a valence-6 mesh, so each per-corner array (400 KB)
stays in the L2/L3 caches while a chunk is worked on."""


@dataclass(frozen=True)
class CornerChunk:
    """The corners of the consecutive vertices ``start .. stop-1``, grouped by vertex.

    Attributes
    ----------
    start, stop : int
        Vertex range of the chunk.
    indptr : (stop - start + 1,) int64
        Local row pointers: the corners of vertex ``start + i`` are ``corners[indptr[i]:indptr[i+1]]``.
    corners : (k,) int64
        Corner ids (indices into ``mesh.face_indices``).
    local : (k,) int64
        The corner's vertex relative to the chunk (``vertex - start``): ``np.take(x[start:stop], local)``
        expands per-vertex values to the corners (``np.repeat`` would hold the GIL).
    vertex, nxt, prv : (k,) int64
        The corner's vertex (``start + local``), the vertex of the next corner of its face and that
        of the previous corner: edges ``vertex -> nxt`` and ``vertex -> prv`` leave the vertex.
    """

    start: int
    stop: int
    indptr: np.ndarray
    corners: np.ndarray
    local: np.ndarray
    vertex: np.ndarray
    nxt: np.ndarray
    prv: np.ndarray

    @property
    def counts(self) -> np.ndarray:
        """(stop - start,) int64 number of corners at each vertex."""
        return np.diff(self.indptr)

    def expand(self, values: np.ndarray) -> np.ndarray:
        """Per-vertex ``values`` of the whole mesh, (n,) or (n, c), taken at every corner's vertex: (k, ...)."""
        return np.take(values[self.start:self.stop], self.local, axis=0)

    def sum(self, values: np.ndarray) -> np.ndarray:
        """Sum per-corner ``values`` (k,) or (k, c) over the corners of each vertex: (stop - start, ...).

        Vertices without a corner get 0.
        """
        return segment_sum(values, self.indptr)

    def ring_any(self, flags: np.ndarray) -> np.ndarray:
        """(stop - start,) bool: per-vertex ``flags`` (n,) bool set at the vertex or at any edge neighbour.

        The edge neighbours of a vertex are the next and previous vertices of its corners.
        """
        near = np.take(flags, self.nxt) | np.take(flags, self.prv)
        return flags[self.start:self.stop] | self.any(near)

    def any(self, flags: np.ndarray) -> np.ndarray:
        """(stop - start,) bool: whether any corner of each vertex has ``flags`` (k,) bool set."""
        return self.sum(flags.astype(np.int32)) > 0


def corner_chunks(mesh: Mesh, chunk: int | None = None) -> list[tuple[int, int]]:
    """The vertex ranges ``(start, stop)`` of the chunks of ``mesh`` (default :data:`CHUNK_VERTICES`)."""
    n = mesh.n_vertices
    chunk = chunk or CHUNK_VERTICES
    return [(s, min(s + chunk, n)) for s in range(0, n, chunk)]


def _chunk(mesh: Mesh, start: int, stop: int) -> CornerChunk:
    indptr, corners = mesh.vertex_corners
    lo, hi = indptr[start], indptr[stop]
    ids = corners[lo:hi]
    local = indptr[start:stop + 1] - lo
    idx = mesh.face_indices
    rows = segment_ids(local)
    return CornerChunk(
        start=start, stop=stop, indptr=local, corners=ids, local=rows, vertex=rows + start,
        nxt=np.take(idx, np.take(mesh.corner_next, ids)),
        prv=np.take(idx, np.take(mesh.corner_prev, ids)),
    )


def map_vertex_chunks(mesh: Mesh, work: Callable[[CornerChunk], None], *, chunk: int | None = None,
                      workers: int | None = None) -> None:
    """Call ``work(chunk)`` for every chunk of vertices, on a thread pool.

    ``work`` must write only the rows ``chunk.start:chunk.stop`` of its outputs (chunks run
    concurrently). Exceptions propagate to the caller.

    Parameters
    ----------
    mesh : Mesh
    work : callable
        ``work(CornerChunk) -> None``.
    chunk : int, optional
        Vertices per chunk; default :data:`CHUNK_VERTICES`.
    workers : int, optional
        Threads; default :func:`curv.neighbourhood.default_workers`.
    """
    mesh.vertex_corners  # build the shared grouping once, not racing in the threads
    mesh.corner_next, mesh.corner_prev
    ranges = corner_chunks(mesh, chunk)
    workers = workers or default_workers()
    if workers == 1 or len(ranges) == 1:
        for start, stop in ranges:
            work(_chunk(mesh, start, stop))
        return
    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="curv-chunk") as pool:
        for _ in pool.map(lambda r: work(_chunk(mesh, *r)), ranges):
            pass
