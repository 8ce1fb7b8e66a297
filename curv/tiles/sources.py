"""Reading an input too large for memory a chunk at a time: LAS/LAZ and binary PLY.

A :class:`Source` hands out its points in order, a chunk at a time, exactly as the in-memory
readers (:mod:`curv.formats.pointio`, :mod:`curv.io`) would give them as whole columns (float64
coordinates: a LAS file's scaled and offset, a PLY file's as stored; the file's own normals):

* **LAS/LAZ** through laspy's chunked reader. A compressed file cannot be read at a random place,
  so the first pass (:meth:`Source.scan`) also copies the coordinates (and normals) into the run's
  scratch folder as plain float64 columns, which every later pass reads instead.
* **Binary PLY** through plyfile's memory map of the vertex element (and of the faces, when every
  face is a triangle): nothing is copied. A polygon mesh's faces (quads, or polygons mixed) are
  read a block of bytes at a time (:mod:`curv.tiles.polyply`), padded with -1 to the longest.
* **ASCII PLY** of points or triangles a block of text at a time (:mod:`curv.tiles.asciiply`),
  copied as plain columns in the first pass as LAS/LAZ. An ASCII polygon mesh (kept as polygons by
  the in-memory reader), a binary PLY of other elements or face properties, or any other format is
  read whole (:func:`open_source` returns None for them).

Every pass checks what the in-memory readers check (a NaN coordinate, a count the data does not
hold) with the same one-line :class:`curv.LoadError`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import numpy as np

from ..core.errors import LoadError
from ..core.face_input import block_corner_fault
from ..core.paths import check_readable, one_line

__all__ = ["Source", "LasSource", "PlySource", "open_source", "reopen", "CHUNK", "Scan", "ScanTally"]

CHUNK = 1 << 20
"""Points per chunk of a pass (about 50 MB of coordinates and normals)."""

_NORMAL_NAMES = (("nx", "ny", "nz"), ("normal_x", "normal_y", "normal_z"), ("normalx", "normaly", "normalz"))


def _normal_names(names) -> tuple | None:
    from ..formats.pointio import _named_normals

    return _named_normals(Path("?"), list(names), "the file")


@dataclass
class Scan:
    """What the first pass learns: the count, bounds and the sample the grid's cell comes from.

    Attributes
    ----------
    n : int
    lo, hi : (3,) float64
    sample : (s,) int64 and (s, 3) float64
        Every ``step``-th point's coordinates, in the file's order (:func:`curv.core.grid.cell_sample_step`).
    """

    n: int
    lo: np.ndarray
    hi: np.ndarray
    sample: np.ndarray = field(repr=False)


class ScanTally:
    """A first pass's bounds and every ``step``-th point, added chunk by chunk in file order (every
    first pass, whatever else it does with its chunks, keeps its :class:`Scan` through this)."""

    def __init__(self, step: int):
        self.step = step
        self.lo, self.hi = np.full(3, np.inf), np.full(3, -np.inf)
        self.n = 0
        self._sample = []

    def add(self, start: int, pts: np.ndarray) -> None:
        """Points ``start`` to ``start + len(pts)`` of the file, (m, 3) float64."""
        self.lo = np.minimum(self.lo, pts.min(axis=0))
        self.hi = np.maximum(self.hi, pts.max(axis=0))
        self._sample.append(pts[(-start) % self.step::self.step])
        self.n = start + pts.shape[0]

    @property
    def sample(self) -> np.ndarray:
        """(s, 3) float64 every ``step``-th point seen so far."""
        return np.concatenate(self._sample) if self._sample else np.empty((0, 3))

    def scan(self, n: int | None = None) -> Scan:
        """The :class:`Scan` of the pass (``n``: the file's count, default the points seen)."""
        return Scan(self.n if n is None else n, self.lo, self.hi, self.sample)


class Source:
    """An input read a chunk at a time (module notes)."""

    path: Path
    n: int
    has_normals: bool
    is_mesh: bool = False
    n_faces: int = 0

    def face_width(self) -> int:
        """Corners of a mesh's longest face: the width of :meth:`face_chunks`' blocks (-1 pads the shorter)."""
        return 3

    def chunks(self, size: int = CHUNK) -> Iterator[tuple[int, np.ndarray, np.ndarray | None]]:
        """``(start, points (m, 3) float64, normals (m, 3) float64 or None)`` in file order."""
        raise NotImplementedError

    def scan(self, folder: Path | None, step: int) -> Scan:
        """The first pass: count, bounds, every ``step``-th point (and a plain copy in ``folder``
        where later passes need one)."""
        tally = ScanTally(step)
        for start, pts, _ in self.chunks():
            tally.add(start, pts)
        return tally.scan()

    @staticmethod
    def _check(path: Path, start: int, pts: np.ndarray) -> None:
        bad = ~np.isfinite(pts)
        if bad.any():
            row, col = np.argwhere(bad)[0]
            kind = "a NaN" if np.isnan(pts[row, col]) else "an infinite"
            raise LoadError(f"{path}: point {start + int(row)} has {kind} coordinate")


class PlySource(Source):
    """A binary PLY read through plyfile's memory map (module notes)."""

    def __init__(self, path: Path, data):
        self.path = path
        self._data = data
        vert = data["vertex"].data
        fields = vert.dtype.names or ()
        missing = [c for c in "xyz" if c not in fields]
        if missing:
            raise LoadError(f"{path}: PLY vertices lack coordinate(s) {', '.join(missing)}")
        self._vertex = vert
        self.n = int(vert.shape[0])
        names = [e.name for e in data.elements]
        self.is_mesh = "face" in names and data["face"].count > 0
        self._normals = None if self.is_mesh else _normal_names(fields)
        self.has_normals = self._normals is not None
        if self.is_mesh:
            face = data["face"].data
            key = next(k for k in ("vertex_indices", "vertex_index") if k in face.dtype.names)
            self._faces = face[key]
            self.n_faces = int(self._faces.shape[0])

    def chunks(self, size: int = CHUNK):
        for start in range(0, self.n, size):
            rows = self._vertex[start:start + size]
            pts = np.empty((rows.shape[0], 3))
            for i, c in enumerate("xyz"):
                pts[:, i] = rows[c]
            self._check(self.path, start, pts)
            normals = None
            if self._normals:
                normals = np.empty((rows.shape[0], 3))
                for i, c in enumerate(self._normals):
                    normals[:, i] = rows[c]
            yield start, pts, normals

    def vertices_at(self, ids: np.ndarray) -> np.ndarray:
        """(k, 3) float64 coordinates of vertices ``ids`` (any order)."""
        rows = self._vertex[np.asarray(ids, np.int64)]
        return np.stack([np.asarray(rows[c], np.float64) for c in "xyz"], axis=1)

    def face_chunks(self, size: int = CHUNK):
        """``(start, faces (m, 3) int64)`` in file order; an index out of range is a LoadError."""
        for start in range(0, self.n_faces, size):
            faces = np.asarray(self._faces[start:start + size], dtype=np.int64)
            fault = block_corner_fault(faces, self.n, start) if faces.size else None
            if fault is not None:
                raise LoadError(f"{self.path}: {fault}")
            yield start, faces

    def faces_at(self, ids: np.ndarray) -> np.ndarray:
        return np.asarray(self._faces[np.asarray(ids, np.int64)], dtype=np.int64)


class LasSource(Source):
    """A LAS/LAZ file through laspy's chunked reader; later passes read the scan's plain copy."""

    def __init__(self, path: Path, *, coordinates_only: bool = False):
        import laspy

        from ..formats.lasheader import check_las_header

        self.path = path
        self._coordinates_only = coordinates_only  # decompress the x, y, z layers only (LAZ 1.4)
        check_las_header(path)  # the header's promises against the file, before laspy reads it
        try:
            with laspy.open(path) as reader:
                header = reader.header
                self.n = int(header.point_count)
                self._normals = None if coordinates_only else _normal_names(header.point_format.extra_dimension_names)
        except LoadError:
            raise
        except Exception as exc:  # noqa: BLE001 - laspy's and lazrs's errors, in one line
            raise LoadError(f"{path}: not a readable {path.suffix.lstrip('.').upper()} file ({one_line(exc)})") from None
        self.has_normals = self._normals is not None
        self._copy: Path | None = None

    def _file_chunks(self, size: int):
        import laspy

        done = 0
        selection = laspy.DecompressionSelection.all()
        if self._coordinates_only:
            selection = laspy.DecompressionSelection.XY_RETURNS_CHANNEL | laspy.DecompressionSelection.Z
        with laspy.open(self.path, decompression_selection=laspy.DecompressionSelection(selection)) as reader:
            try:
                for points in reader.chunk_iterator(size):
                    m = len(points)
                    if m == 0:
                        break
                    pts = np.empty((m, 3))
                    pts[:, 0], pts[:, 1], pts[:, 2] = points.x, points.y, points.z
                    self._check(self.path, done, pts)
                    normals = None
                    if self._normals:
                        normals = np.column_stack([np.asarray(points[c], dtype=np.float64) for c in self._normals])
                    yield done, pts, normals
                    done += m
            except LoadError:
                raise
            except Exception as exc:  # noqa: BLE001 - a truncated or corrupt file, in one line
                raise LoadError(f"{self.path}: record {done} and after cannot be read ({one_line(exc)})") from None
        if done != self.n:
            raise LoadError(f"{self.path}: holds {done} point records but its header says {self.n}")

    def scan(self, folder: Path | None, step: int) -> Scan:
        if folder is None:
            return super().scan(None, step)
        folder.mkdir(parents=True, exist_ok=True)
        width = 6 if self.has_normals else 3
        copy = folder / "coordinates.f8"
        self._copy = None  # this pass reads the file itself
        tally = ScanTally(step)
        with open(copy, "wb") as fh:
            for start, pts, normals in self._file_chunks(CHUNK):
                tally.add(start, pts)
                block = pts if normals is None else np.concatenate([pts, normals], axis=1)
                fh.write(np.ascontiguousarray(block, dtype=np.float64).tobytes())
        self._copy = copy
        self._width = width
        return tally.scan(self.n)

    def attach(self, folder: Path) -> bool:
        """Read the plain copy an earlier scan left in ``folder`` (a resumed run): whether it is whole."""
        copy = folder / "coordinates.f8"
        width = 6 if self.has_normals else 3
        if copy.is_file() and copy.stat().st_size == self.n * width * 8:
            self._copy, self._width = copy, width
            return True
        return False

    def chunks(self, size: int = CHUNK):
        if self._copy is None:
            yield from self._file_chunks(size)
            return
        with open(self._copy, "rb") as fh:
            for start in range(0, self.n, size):
                m = min(size, self.n - start)
                block = np.fromfile(fh, dtype=np.float64, count=m * self._width).reshape(m, self._width)
                yield start, block[:, :3], (block[:, 3:] if self._width == 6 else None)


def open_source(path) -> Source | None:
    """A :class:`Source` for ``path`` when it can be read a chunk at a time (LAS/LAZ; a PLY of points
    or triangles, binary or ASCII; a binary PLY of polygons), else None (read it whole). Raises :class:`LoadError` for an unreadable file."""
    path = Path(path)
    check_readable(path)
    suffix = path.suffix.lower()
    if suffix in (".las", ".laz"):
        try:
            import laspy  # noqa: F401
        except ImportError:
            raise LoadError(f"{path}: reading LAS/LAZ needs laspy (pip install 'curvlab[points]')") from None
        return LasSource(path)
    if suffix == ".ply":
        from plyfile import PlyData

        from ..formats.guards import read_ply_header

        with open(path, "rb") as fh:
            if fh.readline().strip() != b"ply":
                raise LoadError(f"{path}: not a PLY file (no 'ply' line)")
            header = read_ply_header(fh)
        fmt, counts, lists = header.format, header.counts, header.lists
        if fmt == "ascii":
            from .asciiply import ascii_source

            return ascii_source(path)
        if not fmt.startswith("binary"):
            return None
        known = {}
        face_lists = lists.get("face", [])
        key = next((k for k in ("vertex_indices", "vertex_index") if k in face_lists), None)
        if counts.get("face", 0):
            if key is None or face_lists != [key]:
                return None
            known = {"face": {key: 3}}
            from ..formats.guards import check_ply_header
            from .polyply import polygon_source

            polygons = polygon_source(path, check_ply_header(path))
            if polygons is not None and not polygons.starts_with_triangle():
                return polygons  # plyfile would map the faces as triangles, then read them all to find out
        try:
            data = PlyData.read(str(path), known_list_len=known) if known else PlyData.read(str(path))
        except Exception as exc:  # noqa: BLE001 - a polygon mesh (lists of other lengths), or a bad file
            if known and "list length" in str(exc):
                return polygons
            raise LoadError(f"{path}: not a readable PLY file ({one_line(exc)})") from None
        if "vertex" not in [e.name for e in data.elements]:
            raise LoadError(f"{path}: PLY file has no vertex element")
        if not isinstance(data["vertex"].data, np.memmap):
            return None
        _check_size(path, data)
        return PlySource(path, data)
    return None


def reopen(path, folder: Path) -> Source | None:
    """:func:`open_source` for a run's worker: a source whose first pass left plain copies in the
    scratch ``folder`` reads them (an ASCII PLY is not parsed again)."""
    path = Path(path)
    if path.suffix.lower() == ".ply":
        from .asciiply import ascii_source

        source = ascii_source(path, folder=folder)
        if source is not None:
            return source
    return open_source(path)


def _check_size(path: Path, data) -> None:
    """A binary PLY whose data is longer than its header declares has wrong counts (as :mod:`curv.io` says)."""
    from ..formats.pointio import _ply_header_bytes

    sizes = [e.count * e.data.dtype.itemsize for e in data.elements]
    expected = _ply_header_bytes(path) + sum(sizes)
    actual = path.stat().st_size
    if actual > expected:
        raise LoadError(f"{path}: holds {actual - expected} bytes more than its header declares "
                        f"({', '.join(f'{e.count} {e.name}' for e in data.elements)}); the element counts are wrong")
    if actual < expected:
        raise LoadError(f"{path}: is {expected - actual} bytes shorter than its header declares "
                        f"({', '.join(f'{e.count} {e.name}' for e in data.elements)}); the file is truncated")
