"""Reading meshes as raw arrays, keeping polygons where the format has them (below :mod:`curv.io`).

PLY through plyfile (polygons kept), OBJ through meshio and OFF (polygons kept), anything else
trimesh reads (STL, glTF/GLB, 3MF, ...) through trimesh (triangles). Every failure becomes a
:class:`LoadError` or :class:`MeshError` whose one-line message starts with the file name. Before a
library sees a file, :func:`curv.formats.guards.check_header` checks what its header promises
against its size, so that no header makes a reader allocate or loop beyond the file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.errors import LoadError
from ..core.paths import check_readable as _check_path
from ..core.paths import read_with
from .guards import PLY_TYPE_SIZES, PlyHeader, check_header, check_off_header, check_ply_header, read_ply_header

__all__ = ["read_arrays", "peek_counts", "is_point_file"]

_MESHIO_SUFFIXES = {".obj"}


_PLY_LENGTH_TYPES = {"uchar": "u1", "uint8": "u1", "ushort": "u2", "uint16": "u2", "uint": "u4", "uint32": "u4",
                     "char": "i1", "int8": "i1", "short": "i2", "int16": "i2", "int": "i4", "int32": "i4"}
"""numpy type codes of the PLY integer types a list's length may have."""


def _first_face_length(fh, header: PlyHeader) -> int:
    """The corner count of a binary PLY's first face, read where the header puts it; 3 when it cannot
    be placed (an element with a list before the faces, an unknown type, no face). A mesh whose faces
    all have that count is then memory-mapped whole (quads as well as triangles); a mixed one is
    read face by face, as before."""
    offset = header.header_bytes
    for element in header.elements:
        if element.name == "face":
            length_type = element.properties[0][2] if element.properties else None
            if offset is None or length_type not in _PLY_LENGTH_TYPES:
                return 3
            order = "<" if header.format == "binary_little_endian" else ">"
            fh.seek(offset)
            raw = fh.read(PLY_TYPE_SIZES[length_type])
            if len(raw) < PLY_TYPE_SIZES[length_type]:
                return 3
            return max(3, int(np.frombuffer(raw, order + _PLY_LENGTH_TYPES[length_type])[0]))
        sizes = [PLY_TYPE_SIZES.get(kind) if length is None else None for _, kind, length in element.properties]
        if element.count is None or offset is None or None in sizes:
            return 3
        offset += element.count * sum(sizes)
    return 3


def _ply_trailing_data(fh, fmt: str, header_end: int, counts: dict[str, int], position: int) -> bool:
    """True when the file holds more data than the header's element counts declare."""
    if fmt == "ascii":
        fh.seek(header_end)
        lines = [ln for ln in fh.read().split(b"\n") if ln.strip()]
        return len(lines) > sum(counts.values())
    fh.seek(position)
    return bool(fh.read(64).strip())


def _read_off(path: Path):
    """OFF / COFF / NOFF: vertices (extra per-vertex values ignored), polygons of any size."""
    text = path.read_bytes().decode("ascii", errors="strict")
    lines = [ln.split("#", 1)[0].split() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln]
    if not lines or not lines[0][0].upper().endswith("OFF"):
        raise ValueError("no OFF keyword on the first line")
    head = lines[0][1:] or lines[1]
    body = lines[1:] if lines[0][1:] else lines[2:]
    if len(head) < 2:
        raise ValueError("missing vertex and face counts")
    nv, nf = int(head[0]), int(head[1])
    if len(body) < nv + nf:
        raise ValueError(f"header declares {nv} vertices and {nf} faces but the file ends after {len(body)} lines")
    if len(body) > nv + nf:
        raise ValueError(f"header declares {nv} vertices and {nf} faces but the file has {len(body)} data lines")
    vertices = np.array([ln[:3] for ln in body[:nv]], dtype=np.float64).reshape(-1, 3)
    faces = [np.array(ln[1:1 + int(ln[0])], dtype=np.int64) for ln in body[nv:]]
    bad = [i for i, (ln, f) in enumerate(zip(body[nv:], faces)) if f.size != int(ln[0])]
    if bad:
        raise ValueError(f"face {bad[0]} lists fewer indices than its count")
    if not faces:
        raise LoadError(f"{path}: has {nv} vertices but no faces; curv needs a mesh")
    return vertices, faces


def _read_ply(path: Path):
    from plyfile import PlyData, PlyElementParseError

    with open(path, "rb") as fh:
        header = read_ply_header(fh)
        fmt, counts, lists = header.format, header.counts, header.lists
        header_end = fh.tell()
        fh.seek(0)
        key = next((k for k in ("vertex_indices", "vertex_index") if k in lists.get("face", [])), None)
        data = None
        if fmt.startswith("binary") and key is not None and lists["face"] == [key]:
            # fast path: faces of one size (the first's) memory-mapped as an (m, k) array, no
            # per-face Python objects: a 1M-vertex quad grid loads in 0.1 s instead of 3 s
            corners = _first_face_length(fh, header)
            fh.seek(0)
            try:
                data = PlyData.read(fh, known_list_len={"face": {key: corners}})
            except PlyElementParseError:  # faces of other sizes (or a broken file: the plain read says how)
                fh.seek(0)
        if data is None:
            data = PlyData.read(fh)
        position = fh.tell() if not fh.closed else 0
    with open(path, "rb") as fh:
        if _ply_trailing_data(fh, fmt, header_end, counts, position):
            raise LoadError(f"{path}: holds more data than its header declares "
                            f"({', '.join(f'{n} {e}' for e, n in counts.items())}); the element counts are wrong")
        names = [e.name for e in data.elements]
        if "vertex" not in names:
            raise LoadError(f"{path}: PLY file has no vertex element")
        vert = data["vertex"].data
        missing = [c for c in "xyz" if c not in vert.dtype.names]
        if missing:
            raise LoadError(f"{path}: PLY vertices lack coordinate(s) {', '.join(missing)}")
        vertices = np.stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"], axis=1)
        if "face" not in names or len(data["face"].data) == 0:
            raise LoadError(f"{path}: has {len(vertices)} vertices but no faces (a point cloud?); curv needs a mesh")
        face = data["face"].data
        key = next((k for k in ("vertex_indices", "vertex_index") if k in face.dtype.names), None)
        if key is None:
            raise LoadError(f"{path}: PLY faces have no vertex_indices list")
        column = face[key]
        if column.dtype != object:
            return vertices, np.asarray(column)  # Mesh converts to int64 once, copying
        sizes = np.fromiter((len(p) for p in column), dtype=np.int64, count=len(column))
        if np.all(sizes == sizes[0]) and sizes[0] > 0:
            return vertices, np.stack(column).astype(np.int64)
        return vertices, list(column)


def _read_meshio(path: Path):
    import meshio

    m = meshio.read(path)
    polys = []
    for block in m.cells:
        data = block.data
        if block.type in ("vertex", "line"):
            continue
        if isinstance(data, np.ndarray) and data.ndim == 2:
            polys.extend(data)
        else:
            polys.extend(np.asarray(p) for p in data)
    if not polys:
        raise LoadError(f"{path}: has {len(m.points)} points but no faces; curv needs a mesh")
    pts = np.asarray(m.points, dtype=np.float64)
    if pts.ndim == 2 and pts.shape[1] == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    return pts, polys


def _read_trimesh(path: Path):
    import trimesh

    loaded = trimesh.load(path, force="mesh", process=False)
    faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))))
    if faces.size == 0:
        raise LoadError(f"{path}: contains no faces")
    return np.asarray(loaded.vertices, dtype=np.float64), faces


def peek_counts(path) -> tuple[int, int] | None:
    """``(n_vertices, n_faces)`` from a PLY or OFF header without reading the data; None otherwise.

    Never raises: a file it cannot peek into gives None (:func:`load` then reports the problem).
    """
    path = Path(path)
    try:
        if path.suffix.lower() == ".ply":
            counts = check_ply_header(path).counts  # counts the file can hold, or a LoadError
            if "vertex" in counts:
                return counts["vertex"], counts.get("face", 0)
        elif path.suffix.lower() == ".off":
            check_off_header(path)
            with open(path, "rb") as fh:
                words = fh.read(4096).split()
            if words and words[0].upper().endswith(b"OFF") and len(words) >= 3:
                return int(words[1]), int(words[2])
    except (OSError, ValueError):  # LoadError is an OSError
        return None
    return None


def is_point_file(path) -> bool:
    """True when ``path`` holds a point cloud: a point-cloud suffix, or a PLY that declares no faces."""
    from .pointio import POINT_SUFFIXES

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".ply" and path.is_file():
        counts = peek_counts(path)
        return counts is not None and counts[1] == 0
    return suffix in POINT_SUFFIXES


def read_arrays(path) -> tuple[np.ndarray, list | np.ndarray]:
    """Read raw ``(vertices (n, 3), faces)`` from a file without building a :class:`Mesh`.

    Raises
    ------
    LoadError
        Missing, unreadable, empty, malformed or face-less file, or a header that promises more
        than the file holds.
    """
    path = Path(path)
    _check_path(path)
    suffix = path.suffix.lower()
    reader = {".ply": _read_ply, ".off": _read_off}.get(suffix) or (
        _read_meshio if suffix in _MESHIO_SUFFIXES else _read_trimesh)

    def guarded(path: Path):
        check_header(path)
        return reader(path)

    return read_with(guarded, path, suffix.lstrip(".").upper() or "mesh")
