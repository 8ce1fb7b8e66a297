"""What a file's header promises, checked against the file's size before a third-party reader sees it.

The libraries curv reads with trust their headers: plyfile allocates a PLY element's declared count
of rows before it reads one, laspy reads as many VLRs as the header counts (:mod:`.lasheader`),
trimesh zero-fills a glTF accessor of any declared count. A header that promises more than the file
holds would make them allocate without bound or loop for ever. Each check here reads the header
only, works in time and memory bounded by the file's size, and turns a broken promise into a
one-line :class:`LoadError` naming the file and the field:

- PLY: every element's count times the least bytes one of its rows takes (binary: the fixed
  properties' sizes plus each list's length field; ascii: a character and a separator per
  property) fits in the data after the header; counts are not negative;
- OFF: the vertex and face counts are not negative, and each fits a line of 2 bytes in the file;
- STL: a binary file's face count times 50 bytes plus its 84-byte header is the file's size, else
  the file is ASCII (``solid ...``);
- glTF / GLB: the GLB container's length and every chunk fit in the file; every buffer's byteLength
  fits in its data (the BIN chunk, a ``data:`` URI or the file it names), every bufferView in its
  buffer, every accessor (count, byteOffset, byteStride) in its bufferView; an accessor without
  one (zero-filled) holds at most :data:`ZERO_ACCESSOR_RATIO` times the file's size;
- LAS / LAZ: :func:`curv.formats.lasheader.check_las_header`.

The point readers' own formats (PCD, PTS, text) are bounded by their readers (:mod:`.pointio`,
:mod:`.pts`), which check their headers the same way before allocating.
"""

from __future__ import annotations

import json
import re
import struct
from dataclasses import dataclass, field
from pathlib import Path

from ..core.errors import LoadError
from ..core.paths import one_line
from .lasheader import check_las_header

__all__ = ["check_header", "read_ply_header", "PlyHeader", "check_ply_header", "check_off_header",
           "check_stl_header", "check_gltf_header", "ZERO_ACCESSOR_RATIO"]

ZERO_ACCESSOR_RATIO = 64
"""How many times the file's size a glTF accessor without data (all zeros) may take."""

PLY_TYPE_SIZES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2, "int16": 2,
                  "uint16": 2, "int": 4, "uint": 4, "int32": 4, "uint32": 4, "float": 4, "float32": 4,
                  "double": 8, "float64": 8}
"""Bytes of each PLY scalar type."""

_HEADER_BLOCK = 1 << 16


def _fail(path: Path, text: str):
    raise LoadError(f"{path}: {text}")


# --- PLY ----------------------------------------------------------------------------------------

@dataclass
class PlyElementHeader:
    """One ``element`` line of a PLY header and its properties."""

    name: str
    count: int | None
    """The declared count; None when it is not an integer (plyfile reports it)."""
    properties: list[tuple[str, str, str | None]] = field(default_factory=list)
    """(name, value type, list length type or None) of each property."""

    @property
    def lists(self) -> list[str]:
        return [name for name, _, length in self.properties if length is not None]


@dataclass
class PlyHeader:
    """A PLY header as far as sizes go: the format, the elements in order, the header's length."""

    format: str
    elements: list[PlyElementHeader]
    header_bytes: int | None
    """Bytes up to and including the ``end_header`` line; None when the file has none."""

    @property
    def counts(self) -> dict[str, int]:
        return {e.name: e.count for e in self.elements if e.count is not None}

    @property
    def lists(self) -> dict[str, list[str]]:
        """The list properties' names of each element."""
        return {e.name: e.lists for e in self.elements}


def read_ply_header(fh) -> PlyHeader:
    """Parse a PLY header from an open binary file positioned after the ``ply`` line.

    Reads line by line up to ``end_header`` (or the end of the file); lenient: a line it does not
    understand is skipped, so that plyfile reports what is wrong with it.
    """
    fmt, elements = "", []
    for _ in range(1 << 20):  # a header line takes a byte at least; the loop ends at the end of the file
        line = fh.readline(_HEADER_BLOCK)
        if not line:
            return PlyHeader(fmt, elements, None)
        words = line.decode("ascii", errors="replace").split()
        if not words:
            continue
        if words[0] == "format" and len(words) > 1:
            fmt = words[1]
        elif words[0] == "element" and len(words) == 3:
            count = int(words[2]) if re.fullmatch(r"[+-]?\d+", words[2]) else None
            elements.append(PlyElementHeader(words[1], count))
        elif words[0] == "property" and elements:
            if len(words) == 5 and words[1] == "list":
                elements[-1].properties.append((words[4], words[3], words[2]))
            elif len(words) == 3:
                elements[-1].properties.append((words[2], words[1], None))
        elif words[0] == "end_header":
            return PlyHeader(fmt, elements, fh.tell())
    return PlyHeader(fmt, elements, None)


def check_ply_header(path) -> PlyHeader:
    """Check a PLY header's element counts against the data after it (see the module's notes).

    Returns
    -------
    PlyHeader
        The parsed header (also when the file is not a PLY file or its header is malformed: plyfile
        then says what is wrong).
    """
    path = Path(path)
    size = path.stat().st_size
    with open(path, "rb") as fh:
        if fh.readline(8).strip() != b"ply":
            return PlyHeader("", [], None)
        header = read_ply_header(fh)
    if header.header_bytes is None:
        return header
    body = size - header.header_bytes
    binary = header.format.startswith("binary")
    need = 0
    for element in header.elements:
        if element.count is None:
            continue
        if element.count < 0:
            _fail(path, f"PLY header's element {element.name} count {element.count} is negative")
        if binary:
            sizes = [PLY_TYPE_SIZES.get(length if length is not None else kind) for _, kind, length in element.properties]
            if None in sizes:
                return header  # an unknown type: plyfile names it
            row, unit = sum(sizes), "bytes"
        else:
            row, unit = max(1, 2 * len(element.properties)), "characters"
        before = need
        need += element.count * row
        if need > body + (0 if binary else 1):  # an ascii file's last row may lack its newline
            after = f" after the {before} bytes of the elements before it" if before else ""
            _fail(path, f"PLY header's element {element.name} count {element.count} needs at least "
                        f"{element.count * row} bytes ({row} {unit} a row){after}; the file holds {body} "
                        f"bytes after its header")
    return header


# --- OFF ----------------------------------------------------------------------------------------

def check_off_header(path) -> None:
    """An OFF file's vertex and face counts: integers, not negative, each a line of 2 bytes at least."""
    path = Path(path)
    size = path.stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(_HEADER_BLOCK)
    words = []
    for raw in head.split(b"\n")[:64]:
        words += raw.split(b"#", 1)[0].split()
        if len(words) >= 3:
            break
    if not words or not words[0].upper().endswith(b"OFF"):
        return  # the reader says it is not an OFF file
    for name, word in zip(("vertex", "face"), words[1:3]):
        try:
            value = int(word)
        except ValueError:
            _fail(path, f"OFF {name} count {word.decode('ascii', 'replace')[:20]!r} is not an integer")
        if value < 0:
            _fail(path, f"OFF {name} count {value} is negative")
        if 2 * value > size:
            _fail(path, f"OFF {name} count {value} needs a line of 2 bytes at least for each; the file has "
                        f"{size} bytes")


# --- STL ----------------------------------------------------------------------------------------

def check_stl_header(path) -> None:
    """A binary STL's face count against the file's size; a file that does not match must be ASCII."""
    path = Path(path)
    size = path.stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(84)
    if len(head) == 84:
        faces = struct.unpack_from("<I", head, 80)[0]
        if 84 + 50 * faces == size:
            return
    if head.lstrip()[:5].lower() == b"solid":
        return  # ASCII: trimesh parses text, bounded by the file
    if len(head) < 84:
        _fail(path, f"STL file of {size} bytes is neither ASCII (solid ...) nor a binary STL (84-byte header)")
    _fail(path, f"binary STL face count {faces} needs 84 + 50 x {faces} = {84 + 50 * faces} bytes; "
                f"the file has {size}")


# --- glTF / GLB ---------------------------------------------------------------------------------

_GLB_BIN = 0x004E4942
_GLTF_COMPONENT = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
_GLTF_TYPE = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


def check_gltf_header(path) -> None:
    """A GLB container against the file, and every buffer, bufferView and accessor against its data."""
    path = Path(path)
    size = path.stat().st_size
    bin_length = None
    with open(path, "rb") as fh:
        head = fh.read(20)
        if head[:4] != b"glTF":
            text = head + fh.read()  # a .gltf: the JSON document
        else:
            if len(head) < 20:
                _fail(path, f"GLB file of {size} bytes is shorter than its 12-byte header and a chunk header")
            _version, length, json_length, _json_type = struct.unpack_from("<IIII", head, 4)
            if length > size:
                _fail(path, f"GLB header's length {length} is beyond the end of the file ({size} bytes)")
            if 20 + json_length > length:
                _fail(path, f"GLB JSON chunk length {json_length} runs past the file's length {length}")
            text = fh.read(json_length)
            # every chunk trimesh will read: it reads one after the other from the end of the JSON
            # (aligned in valid files) while it has read less than the header's length, and stops
            # at a short chunk header; each chunk takes 8 bytes at least
            start = at = 20 + json_length
            while at - start < length and at + 8 <= size:
                fh.seek(at)
                chunk_length, chunk_type = struct.unpack("<II", fh.read(8))
                kind = "BIN" if chunk_type == _GLB_BIN else f"chunk at byte {at}"
                if at + 8 + chunk_length > size:
                    _fail(path, f"GLB {kind} length {chunk_length} runs past the end of the file ({size} bytes)")
                if chunk_type == _GLB_BIN and bin_length is None:
                    bin_length = chunk_length
                at += 8 + chunk_length
    try:
        doc = json.loads(text)
    except (ValueError, RecursionError) as exc:
        _fail(path, f"glTF JSON does not parse ({one_line(exc)})")
    if not isinstance(doc, dict):
        _fail(path, "glTF JSON is not an object")
    available = []
    for index, buffer in enumerate(_items(doc, "buffers")):
        have = _buffer_bytes(path, buffer, bin_length if index == 0 else None)
        declared = _integer(path, buffer, "byteLength", f"buffer {index}")
        if have is not None and declared > have:
            _fail(path, f"glTF buffer {index} byteLength {declared} is more than its {have} bytes of data")
        available.append(declared)
    views = []
    for index, view in enumerate(_items(doc, "bufferViews")):
        what = f"bufferView {index}"
        buffer = _integer(path, view, "buffer", what)
        offset = _integer(path, view, "byteOffset", what, 0)
        length = _integer(path, view, "byteLength", what)
        if buffer >= len(available):
            _fail(path, f"glTF {what} names buffer {buffer}; the file has {len(available)}")
        if offset + length > available[buffer]:
            _fail(path, f"glTF {what} byteOffset {offset} + byteLength {length} runs past buffer {buffer}'s "
                        f"{available[buffer]} bytes")
        views.append((length, _integer(path, view, "byteStride", what, 0)))
    for index, accessor in enumerate(_items(doc, "accessors")):
        _check_accessor(path, index, accessor, views, size)


def _check_accessor(path: Path, index: int, accessor: dict, views: list, size: int) -> None:
    what = f"accessor {index}"
    count = _integer(path, accessor, "count", what)
    component = _GLTF_COMPONENT.get(accessor.get("componentType"))
    width = _GLTF_TYPE.get(accessor.get("type"))
    if component is None or width is None:
        return  # trimesh names the unknown type
    element = component * width
    if "bufferView" not in accessor:
        if count * element > ZERO_ACCESSOR_RATIO * size:
            _fail(path, f"glTF {what} count {count} without a bufferView would fill {count * element} bytes "
                        f"with zeros, more than {ZERO_ACCESSOR_RATIO} times the file's {size}")
        return
    view = _integer(path, accessor, "bufferView", what)
    if view >= len(views):
        _fail(path, f"glTF {what} names bufferView {view}; the file has {len(views)}")
    length, stride = views[view]
    offset = _integer(path, accessor, "byteOffset", what, 0)
    need = offset + (max(count - 1, 0) * max(stride, element) + element if count else 0)
    if need > length:
        _fail(path, f"glTF {what} count {count} of {element} bytes from byteOffset {offset}"
                    f"{f' with byteStride {stride}' if stride else ''} needs {need} bytes; bufferView {view} "
                    f"holds {length}")


def _items(doc: dict, key: str) -> list:
    items = doc.get(key, [])
    return [item if isinstance(item, dict) else {} for item in items] if isinstance(items, list) else []


def _integer(path: Path, obj: dict, key: str, what: str, default: int | None = None) -> int:
    value = obj.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        _fail(path, f"glTF {what} {key} {value!r} is not a non-negative integer")
    return value


def _buffer_bytes(path: Path, buffer: dict, bin_length: int | None) -> int | None:
    """Bytes a glTF buffer's data hold: the GLB BIN chunk, a data: URI, a file beside ``path``; None if unknown."""
    uri = buffer.get("uri")
    if uri is None:
        return bin_length
    if not isinstance(uri, str):
        return None
    if uri.startswith("data:"):
        meta, _, payload = uri.partition(",")
        if ";base64" in meta:  # 4 characters for 3 bytes; trimesh reports malformed base64 itself
            return len(payload.rstrip("=")) * 3 // 4
        return len(payload)
    target = path.parent / uri
    return target.stat().st_size if target.is_file() else None


# --- dispatch -----------------------------------------------------------------------------------

_CHECKS = {".ply": check_ply_header, ".off": check_off_header, ".stl": check_stl_header,
           ".gltf": check_gltf_header, ".glb": check_gltf_header, ".las": check_las_header,
           ".laz": check_las_header}


def check_header(path) -> None:
    """Check what ``path``'s header promises against its size, by suffix (see the module's notes).

    Raises
    ------
    LoadError
        One line naming the file and the field whose promise the file cannot hold.
    """
    path = Path(path)
    check = _CHECKS.get(path.suffix.lower())
    if check is not None:
        check(path)
