"""An ASCII PLY file read a chunk at a time: points, or a triangle mesh.

The body of an ASCII PLY file is a stream of numbers: each vertex's properties in the header's
order, then each face's list (its length, then its corners). :class:`AsciiPlySource` reads it a
block at a time (numpy's text parser over whole blocks, no Python work per line), gives each
coordinate the value the in-memory readers give it (parsed as a double, then held in the
property's type, as plyfile holds it, then a double again), and in its first pass
(:meth:`AsciiPlySource.scan`) keeps plain binary copies of the coordinates (and normals) and of the
triangles in the run's scratch folder, which every later pass and every random read uses.

A face list of another length than 3 is a polygon mesh: the in-memory reader keeps its polygons
(:func:`curv.load`; the estimators take them as they are), so it is read whole, as are files with
other elements or list properties (:func:`ascii_source` says None). A count the data does not
hold, a number that is not one and an index out of range are one-line :class:`curv.LoadError`\\ s.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..core.errors import LoadError
from ..core.face_input import block_corner_fault
from .sources import CHUNK, Scan, ScanTally, Source, _normal_names

__all__ = ["AsciiPlySource", "ascii_source", "FACES_COPY"]

FACES_COPY = "triangles.i8"
"""The scratch folder's copy of a mesh's triangles ((m, 3) int64); the coordinates' is
``coordinates.f8`` as for LAS/LAZ."""

_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
          "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
          "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}

_BLOCK = 1 << 24
"""Bytes of text parsed at once (about 16 MB)."""


class _Numbers:
    """The numbers of a text, in order, a block at a time (:meth:`take`)."""

    def __init__(self, path: Path, start: int):
        self.path = path
        self._fh = open(path, "rb")
        self._fh.seek(start)
        self._carry = b""
        self._pending = np.empty(0)
        self._eof = False

    def close(self) -> None:
        self._fh.close()

    def _more(self) -> bool:
        if self._eof:
            return False
        data = self._carry + self._fh.read(_BLOCK)
        if len(data) == len(self._carry):
            self._eof, text, self._carry = True, data, b""
        else:
            cut = max(data.rfind(c) for c in (b" ", b"\n", b"\t", b"\r")) + 1
            text, self._carry = (data[:cut], data[cut:]) if cut else (b"", data)
        if text.strip():
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                try:
                    numbers = np.fromstring(text.decode("ascii"), dtype=np.float64, sep=" ")
                except (ValueError, UnicodeDecodeError, DeprecationWarning) as exc:
                    raise LoadError(f"{self.path}: holds text that is not a number ({exc})") from None
            self._pending = np.concatenate([self._pending, numbers]) if self._pending.size else numbers
        return True

    def take(self, k: int) -> np.ndarray:
        """The next ``k`` numbers (fewer only at the end of the file)."""
        while self._pending.size < k and self._more():
            pass
        out, self._pending = self._pending[:k], self._pending[k:]
        return out

    def rest(self) -> int:
        """How many numbers are left (reads to the end)."""
        while self._more():
            pass
        return int(self._pending.size)


def _layout(header):
    """``(vertex properties [(name, dtype)], face list name or None)`` when this reader takes the
    file (module notes), else None."""
    names = [e.name for e in header.elements if e.count]
    if not names or names[0] != "vertex" or names not in (["vertex"], ["vertex", "face"]):
        return None
    elements = {e.name: e for e in header.elements}
    props = elements["vertex"].properties
    if any(list_type is not None for _, _, list_type in props) or any(t not in _TYPES for _, t, _ in props):
        return None
    if not all(c in [p[0] for p in props] for c in "xyz"):
        return None
    key = None
    if "face" in names:
        face = elements["face"].properties
        if len(face) != 1 or face[0][0] not in ("vertex_indices", "vertex_index") or face[0][2] is None:
            return None
        key = face[0][0]
    return [(name, np.dtype(_TYPES[t])) for name, t, _ in props], key


class AsciiPlySource(Source):
    """An ASCII PLY of points or triangles read a block at a time (module notes)."""

    def __init__(self, path: Path, header, layout):
        self.path = Path(path)
        self._start = header.header_bytes
        self._props, key = layout
        counts = {e.name: e.count for e in header.elements}
        self.n = int(counts["vertex"])
        self.n_faces = int(counts.get("face", 0)) if key else 0
        self.is_mesh = self.n_faces > 0
        names = [p[0] for p in self._props]
        self._columns = [names.index(c) for c in "xyz"]
        normals = None if self.is_mesh else _normal_names(names)
        self._normal_columns = [names.index(c) for c in normals] if normals else None
        self.has_normals = normals is not None
        self._copy: Path | None = None
        self._faces: Path | None = None

    # --- the text ----------------------------------------------------------------------------
    def _values(self, rows: np.ndarray, columns) -> np.ndarray:
        out = np.empty((rows.shape[0], len(columns)))
        for i, c in enumerate(columns):
            out[:, i] = rows[:, c].astype(self._props[c][1]).astype(np.float64)  # as plyfile holds them
        return out

    def _text_pass(self, size: int):
        """``(start, points, normals)`` chunks, then ``(start, triangles)`` chunks, from the text;
        checks every count and index."""
        numbers = _Numbers(self.path, self._start)
        width = len(self._props)
        try:
            for start in range(0, self.n, size):
                m = min(size, self.n - start)
                rows = numbers.take(m * width)
                if rows.size < m * width:
                    raise LoadError(f"{self.path}: ends inside vertex {start + rows.size // width} "
                                    f"(its header declares {self.n} vertices); the file is truncated")
                rows = rows.reshape(m, width)
                pts = self._values(rows, self._columns)
                self._check(self.path, start, pts)
                yield "v", start, pts, (self._values(rows, self._normal_columns) if self._normal_columns else None)
            for start in range(0, self.n_faces, size):
                m = min(size, self.n_faces - start)
                rows = numbers.take(m * 4)
                if rows.size < m * 4:
                    raise LoadError(f"{self.path}: ends inside face {start + rows.size // 4} "
                                    f"(its header declares {self.n_faces} faces); the file is truncated")
                rows = rows.reshape(m, 4)
                if (rows[:, 0] != 3).any():
                    row = int(np.flatnonzero(rows[:, 0] != 3)[0])
                    raise LoadError(f"{self.path}: face {start + row} is not a triangle (a polygon mesh is read whole)")
                faces = rows[:, 1:].astype(np.int64)
                if (faces != rows[:, 1:]).any():
                    row = int(np.flatnonzero((faces != rows[:, 1:]).any(axis=1))[0])
                    raise LoadError(f"{self.path}: face {start + row} has non-integer indices")
                fault = block_corner_fault(faces, self.n, start)
                if fault is not None:
                    raise LoadError(f"{self.path}: {fault}")
                yield "f", start, faces, None
            extra = numbers.rest()
            if extra:
                raise LoadError(f"{self.path}: holds {extra} numbers more than its header declares "
                                f"({self.n} vertices, {self.n_faces} faces); the element counts are wrong")
        finally:
            numbers.close()

    def all_triangles(self) -> bool:
        """Whether every face lists 3 corners (one pass over the faces' text; vertices skipped by
        their lines)."""
        with open(self.path, "rb") as fh:
            fh.seek(self._start)
            lines, offset = 0, self._start
            while lines < self.n:
                block = fh.read(_BLOCK)
                if not block:
                    return False
                found = block.count(b"\n")
                if lines + found < self.n:
                    lines, offset = lines + found, offset + len(block)
                    continue
                ends = np.flatnonzero(np.frombuffer(block, np.uint8) == ord("\n"))
                offset += int(ends[self.n - lines - 1]) + 1
                lines = self.n
        numbers = _Numbers(self.path, offset)
        try:
            left = self.n_faces
            while left:
                m = min(CHUNK, left)
                rows = numbers.take(4 * m)
                if rows.size < 4 * m or (rows.reshape(m, 4)[:, 0] != 3).any():
                    return False
                left -= m
            return numbers.rest() == 0
        except LoadError:
            return False  # the whole reader says what is wrong
        finally:
            numbers.close()

    # --- the Source --------------------------------------------------------------------------
    def scan(self, folder: Path | None, step: int) -> Scan:
        if folder is None:
            return super().scan(None, step)
        folder.mkdir(parents=True, exist_ok=True)
        self._copy = self._faces = None  # this pass reads the text itself
        tally = ScanTally(step)
        copy, faces = folder / "coordinates.f8", folder / FACES_COPY
        with open(copy, "wb") as fh, (open(faces, "wb") if self.is_mesh else open(folder / ".none.tmp", "wb")) as fh_faces:
            for kind, start, values, normals in self._text_pass(CHUNK):
                if kind == "f":
                    fh_faces.write(np.ascontiguousarray(values, np.int64).tobytes())
                    continue
                tally.add(start, values)
                block = values if normals is None else np.concatenate([values, normals], axis=1)
                fh.write(np.ascontiguousarray(block, np.float64).tobytes())
        (folder / ".none.tmp").unlink(missing_ok=True)
        self.attach(folder)
        return tally.scan(self.n)

    def attach(self, folder: Path) -> bool:
        """Read the plain copies an earlier scan left in ``folder``: whether they are whole."""
        width = 6 if self.has_normals else 3
        copy, faces = Path(folder) / "coordinates.f8", Path(folder) / FACES_COPY
        whole = copy.is_file() and copy.stat().st_size == self.n * width * 8
        if self.is_mesh:
            whole = whole and faces.is_file() and faces.stat().st_size == self.n_faces * 24
        if whole:
            self._copy, self._width = copy, width
            self._faces = faces if self.is_mesh else None
        return whole

    def _coordinates(self) -> np.ndarray:
        return np.memmap(self._copy, dtype=np.float64, mode="r", shape=(self.n, self._width))

    def _triangles(self) -> np.ndarray:
        return np.memmap(self._faces, dtype=np.int64, mode="r", shape=(self.n_faces, 3))

    def chunks(self, size: int = CHUNK):
        if self._copy is None:
            for kind, start, pts, normals in self._text_pass(size):
                if kind == "v":
                    yield start, pts, normals
            return
        block = self._coordinates()
        for start in range(0, self.n, size):
            rows = np.array(block[start:start + size])
            yield start, rows[:, :3], (rows[:, 3:] if self._width == 6 else None)

    def _rows_at(self, chunks, ids: np.ndarray, width: int, dtype) -> np.ndarray:
        """Rows ``ids`` gathered from ``chunks`` (``(start, rows)``) in one pass (no copy to read)."""
        out = np.empty((ids.size, width), dtype)
        for start, rows in chunks:
            mine = np.flatnonzero((ids >= start) & (ids < start + rows.shape[0]))
            out[mine] = rows[ids[mine] - start]
        return out

    def vertices_at(self, ids: np.ndarray) -> np.ndarray:
        ids = np.asarray(ids, np.int64)
        if self._copy is None:
            return self._rows_at(((s, p) for s, p, _ in self.chunks()), ids, 3, np.float64)
        return np.array(self._coordinates()[ids, :3])

    def face_chunks(self, size: int = CHUNK):
        if self._faces is None:  # no scan into a scratch folder (a preview): from the text
            for kind, start, faces, _ in self._text_pass(size):
                if kind == "f":
                    yield start, faces
            return
        triangles = self._triangles()
        for start in range(0, self.n_faces, size):
            yield start, np.array(triangles[start:start + size])

    def faces_at(self, ids: np.ndarray) -> np.ndarray:
        ids = np.asarray(ids, np.int64)
        if self._faces is None:
            return self._rows_at(self.face_chunks(), ids, 3, np.int64)
        return np.array(self._triangles()[ids])


def ascii_source(path, *, folder: Path | None = None) -> AsciiPlySource | None:
    """An :class:`AsciiPlySource` for an ASCII PLY of points or triangles, else None (read whole).
    With ``folder``: the copies an earlier scan left there, without checking the faces again."""
    from ..formats.guards import read_ply_header

    path = Path(path)
    with open(path, "rb") as fh:
        if fh.readline().strip() != b"ply":
            raise LoadError(f"{path}: not a PLY file (no 'ply' line)")
        header = read_ply_header(fh)
    if header.format != "ascii" or header.header_bytes is None:
        return None
    layout = _layout(header)
    if layout is None:
        return None
    source = AsciiPlySource(path, header, layout)
    if folder is not None:
        source.attach(folder)
        return source
    if source.is_mesh and not source.all_triangles():
        return None
    return source
