"""Range neighbourhoods: the support of an estimate at a vertex (paper §4.1).

The support of vertex p is every vertex reachable from p along mesh edges while staying inside the
ball of radius ``r(p)`` around p (:func:`curv.core.ranges.ball_radii` says what ``r(p)`` is): a
breadth-first search that never leaves the ball. :func:`ball_support` is that search for one
vertex, a numba helper that every support-based estimator calls inside its own per-vertex loop, so
no (centre, neighbour) pair arrays are ever built. Each thread brings its own scratch (a visited
stamp per vertex, a queue), allocated once per kernel call and reused for every centre.

The search expands along :func:`expansion_adjacency`: a support may contain a non-manifold vertex
(a bow tie, the end of a fin) but does not continue through it onto another sheet.

**What a search walks.** :func:`expansion_adjacency` returns a typed bundle that says which
(:mod:`curv.core.support`): an ``EdgeSearch`` (CSR edges), or a ``GridSearch`` (a point cloud's
grid). Kernels take its halves as :func:`ball_support`'s ``indptr, indices``; numba picks the walk
along edges or the exact ball through the grid (:func:`curv.core.grid_balls.grid_ball`) by the type of the
first half (a CSR's array, a grid's tuple), so every estimator kernel runs on meshes and points.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Iterator

import weakref

import numpy as np
from numba.core import types
from numba.extending import overload

from ..core.jit import jit, jit_parallel, launch, prange, thread_slices, threads
from ..core.grid_balls import grid_ball
from ..core.mesh import Mesh
from ..core.ranges import Range, ball_radii
from ..core.support import EdgeSearch, GridSearch, support_of

__all__ = ["ball_support", "mesh_ball_support", "start_ball_support", "widen_ball_support", "new_scratch", "new_queues",
           "expansion_adjacency", "coordinate_columns", "all_centres", "blocked_vertices", "cached_with_mesh",
           "latest_with_mesh", "supports", "support_sizes", "Neighbourhood", "iter_neighbourhoods"]

def ball_support(p, radius2, indptr, indices, x, y, z, stamp, queue):
    """The support of vertex ``p``: the mesh search (:func:`mesh_ball_support`) or a point cloud's ball.

    Called inside numba kernels, where the implementation is chosen by the type of ``indptr``:
    an array (mesh CSR edges) or a tuple (a point cloud's grid, :func:`expansion_adjacency`).
    Same arguments and results as :func:`mesh_ball_support`.
    """
    if isinstance(indptr, tuple):
        count = grid_ball(p, radius2, indptr, indices, x, y, z, queue)
        return count, queue
    return mesh_ball_support(p, radius2, indptr, indices, x, y, z, stamp, queue)


@overload(ball_support, jit_options={"cache": True, "nogil": True, "error_model": "numpy"})
def _ball_support_for(p, radius2, indptr, indices, x, y, z, stamp, queue):
    if isinstance(indptr, types.BaseTuple):
        def on_points(p, radius2, indptr, indices, x, y, z, stamp, queue):
            if queue.size < x.size:
                queue = np.empty(x.size, np.int64)
            count = grid_ball(p, radius2, indptr, indices, x, y, z, queue)
            return count, queue
        return on_points

    def on_mesh(p, radius2, indptr, indices, x, y, z, stamp, queue):
        return mesh_ball_support(p, radius2, indptr, indices, x, y, z, stamp, queue)
    return on_mesh


@jit
def mesh_ball_support(p, radius2, indptr, indices, x, y, z, stamp, queue):
    """The support of vertex ``p``: breadth-first search along edges, never leaving the ball.

    Parameters
    ----------
    p : int
        Centre vertex.
    radius2 : float
        Squared ball radius.
    indptr, indices : (n+1,), (a,) int64
        :func:`expansion_adjacency` in CSR form.
    x, y, z : (n,) float64
        Vertex coordinates.
    stamp : (n,) int64
        The calling thread's visited marks: ``stamp[q] == p + 1`` once q was seen from p (0: never
        seen, so that zeroed scratch costs no work, :func:`new_scratch`). Never reset: a new centre
        has a new mark. Take the thread's row of the stamps once, outside the loop
        over vertices: slicing ``stamps[t]`` anew for every vertex made a fit kernel 8x slower.
    queue : (n,) int64
        The calling thread's queue, a slot per vertex (its row of :func:`new_queues`): a support
        can never overflow it, and pages it never reaches cost no memory.

    Returns
    -------
    count : int
        ``queue[0] == p`` and ``queue[1:count]`` is the support (centre excluded), in BFS order.
    queue : (n,) int64
        The same queue (kept in the return so that callers read ``count, queue = ...``).
    """
    # the levelled walk with one level (the range rule has one owner); nothing waits beyond it
    count = start_ball_support(p, stamp, queue)
    count, _, _ = widen_ball_support(p, radius2, False, (indptr, indices), (x, y, z), stamp, queue, (count, 0, 0), None)
    return count, queue


@jit
def start_ball_support(p, stamp, queue):
    """Begin a levelled support of ``p`` (:func:`widen_ball_support`): ``queue[0] = p``, p seen.
    Returns the count, 1."""
    stamp[p] = p + 1
    queue[0] = p
    return 1


@jit
def widen_ball_support(p, radius2, keep_outside, adjacency, coords, stamp, queue, state, waiting):
    """Widen the support of ``p`` to the ball of squared radius ``radius2`` (not smaller than the
    last call's): one walk serves a whole series of radii.

    The support at each radius is the vertices connected to p through vertices within that radius (the range
    rule; :func:`mesh_ball_support` is this walk with one level): the search goes on from where the last
    radius stopped, and a vertex it met beyond the last radius (kept in ``waiting`` with its squared distance)
    joins the queue at the first radius that holds it. Every vertex of the queue has been expanded once, so
    each of their neighbours is in the queue or waits: nothing connected is missed. The order within the queue
    is the walk's (for one level, breadth-first from p).

    Parameters
    ----------
    p : int
        Centre vertex (start with :func:`start_ball_support`: ``state = (1, 0, 0)``).
    radius2 : float
        Squared radius of this level.
    keep_outside : bool
        Keep the vertices met beyond ``radius2`` for a later, larger radius (False on the last).
    adjacency, coords : tuples ``(indptr, indices)``, ``(x, y, z)``
        As in :func:`mesh_ball_support`.
    stamp, queue : (n,) int64
        As in :func:`mesh_ball_support` (the same ``stamp`` mark ``p + 1`` across the levels).
    state : tuple ``(count, head, pending)`` of int
        What the last call returned: support size, vertices expanded, vertices waiting.
    waiting : tuple ``(outside (n,) int64, outside_d2 (n,) float64)`` or None
        The vertices met beyond the last radius and their squared distances to p (None: one level,
        ``keep_outside`` False; numba compiles that case without their code).

    Returns
    -------
    count, head, pending : int
        ``queue[:count]`` is the support at ``radius2`` (p first), this call's rows from the last count on.
    """
    indptr, indices = adjacency
    x, y, z = coords
    count, head, pending = state
    px, py, pz = x[p], y[p], z[p]
    mark = p + 1
    if waiting is not None:
        outside, outside_d2 = waiting
        kept = 0
        for i in range(pending):
            if outside_d2[i] <= radius2:
                queue[count] = outside[i]
                count += 1
            else:
                outside[kept] = outside[i]
                outside_d2[kept] = outside_d2[i]
                kept += 1
        pending = kept
    while head < count:
        v = queue[head]
        head += 1
        for j in range(indptr[v], indptr[v + 1]):
            q = indices[j]
            if stamp[q] == mark:
                continue
            stamp[q] = mark
            dx = x[q] - px
            dy = y[q] - py
            dz = z[q] - pz
            d2 = dx * dx + dy * dy + dz * dz
            if d2 <= radius2:
                queue[count] = q
                count += 1
            elif keep_outside:
                if waiting is not None:
                    waiting[0][pending] = q
                    waiting[1][pending] = d2
                    pending += 1
    return count, head, pending


def new_scratch(n_vertices: int, parts: int) -> np.ndarray:
    """(parts, n) int64 visited stamps for :func:`ball_support`, one row per thread slice.

    Zeroed (no vertex seen): the pages come zeroed from the system, so a search over a small region
    touches only the pages it reaches.
    """
    return np.zeros((parts, n_vertices), np.int64)


def new_queues(n_vertices: int, parts: int) -> np.ndarray:
    """(parts, n) int64 queues for :func:`ball_support`, one row per thread slice.

    Uninitialised: a page the searches never reach is never touched and costs no memory.
    """
    return np.empty((parts, n_vertices), np.int64)


def expansion_adjacency(mesh: Mesh, blocked: np.ndarray | None = None, radii: np.ndarray | None = None
                        ) -> EdgeSearch | GridSearch:
    """The edges a support search expands along, as CSR ``EdgeSearch(indptr (n+1,), indices (a,))`` int64.

    The mesh adjacency with the rows of non-manifold vertices (and of ``blocked`` ones) emptied: a
    support may reach such a vertex but must not continue through it onto another sheet, or across
    a crease (:mod:`curv.core.features` passes the feature vertices as ``blocked``).

    Parameters
    ----------
    mesh : Mesh
    blocked : (n,) bool, optional
        More vertices not to expand through.

    Notes
    -----
    The plain form (no ``blocked``) is cached with the mesh, and the form for the latest
    ``blocked`` array (the same object again: a cached feature set's vertices), so that an estimate
    over a small region does no O(n) work to build it again. Where the input's provider gives a
    grid (a cloud, :meth:`curv.core.support.Support.search_grid`, its cells suited to ``radii``):
    that ``GridSearch``, which :func:`ball_support` searches instead of edges.
    """
    if (grid := support_of(mesh).search_grid(radii)) is not None:
        return grid
    if blocked is None or not blocked.any():
        return EdgeSearch(*cached_with_mesh(mesh, "expansion", lambda: _expansion(mesh, mesh.nonmanifold_vertices)))
    return EdgeSearch(*latest_with_mesh(mesh, "blocked expansion", (blocked,),
                                        lambda: _expansion(mesh, mesh.nonmanifold_vertices | blocked)))


def _expansion(mesh: Mesh, bad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    indptr, indices = mesh.neighbour_lists
    if bad.any():
        keep = np.repeat(~bad, np.diff(indptr))
        counts = np.where(bad, 0, np.diff(indptr))
        indptr = np.zeros(mesh.n_vertices + 1, np.int64)
        np.cumsum(counts, out=indptr[1:])
        indices = indices[keep]
        for arr in (indptr, indices):
            arr.setflags(write=False)
    return indptr, indices


def all_centres(n_vertices: int, centres: np.ndarray | None) -> np.ndarray:
    """(c,) int64 centre vertices of a kernel run: ``centres``, or every vertex when None."""
    if centres is None:
        return np.arange(n_vertices, dtype=np.int64)
    return np.ascontiguousarray(centres, dtype=np.int64)


def blocked_vertices(features) -> np.ndarray | None:
    """(n,) bool vertices a support search must not expand through for a :class:`curv.core.features.FeatureSet`."""
    return None if features is None or not features.any else features.vertices


def coordinate_columns(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The vertex coordinates as three contiguous (n,) float64 columns (cached with the mesh, read-only)."""
    def build():
        columns = tuple(np.ascontiguousarray(mesh.vertices[:, c]) for c in range(3))
        for arr in columns:
            arr.setflags(write=False)
        return columns

    return cached_with_mesh(mesh, "columns", build)


_CACHE: "weakref.WeakKeyDictionary[Mesh, dict]" = weakref.WeakKeyDictionary()


def cached_with_mesh(mesh: Mesh, key: str, build):
    """``build()`` once per mesh and ``key`` (the mesh is immutable; the entry goes with it)."""
    entry = _CACHE.setdefault(mesh, {})
    if key not in entry:
        entry[key] = build()
    return entry[key]


def latest_with_mesh(mesh: Mesh, key: str, token: tuple, build):
    """``build()`` for ``token``, keeping only the latest token's value per mesh and ``key``.

    For what depends on a choice as well as on the mesh (a feature angle, a feature set's arrays):
    asking again with the same choice costs nothing, a new choice replaces the old value (so a user
    trying many angles does not pile up whole-mesh arrays). ``token`` is a tuple of floats (compared
    by value) and arrays (compared by identity; the entry holds them, so their ids stay theirs).
    """
    entry = _CACHE.setdefault(mesh, {})
    held = entry.get(key)  # one read: another thread may replace the entry meanwhile
    if held is not None and len(held[0]) == len(token) and all(_same(a, b) for a, b in zip(held[0], token)):
        return held[1]
    held = None
    entry.pop(key, None)  # free the old value before building the new one
    value = build()
    entry[key] = (token, value)
    return value


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return a is b
    return type(a) is type(b) and a == b


@jit_parallel
def _search_supports(centres, radius2, indptr, indices, coords, scratch, counts, flagging, members):
    """The support of every centre, a slice of centres per thread (:func:`_search_setup`).

    Parameters
    ----------
    centres : (c,) int64
    radius2 : (n,) float64
        Squared ball radius of every vertex.
    indptr, indices
        :func:`expansion_adjacency` (CSR edges, or a point cloud's grid).
    coords : tuple of three (n,) float64
        x, y, z.
    scratch : tuple
        ``(stamps, queues, starts, stops)``: per-thread stamps and queues (:func:`new_scratch`,
        :func:`new_queues`) and each thread's slice of ``centres``.
    counts : (c,) int64
        Out: the support size of centre i, itself excluded.
    flagging : tuple ``(flags, flagged)`` or None
        ``flags`` (n,) bool; out ``flagged`` (c,) bool: the support (the centre included) holds a
        flagged vertex. None: not asked for (numba compiles that case without the loop).
    members : tuple ``(out_ptr, out)`` or None
        Out: the members of centre i (BFS order, the centre left out) in
        ``out[out_ptr[i]:out_ptr[i + 1]]``; None: not asked for.
    """
    x, y, z = coords
    stamps, queues, starts, stops = scratch
    for t in prange(starts.size):
        queue = queues[t]
        stamp = stamps[t]
        for i in range(starts[t], stops[t]):
            p = centres[i]
            count, queue = ball_support(p, radius2[p], indptr, indices, x, y, z, stamp, queue)
            counts[i] = count - 1
            if flagging is not None:
                hit = False
                for j in range(count):
                    hit = hit or flagging[0][queue[j]]
                flagging[1][i] = hit
            if members is not None:
                start = members[0][i]
                for j in range(1, count):
                    members[1][start + j - 1] = queue[j]


def _search_setup(mesh, radii, vertices, blocked=None):
    """What a support search over some centres needs: the centres (c,), squared radii (n,), the
    expansion CSR (or grid), the coordinate columns and the scratch of :func:`_search_supports`."""
    centres = all_centres(mesh.n_vertices, vertices)
    radius2 = np.ascontiguousarray(radii, dtype=np.float64) ** 2
    indptr, indices = expansion_adjacency(mesh, blocked, radii)
    parts = max(1, min(threads(), centres.size))
    starts, stops = thread_slices(centres.size, parts)
    scratch = (new_scratch(mesh.n_vertices, parts), new_queues(mesh.n_vertices, parts), starts, stops)
    return centres, radius2, indptr, indices, coordinate_columns(mesh), scratch


def support_sizes(mesh: Mesh, radii: np.ndarray, vertices: np.ndarray | None = None,
                  flags: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """How many vertices each support holds, and whether it holds a flagged one, without storing it.

    Parameters
    ----------
    mesh : Mesh
    radii : (n,) float64
        Ball radius of every vertex (:func:`curv.core.ranges.ball_radii`).
    vertices : (c,) int, optional
        Centres; default all.
    flags : (n,) bool, optional
        E.g. ``mesh.border_vertices``; default none flagged.

    Returns
    -------
    counts : (c,) int64
        Support size of each centre, itself excluded.
    flagged : (c,) bool
        The support (the centre included) holds a flagged vertex.
    """
    centres, radius2, indptr, indices, coords, scratch = _search_setup(mesh, radii, vertices)
    counts = np.empty(centres.size, np.int64)
    if flags is None:
        launch(_search_supports, centres, radius2, indptr, indices, coords, scratch, counts, None, None)
        return counts, np.zeros(centres.size, np.bool_)
    flagged = np.empty(centres.size, np.bool_)
    launch(_search_supports, centres, radius2, indptr, indices, coords, scratch, counts,
           (np.ascontiguousarray(flags, np.bool_), flagged), None)
    return counts, flagged


def supports(mesh: Mesh, radii: np.ndarray, vertices: np.ndarray | None = None, *,
             blocked: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The supports of some vertices as CSR rows (for tests, the study's exclusion zone, small jobs).

    Parameters
    ----------
    mesh, radii, vertices
        As in :func:`support_sizes`.
    blocked : (n,) bool, optional
        Vertices the search reaches but does not expand through (the feature vertices of
        :mod:`curv.core.features`), as in :func:`expansion_adjacency`.

    Returns
    -------
    indptr : (c+1,) int64
    indices : (nnz,) int64
        Support of centre i (itself excluded) in ``indices[indptr[i]:indptr[i+1]]``, in BFS order.
    """
    centres, radius2, indptr, indices, coords, scratch = _search_setup(mesh, radii, vertices, blocked)
    counts = np.empty(centres.size, np.int64)
    launch(_search_supports, centres, radius2, indptr, indices, coords, scratch, counts, None, None)
    out_ptr = np.zeros(centres.size + 1, np.int64)
    np.cumsum(counts, out=out_ptr[1:])
    out = np.empty(out_ptr[-1], np.int64)
    scratch[0].fill(0)
    launch(_search_supports, centres, radius2, indptr, indices, coords, scratch, counts, None, (out_ptr, out))
    return out_ptr, out


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
        Support vertices of each centre, the centre itself excluded, in BFS order.
    radius : (c,) float64
        The radius of the ball of each centre.
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
        """(nnz,) int64 local row (0..c-1) of every entry."""
        return np.repeat(np.arange(self.size), self.counts)

    @property
    def centres(self) -> np.ndarray:
        """(nnz,) int64 centre vertex of every entry."""
        return self.vertices[self.rows]

    def any(self, flags: np.ndarray) -> np.ndarray:
        """(c,) bool: whether any support vertex has ``flags[vertex]`` set; ``flags`` is (n,) bool."""
        return np.bincount(self.rows, weights=flags[self.indices], minlength=self.size) > 0


def iter_neighbourhoods(mesh: Mesh, factor: float, *, block_size: int | None = None,
                        vertices: np.ndarray | None = None) -> Iterator[Neighbourhood]:
    """Yield the supports at range factor ``factor`` of all (or the given) vertices, a block at a time.

    Parameters
    ----------
    mesh : Mesh
    factor : float
        Ball radius in units of each vertex's longest 1-ring edge. Must be positive.
    block_size : int, optional
        Centres per block; default 65536.
    vertices : (c,) int array, optional
        Centre vertices; default all.

    Yields
    ------
    Neighbourhood
        Blocks in order of ``vertices``.
    """
    if not factor > 0:
        raise ValueError(f"range factor must be positive, got {factor}")
    radii = ball_radii(mesh, Range(k=float(factor)), uses_normals=False)
    ids_all = np.arange(mesh.n_vertices) if vertices is None else np.asarray(vertices, dtype=np.int64)
    block = block_size or 65536
    for start in range(0, ids_all.size, block):
        ids = ids_all[start:start + block]
        indptr, indices = supports(mesh, radii, ids)
        yield Neighbourhood(ids, indptr, indices, radii[ids])
