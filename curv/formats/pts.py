"""PTS point files: Leica's text format and Expé's point sets (MeshLab reads both as ``.pts``).

- Leica PTS: a line with the number of points, then one point a line, ``x y z``, ``x y z i``,
  ``x y z r g b`` or ``x y z i r g b`` (intensity, colour 0-255); a file may hold several scans,
  each opened by its own count line.
- Expé point sets (``[Expe/PointSet/Binary/0.1]``, ``.../Binary/0.2``, ``.../Ascii/0.2``): a header of
  ``property NAME BYTES`` lines (0.1: position 12 bytes, normal 12, radius 4, colour 4) or
  ``property NAME COUNT TYPE`` lines (0.2: ``r32``, ``i16``, ``ui8``, ...), ``nofpoints N``, ``data``,
  then N little-endian records (binary) or N lines of ``;``-separated properties whose components
  are separated by commas (ascii).

The positions are read, and an Expé file's ``normal`` property as the normals; intensity, colour
and radius are read past, as :mod:`.pointio` does with a LAS file's intensity and colours. Every
count is checked against the file before anything is allocated: a count line promising more
points than the file has lines, or ``nofpoints`` times the record size beyond the file's size, is
a one-line :class:`LoadError` naming the field.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np

from ..core.errors import LoadError
from ..core.paths import one_line
from ..core.wording import count_text

__all__ = ["read_pts_arrays", "EXPE_SIGNATURE"]

EXPE_SIGNATURE = b"[Expe/PointSet/"

_EXPE_TYPES = {"r32": "<f4", "r16": "<f2", "r64": "<f8", "i32": "<i4", "ui32": "<u4", "i16": "<i2",
               "ui16": "<u2", "i8": "i1", "ui8": "u1"}
_EXPE_V01 = {"position": ("<f4", 3), "normal": ("<f4", 3), "radius": ("<f4", 1), "color": ("u1", 4)}
_LEICA_COLUMNS = (3, 4, 6, 7)
_COUNT = re.compile(rb"\s*(\d+)\s*")


def _fail(path: Path, text: str):
    raise LoadError(f"{path}: {text}")


def read_pts_arrays(path) -> tuple[np.ndarray, np.ndarray | None]:
    """``(points (n, 3) float64, normals (n, 3) float64 or None)`` from a Leica or Expé ``.pts`` file.

    Raises
    ------
    LoadError
        A count the file cannot hold, a row of the wrong width, a malformed header: one line.
    """
    path = Path(path)
    with open(path, "rb") as fh:
        start = fh.read(len(EXPE_SIGNATURE))
    if start == EXPE_SIGNATURE:
        return _read_expe(path)
    return _read_leica(path), None


# --- Leica --------------------------------------------------------------------------------------

def _read_leica(path: Path) -> np.ndarray:
    raw = path.read_bytes()
    newlines = np.flatnonzero(np.frombuffer(raw, np.uint8) == 10)
    starts = np.concatenate([[0], newlines + 1])
    ends = np.concatenate([newlines, [len(raw)]])
    if raw.endswith(b"\n"):  # the newline ends the last line; no empty line after it
        starts, ends = starts[:-1], ends[:-1]
    blocks, index = [], 0
    while index < starts.size:  # each pass consumes a line at least
        text = raw[starts[index]:ends[index]]
        if not text.strip():
            index += 1
            continue
        match = _COUNT.fullmatch(text)
        if match is None:
            what = "first line" if not blocks else f"line {index + 1}"
            _fail(path, f"PTS {what} is not a point count: {text[:40].decode('ascii', 'replace')!r}")
        count = int(match.group(1))
        if index + count >= starts.size:
            _fail(path, f"PTS point count {count} on line {index + 1} is more than the "
                        f"{count_text(starts.size - index - 1, 'line', 'lines')} after it")
        block = raw[starts[index + 1]:ends[index + count]] if count else b""
        blocks.append(_leica_block(path, block, count, index + 1))
        index += count + 1
    if not blocks:
        _fail(path, "has no points")
    return np.concatenate(blocks) if len(blocks) > 1 else blocks[0]


def _leica_block(path: Path, text: bytes, count: int, line: int) -> np.ndarray:
    """The (count, 3) positions of the rows after the count line at ``line`` (1-based)."""
    if count == 0:
        return np.empty((0, 3))
    try:
        table = np.loadtxt(io.StringIO(text.decode("ascii")), dtype=np.float64, ndmin=2, comments=None)
    except (ValueError, UnicodeDecodeError) as exc:
        _fail(path, f"PTS rows after line {line} are not numbers ({one_line(exc)})")
    if table.shape[0] != count:
        _fail(path, f"PTS point count {count} on line {line} is followed by "
                    f"{count_text(table.shape[0], 'row', 'rows')}")
    if table.shape[1] not in _LEICA_COLUMNS:
        _fail(path, f"PTS rows after line {line} have {table.shape[1]} columns; Leica PTS has x y z, x y z i, "
                    f"x y z r g b or x y z i r g b")
    return np.ascontiguousarray(table[:, :3])


# --- Expé ---------------------------------------------------------------------------------------

def _expe_header(path: Path) -> tuple[str, list[tuple[str, str, int]], int, int]:
    """(``Binary`` or ``Ascii``, properties as (name, numpy type, components), points, data offset)."""
    with open(path, "rb") as fh:
        head = fh.read(1 << 16)
    at = re.search(rb"(^|\n)[ \t]*data[ \t\r]*\n", head)
    if at is None:
        _fail(path, "Expe point set header has no data line in its first 64 KiB")
    lines = head[:at.start()].decode("ascii", errors="replace").split("\n")
    kind = re.fullmatch(r"\s*\[Expe/PointSet/(Binary|Ascii)/(0\.1|0\.2)\]\s*", lines[0])
    if kind is None:
        _fail(path, f"Expe point set header {lines[0][:40]!r} is not Binary/0.1, Binary/0.2 or Ascii/0.2")
    layout, version = kind.groups()
    props, points = [], None
    for text in lines[1:]:
        words = text.split()
        if not words:
            continue
        if words[0] == "nofpoints" and len(words) == 2 and re.fullmatch(r"[+-]?\d+", words[1]):
            points = int(words[1])
        elif words[0] == "property" and version == "0.1" and len(words) == 3 and words[2].isdigit():
            dtype, n = _EXPE_V01.get(words[1], ("u1", int(words[2])))
            if np.dtype(dtype).itemsize * n != int(words[2]):
                _fail(path, f"Expe property {words[1]} has {words[2]} bytes; version 0.1 gives it "
                            f"{np.dtype(dtype).itemsize * n}")
            props.append((words[1], dtype, n))
        elif words[0] == "property" and version == "0.2" and len(words) == 4 and words[2].isdigit():
            if words[3] not in _EXPE_TYPES:
                _fail(path, f"Expe property {words[1]} has an unknown type {words[3][:20]!r}")
            props.append((words[1], _EXPE_TYPES[words[3]], int(words[2])))
        else:
            _fail(path, f"Expe point set header line {text.strip()[:40]!r} is not a property or nofpoints line")
    if points is None:
        _fail(path, "Expe point set header has no nofpoints line")
    if points < 0:
        _fail(path, f"Expe nofpoints {points} is negative")
    names = [p[0] for p in props]
    if "position" not in names or len(set(names)) != len(names):
        _fail(path, "Expe point set header must name a position property, and each property once")
    for name in ("position", "normal"):
        if name in names and props[names.index(name)][2] != 3:
            _fail(path, f"Expe property {name} has {props[names.index(name)][2]} components, not 3")
    return layout, props, points, at.end()


def _read_expe(path: Path) -> tuple[np.ndarray, np.ndarray | None]:
    layout, props, n, offset = _expe_header(path)
    size = path.stat().st_size
    dtype = np.dtype([(name, kind, (count,)) for name, kind, count in props])
    if layout == "Binary":
        if offset + n * dtype.itemsize != size:
            _fail(path, f"Expe nofpoints {n} x {dtype.itemsize} bytes needs {n * dtype.itemsize} bytes of data; "
                        f"the file holds {size - offset}")
        table = np.fromfile(path, dtype=dtype, count=n, offset=offset)
        columns = {name: table[name] for name in dtype.names}
    else:
        width = sum(count for _, _, count in props)
        if n * 2 * width > size - offset + 1:  # a character and a separator for each value
            _fail(path, f"Expe nofpoints {n} x {width} values needs at least {n * 2 * width} bytes; "
                        f"the file holds {size - offset}")
        with open(path, "rb") as fh:
            fh.seek(offset)
            text = fh.read().decode("ascii", errors="replace").replace(";", " ").replace(",", " ")
        try:
            values = np.loadtxt(io.StringIO(text), dtype=np.float64, ndmin=2, comments=None)
        except ValueError as exc:
            _fail(path, f"Expe ascii data are not numbers ({one_line(exc)})")
        if values.shape != (n, width) and not (n == 0 and values.size == 0):
            _fail(path, f"Expe nofpoints {n} of {width} values, the data has {values.shape[0]} rows of "
                        f"{values.shape[1] if values.ndim == 2 else 0}")
        starts = np.cumsum([0] + [count for _, _, count in props])
        columns = {name: values[:, starts[i]:starts[i + 1]] for i, (name, _, _) in enumerate(props)}
    points = np.asarray(columns["position"], dtype=np.float64)
    normals = np.asarray(columns["normal"], dtype=np.float64) if "normal" in columns else None
    return points, normals
