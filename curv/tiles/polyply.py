"""A binary PLY of polygons (quads, or triangles and quads mixed) read a block of bytes at a time.

plyfile memory-maps a face element only when every list has one known length (a triangle mesh,
:class:`curv.tiles.sources.PlySource`); otherwise it reads each face as a Python object, the whole
file at once. Here the face element is read as raw bytes, :data:`BLOCK_BYTES` at a time: a kernel
walks the records (a length, then that many corners) and finds where each starts
(:func:`_record_starts`), another decodes them into an (m, k) int64 array padded with -1 to the
file's longest polygon (:func:`_decode`), the convention of :class:`curv.Mesh` and of the tiles
(:mod:`curv.tiles.frame`). Both byte orders and every integer type of the length and the corners
are read by the same two kernels: a type is its bytes' shifts and its sign's range (data, not a
code path).

The vertex element is memory-mapped as numpy's structured array of the header's properties, as
plyfile maps it. The layout read this way is the common one: a ``vertex`` element of scalar
properties, then a ``face`` element whose only property is its ``vertex_indices`` (or
``vertex_index``) list; any other layout is read whole (:func:`polygon_source` says None).

The first walk over the faces (:meth:`PolygonPlySource.face_width`, on first need) checks what the
in-memory reader checks, with the same one-line :class:`curv.LoadError`: a face block shorter than
its count (``early end-of-file``), longer (``the element counts are wrong``), a face of fewer than
3 corners, a corner that is negative or not a vertex (the first of each, in the whole reader's
order of checks); and it keeps the byte offset of every :data:`MARK_EVERY`-th face, so
that a few faces are read anywhere (:meth:`PolygonPlySource.faces_at`) without a copy of the faces.
Memory stays one block's, whatever the face count.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.errors import LoadError
from ..core.face_input import missing_corner, negative_corner
from ..core.jit import jit, jit_inlined
from .sources import CHUNK, PlySource

__all__ = ["PolygonPlySource", "polygon_source", "BLOCK_BYTES", "MARK_EVERY"]

BLOCK_BYTES = 1 << 24
"""Bytes of the face element read at once (about a million quads)."""

MARK_EVERY = 256
"""Every this many faces, the byte offset of one is kept for :meth:`PolygonPlySource.faces_at`."""

_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
          "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
          "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


@jit_inlined
def _read_int(buf, pos, shifts, limit, wrap):
    """The integer whose bytes start at ``buf[pos]``: each byte shifted by ``shifts`` (the byte
    order), less ``wrap`` from ``limit`` up (a signed type's negative values)."""
    value = np.int64(0)
    for b in range(shifts.size):
        value |= np.int64(buf[pos + b]) << shifts[b]
    if value >= limit:
        value -= wrap
    return value


@jit
def _record_starts(buf, shifts, ranges, starts, sizes):
    """Walk the whole records at the start of ``buf`` (a length, then that many corners).

    Parameters
    ----------
    buf : (b,) uint8
    shifts : ((c,) int64, (i,) int64)
        The bit shift of each byte of the length and of a corner (their byte order and size).
    ranges : (4,) int64
        ``(length limit, length wrap, corner limit, corner wrap)`` (:func:`_read_int`).
    starts, sizes : (r,) int64
        Written: each record's byte offset in ``buf`` and its length, for at most r records.

    Returns
    -------
    (records, end, widest, negative, wanted) : int
        Whole records found, the byte after the last, the longest, whether the walk stopped at a
        negative length (a signed length type), and the bytes the record at ``end`` takes when
        ``buf`` ends inside it (0 when the walk stopped at r records).
    """
    count_shifts, index_shifts = shifts
    head, corner = count_shifts.size, index_shifts.size
    pos, m, widest = 0, 0, 0
    n = buf.size
    while m < starts.size:
        if pos + head > n:
            return m, pos, widest, False, head
        k = _read_int(buf, pos, count_shifts, ranges[0], ranges[1])
        if k < 0:
            return m, pos, widest, True, 0
        if pos + head + k * corner > n:
            return m, pos, widest, False, head + k * corner
        starts[m] = pos
        sizes[m] = k
        widest = max(widest, k)
        pos += head + k * corner
        m += 1
    return m, pos, widest, False, 0


@jit
def _decode(buf, starts, sizes, shifts, ranges, out):
    """Decode the records at ``starts`` into ``out`` (m, k) int64, padded with -1 (arguments as
    :func:`_record_starts`)."""
    count_shifts, index_shifts = shifts
    head, corner = count_shifts.size, index_shifts.size
    for f in range(starts.size):
        pos = starts[f] + head
        k = sizes[f]
        for j in range(k):
            out[f, j] = _read_int(buf, pos + j * corner, index_shifts, ranges[2], ranges[3])
        for j in range(k, out.shape[1]):
            out[f, j] = -1


def _integer_code(kind: str, big: bool) -> tuple[np.ndarray, int, int]:
    """``(shifts, limit, wrap)`` of a PLY integer type in a byte order (:func:`_read_int`)."""
    dtype = np.dtype(_TYPES[kind])
    size = dtype.itemsize
    shifts = 8 * (np.arange(size)[::-1] if big else np.arange(size))
    wrap = 1 << (8 * size)
    return shifts.astype(np.int64), (wrap >> 1 if dtype.kind == "i" else wrap), wrap


class PolygonPlySource(PlySource):
    """A binary PLY polygon mesh read a block of bytes at a time (module notes)."""

    def __init__(self, path: Path, header):
        vertex, face = header.elements
        big = header.format == "binary_big_endian"
        order = ">" if big else "<"
        self.path = path
        self._header = header
        dtype = np.dtype([(name, order + _TYPES[kind]) for name, kind, _ in vertex.properties])
        missing = [c for c in "xyz" if c not in dtype.names]
        if missing:
            raise LoadError(f"{path}: PLY vertices lack coordinate(s) {', '.join(missing)}")
        self.n = int(vertex.count)
        self._vertex = np.memmap(path, dtype=dtype, mode="r", offset=header.header_bytes, shape=(self.n,))
        self._normals = None
        self.has_normals = False
        self.is_mesh = True
        self.n_faces = int(face.count)
        self._key, index_kind, count_kind = face.properties[0]
        self._offset = header.header_bytes + self.n * dtype.itemsize
        count_shifts, count_limit, count_wrap = _integer_code(count_kind, big)
        index_shifts, index_limit, index_wrap = _integer_code(index_kind, big)
        self._shifts = (count_shifts, index_shifts)
        self._ranges = np.array([count_limit, count_wrap, index_limit, index_wrap], np.int64)
        self._width: int | None = None
        self._marks: np.ndarray | None = None

    # --- the face element, a block at a time -------------------------------------------------
    def _early_end(self, row: int):
        raise LoadError(f"{self.path}: not a readable PLY file (element 'face': row {row}: property "
                        f"'{self._key}': early end-of-file)")

    def _blocks(self, first: int = 0, offset: int | None = None, count: int | None = None, size: int = CHUNK,
                block: int | None = None):
        """``(face number, buf, starts, sizes, base)`` of whole records (``base`` the file offset of
        ``buf[0]``), from face ``first`` at byte ``offset`` (default the element's start), ``count``
        faces (default to the end), at most ``size`` a time, reading ``block`` bytes at a time
        (default :data:`BLOCK_BYTES`); a
        record the file ends inside is a :class:`LoadError`, and so (reading to the end) is a
        longer element than the header declares."""
        base = self._offset if offset is None else int(offset)
        block = BLOCK_BYTES if block is None else block
        count = self.n_faces - first if count is None else count
        done, stop = first, first + count
        file_size = self.path.stat().st_size
        carry = np.empty(0, np.uint8)
        progress = True
        with open(self.path, "rb") as fh:
            fh.seek(base)
            while done < stop:
                buf = carry
                if carry.size < block // 2 or not progress:  # the rest of a block is parsed before reading on
                    raw = np.fromfile(fh, dtype=np.uint8, count=max(block, carry.size))
                    buf = np.concatenate([carry, raw]) if carry.size else raw
                want = min(stop - done, size)
                starts, sizes = np.empty(want, np.int64), np.empty(want, np.int64)
                m, end, _, negative, wanted = _record_starts(buf, self._shifts, self._ranges, starts, sizes)
                if negative:
                    raise LoadError(f"{self.path}: face {done + m} has a negative vertex count")
                if wanted and base + end + wanted > file_size:
                    self._early_end(done + m)
                progress = m > 0
                if m:
                    yield done, buf, starts[:m], sizes[:m], base
                    done += m
                carry = buf[end:]
                base += end
            if stop == self.n_faces and (carry.size or fh.read(1)):
                counts = ", ".join(f"{e.count} {e.name}" for e in self._header.elements)
                raise LoadError(f"{self.path}: holds more data than its header declares ({counts}); "
                                f"the element counts are wrong")

    def _decoded(self, buf, starts, sizes, width: int) -> np.ndarray:
        out = np.empty((starts.size, width), np.int64)
        _decode(buf, starts, sizes, self._shifts, self._ranges, out)
        return out

    def _faults(self, start: int, faces: np.ndarray, sizes: np.ndarray) -> list:
        """The first face of a block with each fault :class:`curv.Mesh` refuses, as ``(face,
        value)`` or None: fewer than 3 corners, a negative corner, a corner past the vertices."""
        real = np.arange(faces.shape[1]) < sizes[:, None]
        out = []
        for bad in (sizes < 3, ((faces < 0) & real).any(axis=1), (faces >= self.n).any(axis=1)):
            rows = np.flatnonzero(bad)
            out.append(None if rows.size == 0 else int(rows[0]))
        small, negative, beyond = out
        return [None if small is None else (start + small, int(sizes[small])),
                None if negative is None else (start + negative, int(faces[negative][(faces[negative] < 0)
                                                                                    & real[negative]][0])),
                None if beyond is None else (start + beyond, int(faces[beyond][faces[beyond] >= self.n][0]))]

    def _refuse(self, faults: list) -> None:
        """The whole reader's error for the first fault of the first kind found (its order)."""
        small, negative, beyond = faults
        if small is not None:
            raise LoadError(f"{self.path}: face {small[0]} has {small[1]} vertices; a face needs at least 3")
        if negative is not None:
            raise LoadError(f"{self.path}: {negative_corner(*negative)}")
        if beyond is not None:
            raise LoadError(f"{self.path}: {missing_corner(*beyond, self.n)}")

    def starts_with_triangle(self) -> bool:
        """Whether the first face is a triangle (then plyfile's memory map of triangles is tried
        first: :func:`curv.tiles.sources.open_source`). Read with numpy: no kernel is loaded."""
        kind = self._header.elements[1].properties[0][2]
        order = ">" if self._header.format == "binary_big_endian" else "<"
        with open(self.path, "rb") as fh:
            fh.seek(self._offset)
            first = np.fromfile(fh, dtype=order + _TYPES[kind], count=1)
        return first.size == 0 or int(first[0]) == 3

    def face_width(self) -> int:
        """The longest polygon's corners: the first call walks every face and checks them (module notes)."""
        if self._width is None:
            widest, marks, faults = 0, [], [None, None, None]
            for start, buf, starts, sizes, base in self._blocks():
                width = int(sizes.max())
                found = self._faults(start, self._decoded(buf, starts, sizes, width), sizes)
                faults = [f if f is not None else g for f, g in zip(faults, found)]
                widest = max(widest, width)
                marks.append(starts[(-start) % MARK_EVERY::MARK_EVERY] + base)
            self._refuse(faults)
            self._marks = np.concatenate(marks) if marks else np.empty(0, np.int64)
            self._width = widest
        return self._width

    def face_chunks(self, size: int = CHUNK):
        """``(start, faces (m, k) int64)`` in file order, k the longest polygon, -1 padding the others."""
        width = self.face_width()
        for start, buf, starts, sizes, _ in self._blocks(size=size):
            yield start, self._decoded(buf, starts, sizes, width)

    def faces_at(self, ids: np.ndarray) -> np.ndarray:
        """(s, k) int64 faces ``ids`` (any order), read near the kept offsets (module notes)."""
        ids = np.asarray(ids, np.int64)
        width = self.face_width()
        out = np.empty((ids.size, width), np.int64)
        groups = ids // MARK_EVERY
        for group in np.unique(groups):
            first = int(group) * MARK_EVERY
            count = min(MARK_EVERY, self.n_faces - first)
            record = self._shifts[0].size + width * self._shifts[1].size
            faces = np.concatenate([self._decoded(buf, starts, sizes, width) for _, buf, starts, sizes, _ in
                                    self._blocks(first, int(self._marks[group]), count, block=count * record)])
            rows = groups == group
            out[rows] = faces[ids[rows] - first]
        return out


def polygon_source(path: Path, header) -> PolygonPlySource | None:
    """A :class:`PolygonPlySource` for a binary PLY whose ``header`` (:class:`curv.formats.guards.PlyHeader`)
    has the layout read a block at a time (module notes), else None (read it whole)."""
    if header.header_bytes is None or not header.format.startswith("binary_") or len(header.elements) != 2:
        return None
    vertex, face = header.elements
    if vertex.name != "vertex" or face.name != "face" or vertex.count is None or face.count is None:
        return None
    if vertex.lists or any(kind not in _TYPES for _, kind, _ in vertex.properties):
        return None
    if len(face.properties) != 1:
        return None
    key, index_kind, count_kind = face.properties[0]
    if key not in ("vertex_indices", "vertex_index") or count_kind is None:
        return None
    if np.dtype(_TYPES.get(count_kind, "f4")).kind not in "iu" or np.dtype(_TYPES.get(index_kind, "f4")).kind not in "iu":
        return None
    return PolygonPlySource(path, header)
