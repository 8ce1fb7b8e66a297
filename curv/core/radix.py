"""A stable sort of non-negative integer keys in parallel: the order behind a point cloud's grid
(:func:`curv.core.grid.build_grid`, points by cell) and behind the spanning tree that orients its
normals (:mod:`curv.point_normals.orientation`, edges by weight).

``np.argsort(keys, kind="stable")`` of int64 keys is a merge sort, one thread; this is a
least-significant-digit radix sort, :data:`RADIX_BITS` bits a pass, each pass in parallel: every
slice of the keys counts its digits, the slices' counts are laid out digit by digit and slice by
slice, and every slice puts its keys at its own places. Each pass keeps the order of equal digits,
so the order is exactly ``np.argsort(keys, kind="stable")`` whatever the number of threads or
slices (ties keep their index order).
"""

from __future__ import annotations

import numpy as np

from .jit import jit, jit_parallel, launch, prange, slice_bounds

__all__ = ["stable_order", "stable_sort", "RADIX_BITS"]

RADIX_BITS = 11
"""Bits per pass (2048 buckets: a slice's counts stay in the cache)."""

_SLICE = 1 << 16
"""Keys per slice at least (the slices' counts are laid out one by one between the passes)."""


@jit
def _lay_out(count, m):
    """Turn ``count`` (parts, buckets), the digits' counts of each slice, into where each slice
    puts its first key of each digit (digit by digit, slice by slice); False when one digit holds
    all ``m`` keys (the pass would not move any)."""
    parts, buckets = count.shape
    at = 0
    for d in range(buckets):
        total = 0
        for t in range(parts):
            c = count[t, d]
            count[t, d] = at + total
            total += c
        if total == m:
            return False
        at += total
    return True


@jit_parallel
def _radix_passes(keys, bits, rank, spare_rank):
    """Sort ``rank`` (the identity on entry) by ``keys``' lowest ``bits`` bits, stably; return the
    array that holds the order (``rank`` or ``spare_rank``) and the keys in that order (a copy)."""
    m = keys.size
    parts = max(1, min(64, m // _SLICE))
    buckets = 1 << RADIX_BITS
    count = np.empty((parts, buckets), np.int64)
    keys = keys.copy()
    spare_keys = np.empty(m, np.int64)
    for shift in range(0, bits, RADIX_BITS):
        for t in prange(parts):
            start, stop = slice_bounds(0, m, t, parts)
            for d in range(buckets):
                count[t, d] = 0
            for i in range(start, stop):
                count[t, (keys[i] >> shift) & (buckets - 1)] += 1
        if not _lay_out(count, m):
            continue
        for t in prange(parts):
            start, stop = slice_bounds(0, m, t, parts)
            for i in range(start, stop):
                d = (keys[i] >> shift) & (buckets - 1)
                at = count[t, d]
                count[t, d] = at + 1
                spare_keys[at] = keys[i]
                spare_rank[at] = rank[i]
        keys, spare_keys = spare_keys, keys
        rank, spare_rank = spare_rank, rank
    return rank, keys


def stable_order(keys: np.ndarray, bits: int | None = None, dtype=np.int64) -> np.ndarray:
    """``np.argsort(keys, kind="stable")`` of non-negative integer keys, in parallel
    (:func:`stable_sort`'s order)."""
    return stable_sort(keys, bits, dtype)[0]


def stable_sort(keys: np.ndarray, bits: int | None = None, dtype=np.int64) -> tuple[np.ndarray, np.ndarray]:
    """``np.argsort(keys, kind="stable")`` of non-negative integer keys and the keys in that order,
    in parallel.

    Parameters
    ----------
    keys : (m,) int64
        Non-negative (e.g. grid cells, or the bit patterns of non-negative finite floats, which
        order as their values).
    bits : int, optional
        The keys' significant bits (default: those of the largest key).
    dtype : numpy integer type
        Of the order (int32 halves the memory where m < 2^31).

    Returns
    -------
    order : (m,) ``dtype``
        The positions of the keys in ascending order, equal keys in index order.
    sorted_keys : (m,) int64
        ``keys[order]``.
    """
    keys = np.ascontiguousarray(keys, dtype=np.int64)
    if bits is None:
        bits = int(keys.max(initial=0)).bit_length()
    rank = np.arange(keys.size, dtype=dtype)
    return launch(_radix_passes, keys, int(bits), rank, np.empty(keys.size, dtype))
