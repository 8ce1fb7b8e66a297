"""The corners of a mesh grouped by vertex, and how a corner steps to its neighbours in its face.

:func:`group_corners` groups the corners by their vertex (a stable counting sort, linear time).
Within a face, a corner's next and previous corners are :func:`next_corner` and
:func:`prev_corner`: from the mesh's corner links on a polygon mesh, by arithmetic on a triangle
mesh (face f has the corners 3f, 3f + 1, 3f + 2), where the links are None and numba compiles the
arithmetic alone. Also the small sorts and the union-find root the other connectivity kernels use.
"""

from __future__ import annotations

import numpy as np

from ..jit import jit, jit_parallel, launch, prange, threads

__all__ = ["group_corners", "next_corner", "prev_corner", "face_of", "corner_links", "find_root", "sort_pairs",
           "insertion_sort", "thread_slice", "ring_width", "KERNELS"]

SMALL_GROUP = 32
"""The halfedges around a vertex are sorted by insertion up to this many; more (a vertex with a
huge fan) by a heap sort, so that no vertex costs quadratic time."""


def group_corners(vertex_of: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Stable counting sort of items by their vertex, a slice of the items per thread.

    Each thread counts its slice's items per vertex; a thread's items at v go after those of the
    earlier slices, so the order within a vertex stays increasing.

    Parameters
    ----------
    vertex_of : (h,) int64
        Vertex of each item (corner), in ``0 .. n-1``.
    n : int

    Returns
    -------
    indptr : (n + 1,) int64
    items : (h,) int64
        The items of vertex v are ``items[indptr[v]:indptr[v + 1]]``, in increasing order.
    """
    parts = max(1, min(threads(), vertex_of.size // 65536))
    slots = np.zeros((parts, n), np.int64)
    launch(_count_by_vertex, vertex_of, slots)
    indptr = np.empty(n + 1, np.int64)
    _first_slots(slots, indptr)
    items = np.empty(vertex_of.size, np.int64)
    launch(_place_by_vertex, vertex_of, slots, items)
    return indptr, items


@jit_parallel
def _count_by_vertex(vertex_of, counts):
    parts = counts.shape[0]
    for t in prange(parts):
        lo, hi = thread_slice(vertex_of.size, t, parts)
        row = counts[t]
        for c in range(lo, hi):
            row[vertex_of[c]] += 1


@jit
def _first_slots(counts, indptr):
    """Turn the per-slice counts (parts, n) into each slice's first slot at each vertex, in place; fill indptr."""
    parts, n = counts.shape
    total = 0
    for v in range(n):
        indptr[v] = total
        for t in range(parts):
            k = counts[t, v]
            counts[t, v] = total
            total += k
    indptr[n] = total


@jit_parallel
def _place_by_vertex(vertex_of, slots, items):
    parts = slots.shape[0]
    for t in prange(parts):
        lo, hi = thread_slice(vertex_of.size, t, parts)
        row = slots[t]
        for c in range(lo, hi):
            v = vertex_of[c]
            items[row[v]] = c
            row[v] += 1


@jit
def _before(key, value, i, j):
    return key[i] < key[j] or (key[i] == key[j] and value[i] < value[j])


@jit
def _sift_down(key, value, root, end):
    while 2 * root + 1 < end:
        child = 2 * root + 1
        if child + 1 < end and _before(key, value, child, child + 1):
            child += 1
        if not _before(key, value, root, child):
            return
        key[root], key[child] = key[child], key[root]
        value[root], value[child] = value[child], value[root]
        root = child


@jit
def sort_pairs(key, value, k):
    """Sort the pairs ``(key[i], value[i])``, ``i < k``, in increasing order (key first).

    By insertion when short; a heap sort beyond :data:`SMALL_GROUP`, so that a vertex with a
    huge fan does not cost quadratic time.
    """
    if k <= SMALL_GROUP:
        for i in range(1, k):
            kk, v = key[i], value[i]
            j = i - 1
            while j >= 0 and (key[j] > kk or (key[j] == kk and value[j] > v)):
                key[j + 1], value[j + 1] = key[j], value[j]
                j -= 1
            key[j + 1], value[j + 1] = kk, v
        return
    for root in range(k // 2 - 1, -1, -1):
        _sift_down(key, value, root, k)
    for end in range(k - 1, 0, -1):
        key[0], key[end] = key[end], key[0]
        value[0], value[end] = value[end], value[0]
        _sift_down(key, value, 0, end)


@jit
def insertion_sort(a, k):
    """Sort ``a[:k]`` in place (k small)."""
    for i in range(1, k):
        v = a[i]
        j = i - 1
        while j >= 0 and a[j] > v:
            a[j + 1] = a[j]
            j -= 1
        a[j + 1] = v


@jit
def thread_slice(count, t, parts):
    """Items ``lo .. hi - 1`` of slice t of ``parts`` equal slices of ``range(count)``."""
    return count * t // parts, count * (t + 1) // parts


def ring_width(indptr: np.ndarray) -> int:
    """Scratch length for the halfedges around the busiest vertex: two per corner."""
    return int(2 * np.diff(indptr).max(initial=0)) + 1


@jit
def find_root(parent, i):
    """The root of ``i`` in a union-find forest ``parent`` (path halving: the path is shortened on the way)."""
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@jit
def next_corner(c, corner_next):
    """The next corner of corner c in its face: ``corner_next[c]``, or by arithmetic when ``corner_next`` is
    None (a triangle mesh, :attr:`curv.Mesh.corner_steps`: face f has the corners 3f, 3f + 1, 3f + 2)."""
    if corner_next is None:
        return c - 2 if c % 3 == 2 else c + 1
    return np.int64(corner_next[c])


@jit
def prev_corner(c, corner_prev):
    """The previous corner of corner c in its face (as :func:`next_corner`)."""
    if corner_prev is None:
        return c + 2 if c % 3 == 0 else c - 1
    return np.int64(corner_prev[c])


@jit
def face_of(c, corner_face):
    """The face of corner c: ``corner_face[c]``, or ``c // 3`` when ``corner_face`` is None (a triangle mesh,
    as :func:`next_corner`)."""
    if corner_face is None:
        return c // 3
    return np.int64(corner_face[c])


@jit_parallel
def corner_links(offsets, corner_next, corner_prev):
    """The next and previous corner of every corner within its face (faces are contiguous runs).

    Parameters
    ----------
    offsets : (m + 1,) int64
        Face f's corners are ``offsets[f] .. offsets[f + 1] - 1``.
    corner_next, corner_prev : (h,) int64
        Filled.
    """
    for f in prange(offsets.size - 1):
        first, last = offsets[f], offsets[f + 1] - 1
        for c in range(first, last + 1):
            corner_next[c] = first if c == last else c + 1
            corner_prev[c] = last if c == first else c - 1


KERNELS = (_count_by_vertex, _first_slots, _place_by_vertex, corner_links)
"""The numba dispatchers of this module (for :func:`curv.core.jit.compile_pending`)."""
