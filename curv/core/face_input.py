"""A mesh's faces as given (an (m, k) array, padded with -1, or a list of polygons) checked and
flattened into the form :class:`curv.Mesh` stores: every face's vertex indices one after the other,
with the offsets where each face starts.
"""

from __future__ import annotations

import numpy as np

from .errors import MeshError

__all__ = ["flat_faces", "negative_corner", "missing_corner", "block_corner_fault"]


def flat_faces(faces, n_vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """Flatten ``faces`` into ``(indices, offsets)``; validate sizes and index range.

    Parameters
    ----------
    faces : (m, k) array_like of int, or sequence of sequences of int
        Polygons as vertex indices; a 2-D array may pad shorter polygons with trailing ``-1``.
    n_vertices : int
        The mesh's vertex count (every index must be below it).

    Returns
    -------
    indices : (sum of face sizes,) int64
    offsets : (m + 1,) int64
        Face i is ``indices[offsets[i]:offsets[i + 1]]``.

    Raises
    ------
    MeshError
        Naming the first face that is wrong and how.
    """
    if isinstance(faces, np.ndarray) and faces.dtype != object:
        f = faces
        if f.ndim != 2:
            raise MeshError(f"faces must be a 2-D array (m, k) or a list of polygons, got shape {f.shape}")
        if f.size and not np.issubdtype(f.dtype, np.integer):
            if not np.all(np.mod(f, 1) == 0):
                raise MeshError("face indices must be integers")
        low = f.min() if f.size else -1
        if low >= 0 and f.shape[1] >= 3 and f.max() < n_vertices:
            # the usual input, a plain (m, k) array of valid indices: no padding mask, no sizes to add up
            # and one pass for each bound, read from the caller's (often int32) array before the copy
            m, k = f.shape
            return f.astype(np.int64).reshape(-1), np.arange(0, m * k + 1, k, dtype=np.int64)
        f = f.astype(np.int64)
        if f.size and low >= 0:  # no padding: every row is a whole polygon (no mask to build)
            sizes = np.full(f.shape[0], f.shape[1], np.int64)
            indices = f.reshape(-1)
        else:
            # A padded array marks unused trailing slots with -1.
            pad = f == -1
            trailing = np.flip(np.cumprod(np.flip(pad, axis=1), axis=1), axis=1).astype(bool)
            sizes = (~trailing).sum(axis=1)
            indices = f[~trailing]
    else:
        try:
            polys = [np.asarray(p).reshape(-1) for p in faces]
        except (TypeError, ValueError) as exc:
            raise MeshError(f"faces are not index lists: {exc}") from None
        for i, p in enumerate(polys):
            if p.size and not np.issubdtype(p.dtype, np.integer):
                if not (np.issubdtype(p.dtype, np.number) and np.all(np.mod(p, 1) == 0)):
                    raise MeshError(f"face {i} has non-integer indices")
        sizes = np.array([p.size for p in polys], dtype=np.int64)
        indices = np.concatenate(polys).astype(np.int64) if polys else np.zeros(0, np.int64)
    if sizes.size == 0:
        raise MeshError("mesh has no faces")
    small = np.flatnonzero(sizes < 3)
    if small.size:
        raise MeshError(f"face {small[0]} has {sizes[small[0]]} vertices; a face needs at least 3")
    offsets = np.zeros(sizes.size + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    if indices.size and (indices.min() < 0 or indices.max() >= n_vertices):
        def face_of(corner: int) -> int:
            return int(np.searchsorted(offsets, corner, side="right")) - 1

        neg = np.flatnonzero(indices < 0)
        if neg.size:
            raise MeshError(negative_corner(face_of(neg[0]), int(indices[neg[0]])))
        high = np.flatnonzero(indices >= n_vertices)
        raise MeshError(missing_corner(face_of(high[0]), int(indices[high[0]]), n_vertices))
    return indices, offsets


def negative_corner(face: int, index: int) -> str:
    """The words for a face with a negative vertex index (every reader says it the same way)."""
    return f"face {face} has a negative vertex index {index}"


def missing_corner(face: int, index: int, n_vertices: int) -> str:
    """The words for a face that refers to a vertex past the last one."""
    return f"face {face} refers to vertex {index}, but the mesh has only {n_vertices} vertices"


def block_corner_fault(faces: np.ndarray, n_vertices: int, start: int = 0) -> str | None:
    """The first fault of a block of fixed-width faces read from a file, in :func:`flat_faces`' words.

    Parameters
    ----------
    faces : (m, k) int64
        Face ``start + i`` is row ``i``; no padding.
    n_vertices : int
    start : int
        The block's first face in the file.

    Returns
    -------
    str or None
        A negative corner first (as :func:`flat_faces` reports it), else a corner past the last
        vertex; None when every corner is a vertex.
    """
    negative = faces < 0
    if negative.any():
        row = int(np.flatnonzero(negative.any(axis=1))[0])
        return negative_corner(start + row, int(faces[row][negative[row]][0]))
    beyond = faces >= n_vertices
    if beyond.any():
        row = int(np.flatnonzero(beyond.any(axis=1))[0])
        return missing_corner(start + row, int(faces[row][beyond[row]][0]), n_vertices)
    return None
