"""Reading point clouds: vertex-only PLY, ``x y z [nx ny nz]`` text, PCD, PTS and LAS/LAZ files.

Every reader works on whole columns (plyfile's memory map, ``np.loadtxt``, ``np.memmap``, laspy's
structured arrays), never point by point. Nothing is made up: a NaN coordinate, a wrong column
count, a missing field or a file shorter or longer than its header says is a :class:`LoadError`
whose one-line message starts with the file name, like the mesh readers' in :mod:`curv.io`.
Normals are taken from the file when it has all three components, as they are (not renormalised);
other attributes (colours, intensity) are not kept.

Work is bounded by the file's size: a header is checked against the file before anything is
allocated from its counts (:func:`curv.formats.guards.check_header` for the files a library reads,
the PCD checks here, :mod:`.pts`), so a count the file cannot hold is a one-line error, never an
allocation or a loop that runs away.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..core.errors import LoadError, MeshError
from ..core.paths import check_readable, one_line as _one_line, read_with
from ..core.pointcloud import PointCloud
from .guards import check_header
from .lasheader import check_las_header
from .pts import read_pts_arrays

__all__ = ["POINT_SUFFIXES", "read_points", "peek_points"]

POINT_SUFFIXES = {".xyz": "text: x y z [nx ny nz], whitespace or comma separated, optional header line",
                  ".txt": "text, as .xyz", ".csv": "text, as .xyz",
                  ".pcd": "PCD (ascii, binary, binary_compressed)",
                  ".pts": "PTS: Leica (a count line, then x y z [i] [r g b]) or Expe point sets",
                  ".las": "LAS (laspy)", ".laz": "LAZ (laspy with its lazrs backend)"}
"""Suffixes that always hold points; a ``.ply`` holds points when it declares no faces (:func:`curv.io.is_point_file`)."""

_NORMAL_NAMES = (("nx", "ny", "nz"), ("normal_x", "normal_y", "normal_z"), ("normalx", "normaly", "normalz"))
_LAS_HINT = "pip install 'curvlab[points]'"


def peek_points(path) -> int | None:
    """The point count a PCD or LAS/LAZ header declares, without reading the data; else None.

    (A PLY's counts are :func:`curv.io.peek_counts`'.) Never raises: :func:`read_points` reports
    what is wrong with the file.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    try:
        if suffix == ".pcd":
            header, offset = _pcd_header(path)
            _check_pcd_size(path, header, offset)
            text_bytes = 2 * header["points"] * sum(header["counts"]) - 1  # a character and a separator a value
            if header["data"] == "ascii" and text_bytes > path.stat().st_size - offset:
                return None  # more than the file can hold: the reader counts the rows and says so
            return header["points"]
        if suffix in (".las", ".laz"):
            return check_las_header(path).point_count
    except Exception:  # noqa: BLE001 - a peek only; the reader gives the one-line error
        return None
    return None


def _named_normals(path: Path, names, kind: str) -> tuple[str, str, str] | None:
    """The normal components among ``names`` (one of the usual spellings), None if there are none."""
    lower = {n.lower(): n for n in names}
    for triple in _NORMAL_NAMES:
        present = [c for c in triple if c in lower]
        if len(present) == 3:
            return tuple(lower[c] for c in triple)
        if present:
            missing = ", ".join(c for c in triple if c not in lower)
            raise LoadError(f"{path}: {kind} has {', '.join(present)} but not {missing}; "
                            f"normals need all three components")
    return None


def _cloud(path: Path, points: np.ndarray, normals: np.ndarray | None, *, georeferenced: bool = False) -> PointCloud:
    """The :class:`PointCloud`; its own checks (no points, a NaN or infinite row) name the file."""
    try:
        return PointCloud(points, normals, georeferenced=georeferenced)
    except MeshError as exc:
        raise LoadError(f"{path}: {exc}") from None


def _columns(table, names) -> np.ndarray:
    """(n, len(names)) float64 from the named columns of a structured array (or dict of columns)."""
    out = np.empty((len(table[names[0]]), len(names)), dtype=np.float64)
    for i, name in enumerate(names):
        out[:, i] = table[name]
    return out


# --- PLY ----------------------------------------------------------------------------------------

def _ply_header_bytes(path: Path) -> int:
    with open(path, "rb") as fh:
        head = fh.read(1 << 16)
    at = head.find(b"end_header")
    if at < 0:
        raise LoadError(f"{path}: PLY header has no end_header line")
    return head.index(b"\n", at) + 1


def _read_ply(path: Path) -> PointCloud:
    from plyfile import PlyData

    data = PlyData.read(str(path))  # binary vertex data is memory-mapped
    names = [e.name for e in data.elements]
    if "vertex" not in names:
        raise LoadError(f"{path}: PLY file has no vertex element")
    if not data.text:
        sizes = [e.count * e.dtype().itemsize for e in data.elements
                 if e.count and not any(hasattr(p, "len_dtype") for p in e.properties)]
        if len(sizes) == len([e for e in data.elements if e.count]):
            expected = _ply_header_bytes(path) + sum(sizes)
            actual = path.stat().st_size
            if actual > expected:
                raise LoadError(f"{path}: holds {actual - expected} bytes more than its header declares "
                                f"({data['vertex'].count} vertices); the element counts are wrong")
    vert = data["vertex"].data
    fields = vert.dtype.names or ()
    missing = [c for c in "xyz" if c not in fields]
    if missing:
        raise LoadError(f"{path}: PLY vertices lack coordinate(s) {', '.join(missing)}")
    normal_names = _named_normals(path, fields, "PLY vertex element")
    normals = _columns(vert, normal_names) if normal_names else None
    return _cloud(path, _columns(vert, "xyz"), normals)


# --- text: .xyz .txt .csv ---------------------------------------------------------------------

def _text_layout(path: Path) -> tuple[int, str | None, list[str] | None]:
    """(lines to skip, delimiter, header names) from the first lines of a text point file."""
    with open(path, "rb") as fh:
        head = fh.read(1 << 16).decode("utf-8", errors="replace").splitlines()
    for index, line in enumerate(head):
        text = line.strip()
        if not text:
            continue
        bare = text.lstrip("#/").strip()
        delimiter = "," if "," in text else None
        words = [w.strip().lower() for w in bare.split(delimiter)]
        is_comment = text.startswith(("#", "//"))
        try:
            [float(w) for w in words]
        except ValueError:
            if is_comment and not {"x", "y", "z"} <= set(words):
                continue  # a comment, not column names
            if not {"x", "y", "z"} <= set(words):
                raise LoadError(f"{path}: line {index + 1} is neither numbers nor a header naming x, y, z "
                                f"columns: {text[:60]!r}") from None
            return index + 1, delimiter, words
        if is_comment:
            continue
        return index, delimiter, None
    raise LoadError(f"{path}: has no points")


def _read_text(path: Path) -> PointCloud:
    skip, delimiter, header = _text_layout(path)
    try:
        with warnings.catch_warnings():  # a header and no rows: said below in one line, not warned too
            warnings.filterwarnings("ignore", "loadtxt: input contained no data", UserWarning)
            table = np.loadtxt(path, dtype=np.float64, delimiter=delimiter, comments="#", skiprows=skip, ndmin=2)
    except ValueError as exc:
        raise LoadError(f"{path}: not a readable point file ({_one_line(exc)})") from None
    if table.size == 0:
        raise LoadError(f"{path}: has no points")
    n_cols = table.shape[1]
    if header is not None:
        if len(header) != n_cols:
            raise LoadError(f"{path}: the header names {len(header)} columns but the rows have {n_cols}")
        if len(set(header)) != len(header):
            raise LoadError(f"{path}: the header names a column twice")
        where = {name: i for i, name in enumerate(header)}
        normal_names = _named_normals(path, header, "the header")
        points = table[:, [where[c] for c in "xyz"]]
        normals = table[:, [where[c] for c in normal_names]] if normal_names else None
        return _cloud(path, points, normals)
    if n_cols not in (3, 6):
        raise LoadError(f"{path}: rows have {n_cols} columns; curv reads x y z or x y z nx ny nz "
                        f"(name other columns in a header line)")
    normals = None
    if n_cols == 6:
        normals = table[:, 3:]
        length = np.linalg.norm(normals, axis=1)
        odd = ~((np.abs(length - 1) < 1e-3) | (length == 0) | np.isnan(length))
        if odd.any():
            row = int(np.flatnonzero(odd)[0])
            raise LoadError(f"{path}: columns 4-6 are not unit normals (row {row + 1} has length "
                            f"{length[row]:.4g}); curv reads x y z nx ny nz (name other columns in a header line)")
    return _cloud(path, np.ascontiguousarray(table[:, :3]), normals)


# --- PCD ----------------------------------------------------------------------------------------

def _pcd_header(path: Path) -> tuple[dict, int]:
    """(header fields, header length in bytes) of a PCD file."""
    keys = {}
    with open(path, "rb") as fh:
        for _ in range(64):
            raw = fh.readline()
            if not raw:
                break
            words = raw.decode("ascii", errors="replace").split()
            if not words or words[0].startswith("#"):
                continue
            keys[words[0].upper()] = words[1:]
            if words[0].upper() == "DATA":
                break
        offset = fh.tell()
    if "DATA" not in keys:
        raise LoadError(f"{path}: PCD header has no DATA line")
    if "FIELDS" not in keys:
        raise LoadError(f"{path}: PCD header has no FIELDS line")
    fields = keys["FIELDS"]
    count = len(fields)
    sizes = keys.get("SIZE", [])
    types = keys.get("TYPE", [])
    counts = keys.get("COUNT", ["1"] * count)
    if not (len(sizes) == len(types) == len(counts) == count):
        raise LoadError(f"{path}: PCD header lists {count} FIELDS but {len(sizes)} SIZE, {len(types)} TYPE "
                        f"and {len(counts)} COUNT entries")
    try:
        sizes, counts = [int(s) for s in sizes], [int(c) for c in counts]
        width = int(keys.get("WIDTH", ["0"])[0])
        height = int(keys.get("HEIGHT", ["1"])[0])
        points = int(keys["POINTS"][0]) if "POINTS" in keys else width * height
    except (ValueError, IndexError):
        raise LoadError(f"{path}: PCD header has a non-integer SIZE, COUNT, WIDTH, HEIGHT or POINTS") from None
    for key, value in (("WIDTH", width), ("HEIGHT", height), ("POINTS", points)):
        if value < 0:
            raise LoadError(f"{path}: PCD {key} {value} is negative")
    if width * height != points:
        raise LoadError(f"{path}: PCD header says WIDTH {width} x HEIGHT {height} but POINTS {points}")
    file_size = path.stat().st_size
    for name, size, n in zip(fields, sizes, counts):
        if n < 1 or n * size > file_size:  # one point's field must fit in the file
            raise LoadError(f"{path}: PCD field {name} has COUNT {n}; a file of {file_size} bytes holds "
                            f"1 to {max(file_size // max(size, 1), 1)}")
    kinds = {"F": "f", "I": "i", "U": "u"}
    dtype = []
    for i, (name, size, kind, n) in enumerate(zip(fields, sizes, types, counts)):
        if kind.upper() not in kinds or size not in (1, 2, 4, 8) or (kind.upper() == "F" and size < 4):
            raise LoadError(f"{path}: PCD field {name} has an unknown TYPE {kind} with SIZE {size}")
        name = f"_{i}" if name == "_" else name  # PCL pads records with fields named "_"
        dtype.append((name, f"<{kinds[kind.upper()]}{size}", (n,) if n > 1 else ()))
    if len({d[0] for d in dtype}) != len(dtype):
        raise LoadError(f"{path}: PCD header names a field twice")
    header = {"points": points, "data": keys["DATA"][0].lower() if keys["DATA"] else "",
              "dtype": np.dtype(dtype), "counts": counts}
    return header, offset


def _pcd_table(path: Path, header: dict, offset: int):
    """The points' records as a structured array (or a dict of columns) from the data section."""
    dtype, n = header["dtype"], header["points"]
    if header["data"] == "ascii":
        try:
            values = np.loadtxt(path, dtype=np.float64, skiprows=_lines_before(path, offset), ndmin=2,
                                comments="#")
        except ValueError as exc:
            raise LoadError(f"{path}: not a readable PCD file ({_one_line(exc)})") from None
        width = sum(header["counts"])
        if values.shape != (n, width) and not (n == 0 and values.size == 0):
            raise LoadError(f"{path}: PCD header declares {n} points of {width} values, "
                            f"the data has {values.shape[0]} rows of {values.shape[1]}")
        starts = np.cumsum([0] + header["counts"])
        return {name: values[:, starts[i]] for i, name in enumerate(dtype.names)}
    if header["data"] == "binary":
        return np.memmap(path, dtype=dtype, mode="r", offset=offset, shape=(n,)) if n else np.empty(0, dtype)
    if header["data"] == "binary_compressed":
        from .lzf import decompress

        with open(path, "rb") as fh:
            fh.seek(offset)
            sizes = np.frombuffer(fh.read(8), dtype="<u4")
            packed = fh.read()
        try:
            raw = decompress(packed, int(sizes[1]))
        except ValueError as exc:
            raise LoadError(f"{path}: {exc}") from None
        columns, at = {}, 0  # field after field, each for all points
        for name in dtype.names:
            field = dtype.fields[name][0]
            columns[name] = raw[at:at + n * field.itemsize].view(field.base).reshape((n, *field.shape))
            at += n * field.itemsize
        return columns
    raise LoadError(f"{path}: PCD DATA {header['data'] or '(missing)'} is not ascii, binary or binary_compressed")


_LZF_MAX_RATIO = 88
"""The most an LZF stream can expand: a 3-byte back reference copies at most 264 bytes."""


def _check_pcd_size(path: Path, header: dict, offset: int) -> None:
    """The PCD header's points x record size against the data after the header (one-line LoadError).

    Binary: exactly the records; binary_compressed: the size header's compressed size is the rest of
    the file, its unpacked size the records and at most an LZF stream's largest expansion of the
    compressed bytes. (Ascii data are read as text, bounded by the file, then counted.)
    """
    dtype, n = header["dtype"], header["points"]
    size = path.stat().st_size
    body = size - offset
    if header["data"] == "binary":
        expected = offset + n * dtype.itemsize
        if size != expected:
            more = "more" if size > expected else "fewer"
            raise LoadError(f"{path}: holds {abs(size - expected)} bytes {more} than its header declares "
                            f"(POINTS {n} of {dtype.itemsize} bytes)")
    elif header["data"] == "binary_compressed":
        with open(path, "rb") as fh:
            fh.seek(offset)
            sizes = np.frombuffer(fh.read(8), dtype="<u4")
        if sizes.size != 2:
            raise LoadError(f"{path}: PCD compressed data has no size header")
        packed, unpacked = int(sizes[0]), int(sizes[1])
        if packed != body - 8:
            raise LoadError(f"{path}: PCD compressed data holds {body - 8} bytes, its header says {packed}")
        if unpacked != n * dtype.itemsize:
            raise LoadError(f"{path}: PCD compressed data unpacks to {unpacked} bytes, "
                            f"POINTS {n} of {dtype.itemsize} bytes need {n * dtype.itemsize}")
        if unpacked > _LZF_MAX_RATIO * packed:
            raise LoadError(f"{path}: PCD compressed data's {packed} bytes cannot unpack to {unpacked} "
                            f"(LZF expands {_LZF_MAX_RATIO} times at most)")


def _lines_before(path: Path, offset: int) -> int:
    with open(path, "rb") as fh:
        return fh.read(offset).count(b"\n")


def _read_pcd(path: Path) -> PointCloud:
    header, offset = _pcd_header(path)
    names = header["dtype"].names
    missing = [c for c in "xyz" if c not in names]
    if missing:
        raise LoadError(f"{path}: PCD fields lack coordinate(s) {', '.join(missing)}")
    if any(header["dtype"].fields[c][0].shape for c in "xyz"):
        raise LoadError(f"{path}: PCD coordinates must have COUNT 1")
    normal_names = _named_normals(path, names, "PCD FIELDS")
    _check_pcd_size(path, header, offset)
    table = _pcd_table(path, header, offset)
    normals = _columns(table, normal_names) if normal_names else None
    return _cloud(path, _columns(table, "xyz"), normals)


# --- LAS / LAZ ----------------------------------------------------------------------------------

def _read_las(path: Path) -> PointCloud:
    try:
        import laspy
    except ImportError:
        raise LoadError(f"{path}: reading LAS/LAZ needs laspy ({_LAS_HINT})") from None
    try:
        las = laspy.read(path)
    except Exception as exc:  # noqa: BLE001 - laspy's errors, and lazrs's, become one line
        hint = f"; LAZ needs the lazrs backend ({_LAS_HINT})" if "LazBackend" in str(exc) else ""
        raise LoadError(f"{path}: not a readable {path.suffix.lstrip('.').upper()} file ({_one_line(exc)}){hint}") from None
    points = np.empty((len(las.points), 3), dtype=np.float64)
    for i, axis in enumerate("xyz"):
        points[:, i] = las[axis]  # scaled and offset coordinates
    normal_names = _named_normals(path, list(las.point_format.extra_dimension_names), "LAS extra bytes")
    normals = np.column_stack([np.asarray(las[c], dtype=np.float64) for c in normal_names]) if normal_names else None
    # LAS holds aerial and terrestrial scans in a map's coordinates, z up: their normals are turned up
    return _cloud(path, points, normals, georeferenced=True)


def _read_pts(path: Path) -> PointCloud:
    return _cloud(path, *read_pts_arrays(path))


_READERS = {".ply": _read_ply, ".xyz": _read_text, ".txt": _read_text, ".csv": _read_text,
            ".pcd": _read_pcd, ".pts": _read_pts, ".las": _read_las, ".laz": _read_las}


def _guarded(reader):
    """``reader`` run after the header checks (:func:`curv.formats.guards.check_header`)."""
    def read(path: Path):
        check_header(path)
        return reader(path)
    return read


def read_points(path) -> PointCloud:
    """Read a point-cloud file.

    Parameters
    ----------
    path : str or Path
        Vertex-only PLY (``x y z`` and optionally ``nx ny nz``), ``.xyz`` / ``.txt`` / ``.csv`` (rows of
        ``x y z`` or ``x y z nx ny nz``, whitespace or comma separated; an optional first line names the
        columns, and then other columns are ignored), PCD (ascii, binary, binary_compressed; fields
        ``x y z`` and optionally ``normal_x normal_y normal_z``) or LAS/LAZ (laspy; normals from extra
        dimensions ``nx ny nz`` or ``normal_x ...`` when present), PTS (Leica text: a count line, then
        ``x y z [i] [r g b]`` rows; Expe point sets, their ``normal`` property as normals).

    Returns
    -------
    PointCloud
        ``points`` (n, 3) float64 and ``normals`` (n, 3) float64 when the file has them, else None.

    Raises
    ------
    LoadError
        Missing, empty or malformed file, a NaN coordinate, a missing field, a header that promises
        more than the file holds: one line naming the file.
    """
    path = Path(path)
    check_readable(path)
    reader = _READERS.get(path.suffix.lower())
    if reader is None:
        raise LoadError(f"{path}: not a point-cloud file (use one of .ply, {', '.join(POINT_SUFFIXES)})")
    return read_with(_guarded(reader), path, path.suffix.lstrip(".").upper())
