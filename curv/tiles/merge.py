"""The finished tiles' rows read back in the input's order, a block of points at a time.

Every tile's rows file is sorted by point number, and a block of the output asks for consecutive
numbers, so each tile is read once from start to end through a small buffer (:class:`Rows`):
whatever the input's order (a LiDAR file's flight lines cross every tile), the memory held is the
buffers and one block. Parts turned over by the orientation across tiles are turned here
(:func:`curv.tiles.orient.turned`), and points the tiles did not agree on are made
``ORIENTATION`` (:func:`curv.tiles.orient.undecided`).
"""

from __future__ import annotations

import numpy as np

from .orient import turned, undecided
from .scratch import ROW_DTYPE, Scratch, read_rows, rows_to_columns

__all__ = ["Rows", "BUFFER_BYTES"]

BUFFER_BYTES = 64 << 20
"""The memory of the tiles' read buffers together (at least 1024 rows each)."""


class _Cursor:
    def __init__(self, path, rows: int, buffer: int):
        self.path = path
        self.total = rows
        self.read = 0
        self.buffer = np.empty(0, ROW_DTYPE)
        self.at = 0
        self.size = buffer

    def take(self, stop: int) -> np.ndarray:
        """The next rows with ids below ``stop``."""
        parts = []
        while True:
            if self.at >= self.buffer.size:
                if self.read >= self.total:
                    break
                self.buffer = read_rows(self.path, self.read, self.size)
                self.read += self.buffer.size
                self.at = 0
            ids = self.buffer["id"]
            end = self.at + int(np.searchsorted(ids[self.at:], stop))
            parts.append(self.buffer[self.at:end])
            self.at = end
            if end < self.buffer.size:
                break
        return np.concatenate(parts) if len(parts) > 1 else (parts[0] if parts else np.empty(0, ROW_DTYPE))


class Rows:
    """The whole input's result rows, read back block by block in order (module notes).

    Parameters
    ----------
    scratch : Scratch
    n_tiles, n : int
    signs : (Parts, (P,) int), optional
        The tiles' parts and +1 or -1 for each (the orientation across tiles,
        :func:`curv.tiles.orient.part_signs`).
    undecided_ids : (k,) int64, optional
        Ascending: points whose orientation the tiles did not agree on.
    """

    def __init__(self, scratch: Scratch, n_tiles: int, n: int, *, signs=None, undecided_ids=None):
        buffer = max(1024, BUFFER_BYTES // max(1, n_tiles) // ROW_DTYPE.itemsize)
        self.cursors = [_Cursor(scratch.rows_path(t), scratch.rows_count(t), buffer) for t in range(n_tiles)]
        self.n = n
        self.parts, self.signs = (None, None) if signs is None else (signs[0], np.asarray(signs[1]))
        self.undecided = np.empty(0, np.int64) if undecided_ids is None else np.asarray(undecided_ids, np.int64)
        self.next = 0

    def block(self, start: int, stop: int) -> dict:
        """The result columns (:func:`curv.formats.laswrite.curvature_columns`' keys) of points
        ``start``..``stop - 1``; blocks must be asked for in order, each once."""
        if start != self.next:
            raise ValueError(f"rows are read in order: expected the block at {self.next}, got {start}")
        out = np.empty(stop - start, ROW_DTYPE)
        got = np.zeros(stop - start, bool)
        for t, cursor in enumerate(self.cursors):
            rows = cursor.take(stop)
            if rows.size == 0:
                continue
            if rows["id"][0] < start:
                raise RuntimeError(f"tile {t} holds point {int(rows['id'][0])} twice or out of order")
            if self.signs is not None:
                over = np.flatnonzero(self.signs[self.parts.of(t, rows["part"])] < 0)
                if over.size:
                    cols = turned(rows_to_columns(rows[over]))
                    for name in ROW_DTYPE.names[1:]:
                        rows[name][over] = cols[name]
            at = rows["id"] - start
            out[at] = rows
            got[at] = True
        if not got.all():
            raise RuntimeError(f"no tile holds point {start + int(np.flatnonzero(~got)[0])}")
        self.next = stop
        columns = rows_to_columns(out)
        lo, hi = np.searchsorted(self.undecided, [start, stop])
        if hi > lo:
            at = self.undecided[lo:hi] - start
            fixed = undecided({name: values[at] for name, values in columns.items()})
            for name, values in fixed.items():
                columns[name][at] = values
        return columns

    def __iter__(self):
        raise TypeError("read Rows with block(start, stop)")
