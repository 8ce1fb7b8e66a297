"""What a LAS or LAZ file's header promises, checked against the file before laspy reads it.

laspy trusts the header: it reads as many VLRs as the header counts (past the end of the file, so a
text file that starts with ``LASF`` made it loop for ever), as many EVLRs, and allocates the point
count times the record length before it reads a point. :func:`check_las_header` reads only the
header, the VLR and EVLR headers and, for LAZ, the laszip VLR and the chunk table, and refuses a
promise the file cannot hold with a one-line :class:`LoadError` naming the field. Its work is
bounded by the file's size: each record it walks takes room in the file, and every count is
checked against that room before a loop runs over it.

What is checked (LAS 1.0-1.5, the public header of the ASPRS specification):

- the signature ``LASF``, version 1.0-1.5, the header size (at least the version's fixed part, at
  most the offset to the point data), the offset to the point data (within the file);
- the VLRs: their number and each one's 54-byte header and record length fit between the header
  and the point data;
- the point format (0-10), a record length at least the format's size, finite non-zero scales and
  finite offsets;
- uncompressed points: point count x record length fits between the point data and the first EVLR
  (or the end of the file);
- the EVLRs (1.4 and later): each 60-byte header and record fits in the file, after the point data;
- LAZ (the point format's compression bit): the laszip VLR (its length, items and their sizes
  summing to the record length, the chunk size), the chunk table's offset (within the file), its
  number of chunks (each chunk takes at least a byte), its chunks' sizes (they fit in the point
  data) and point counts (they add up to the point count), and at most
  :data:`LAZ_MAX_POINTS_PER_BYTE` points per compressed byte in every chunk (for chunks of a fixed
  size, the chunk size: lazrs allocates that many records for each chunk, the last one too). A
  LAZ file is compressed, so its point count is checked against its chunks, not against the
  file's size; in layered chunks (point formats 6-10) each chunk's point count and layer sizes
  are checked against the chunk's bytes (a decompressor allocates a layer's size before reading it).

:func:`check_las_header` is the one owner of these rules: whatever reads or streams LAS/LAZ
files calls it first and uses the :class:`LasHeaderInfo` it returns (the point data's byte
range, the chunk table) rather than parse the header again.
"""

from __future__ import annotations

import io
import math
import struct
from dataclasses import dataclass
from pathlib import Path

from ..core.errors import LoadError
from ..core.paths import is_panic, one_line

__all__ = ["check_las_header", "LasHeaderInfo", "LaszipInfo", "VlrInfo", "LAZ_MAX_POINTS_PER_BYTE",
           "POINT_RECORD_SIZES"]

POINT_RECORD_SIZES = {0: 20, 1: 28, 2: 26, 3: 34, 4: 57, 5: 63, 6: 30, 7: 36, 8: 38, 9: 59, 10: 67}
"""The size in bytes of each LAS point format's standard fields (a record may add extra bytes)."""

LAZ_MAX_POINTS_PER_BYTE = 4096
"""The most points a LAZ chunk may hold per compressed byte.

Measured with lazrs on the most compressible data there is (every point the same, every field
zero): 148 points per byte in laszip's default chunks of 50,000 points, 655 in one chunk of 8
million (point formats 0 and 6); real scans hold 1 to 2. The limit leaves a factor of 6 over the
extreme, and bounds what a chunk table can make a reader allocate by the file's size.
"""

_MIN_HEADER_SIZE = {0: 227, 1: 227, 2: 227, 3: 235, 4: 375, 5: 393}
_VLR_HEADER = 54
_EVLR_HEADER = 60
_LASZIP_USER = b"laszip encoded"
_LASZIP_RECORD = 22204
_VARIABLE_CHUNKS = 0xFFFFFFFF


@dataclass(frozen=True)
class VlrInfo:
    """One (extended) variable-length record: who wrote it and where its data lie in the file."""

    user_id: str
    record_id: int
    data_offset: int
    """Byte offset of the record's data (after its 54- or 60-byte header)."""
    length: int
    """Length of the record's data in bytes."""


@dataclass(frozen=True)
class LaszipInfo:
    """The laszip VLR and chunk table of a LAZ file."""

    compressor: int
    """1 pointwise, 2 pointwise and chunked, 3 layered and chunked (point formats 6-10)."""
    chunk_size: int
    """Points per chunk; ``0xFFFFFFFF`` for chunks of variable size (COPC files)."""
    items: tuple[tuple[int, int, int], ...]
    """(type, size, version) of each compressed item; the sizes add up to the record length."""
    record: bytes
    """The VLR's data, as ``lazrs.LazVlr`` takes it."""
    chunk_table_offset: int
    """Byte offset of the chunk table; -1 when the file has none (pointwise compression)."""
    chunks: tuple[tuple[int, int], ...]
    """(points, bytes) of each chunk, in file order (empty without a chunk table)."""

    @property
    def variable_chunks(self) -> bool:
        return self.chunk_size == _VARIABLE_CHUNKS


@dataclass(frozen=True)
class LasHeaderInfo:
    """What a LAS/LAZ header says, every field checked against the file (:func:`check_las_header`)."""

    path: Path
    file_size: int
    version: tuple[int, int]
    header_size: int
    offset_to_point_data: int
    point_format: int
    """The point format without the compression bits (0-10)."""
    compressed: bool
    record_length: int
    """Bytes per point record, uncompressed (standard fields plus extra bytes)."""
    point_count: int
    scales: tuple[float, float, float]
    offsets: tuple[float, float, float]
    mins: tuple[float, float, float]
    maxs: tuple[float, float, float]
    vlrs: tuple[VlrInfo, ...]
    evlrs: tuple[VlrInfo, ...]
    start_of_first_evlr: int
    laszip: LaszipInfo | None
    """The laszip VLR and chunk table when ``compressed``."""

    @property
    def point_data(self) -> tuple[int, int]:
        """``(start, stop)`` byte range of the point data (a LAZ file's: its chunks, without the table)."""
        if self.laszip is None:
            return self.offset_to_point_data, self.offset_to_point_data + self.point_count * self.record_length
        start = self.offset_to_point_data + (8 if self.laszip.chunk_table_offset >= 0 else 0)
        return start, start + sum(size for _, size in self.laszip.chunks)


def _fail(path: Path, text: str):
    raise LoadError(f"{path}: {text}")


def check_las_header(path) -> LasHeaderInfo:
    """Check a LAS or LAZ file's header, VLRs, EVLRs and (LAZ) chunk table against the file.

    Parameters
    ----------
    path : str or Path
        The file; its suffix does not matter (the point format's compression bit says LAZ).

    Returns
    -------
    LasHeaderInfo
        The header's fields, the VLRs and EVLRs, and the laszip VLR with its chunks for LAZ.

    Raises
    ------
    LoadError
        One line naming the file and the field whose promise the file cannot hold, e.g.
        ``x.las: LAS header's number of VLRs (1819042147) needs 98228275938 bytes of VLR headers
        before the point data at byte 1936876918; the file has 400 bytes``.
    """
    path = Path(path)
    size = path.stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(_MIN_HEADER_SIZE[0])
        if head[:4] != b"LASF":
            kind = "LAZ" if path.suffix.lower() == ".laz" else "LAS"
            _fail(path, f"not a readable {kind} file (it does not start with the signature LASF)")
        if len(head) < _MIN_HEADER_SIZE[0]:
            _fail(path, f"LAS header ends at byte {len(head)}; a header takes at least {_MIN_HEADER_SIZE[0]} bytes")
        major, minor = head[24], head[25]
        if major != 1 or minor not in _MIN_HEADER_SIZE:
            _fail(path, f"LAS version {major}.{minor} is not one of 1.0-1.5")
        header_size, offset, n_vlrs, fmt_id, record_length, legacy_count = struct.unpack_from("<HIIBHI", head, 94)
        least = _MIN_HEADER_SIZE[minor]
        if header_size < least:
            _fail(path, f"LAS header size {header_size} is below the {least} bytes of a version 1.{minor} header")
        if header_size > size:
            _fail(path, f"LAS header size {header_size} is beyond the end of the file ({size} bytes)")
        fh.seek(0)
        head = fh.read(header_size)
        if offset < header_size or offset > size:
            _fail(path, f"LAS offset to point data {offset} is not between the header's end ({header_size}) "
                        f"and the end of the file ({size} bytes)")
        scales = struct.unpack_from("<3d", head, 131)
        offsets = struct.unpack_from("<3d", head, 155)
        bounds = struct.unpack_from("<6d", head, 179)
        start_evlr, n_evlrs, point_count = 0, 0, legacy_count
        if minor >= 4:
            start_evlr, n_evlrs, point_count = struct.unpack_from("<QIQ", head, 235)
        compressed = bool(fmt_id & 0x80) and not fmt_id & 0x40  # laspy's rule
        point_format = fmt_id & 0x3F
        if point_format not in POINT_RECORD_SIZES:
            _fail(path, f"LAS point data format {point_format} is not one of 0-10")
        if record_length < POINT_RECORD_SIZES[point_format]:
            _fail(path, f"LAS point data record length {record_length} is below the "
                        f"{POINT_RECORD_SIZES[point_format]} bytes of point format {point_format}")
        for axis, scale, shift in zip("xyz", scales, offsets):
            if not (math.isfinite(scale) and scale != 0.0):
                _fail(path, f"LAS {axis} scale factor {scale!r} is not a finite non-zero number")
            if not math.isfinite(shift):
                _fail(path, f"LAS {axis} offset {shift!r} is not a finite number")
        vlrs = _walk_records(path, fh, header_size, n_vlrs, offset, size, extended=False)
        evlrs: tuple[VlrInfo, ...] = ()
        data_end = size
        if minor >= 4 and n_evlrs:
            if start_evlr < offset or start_evlr > size:
                _fail(path, f"LAS start of first EVLR {start_evlr} is not between the point data at byte "
                            f"{offset} and the end of the file ({size} bytes)")
            evlrs = _walk_records(path, fh, start_evlr, n_evlrs, size, size, extended=True)
            data_end = start_evlr
        laszip = None
        if compressed:
            laszip = _check_laszip(path, fh, vlrs, record_length, point_count, offset, data_end, size)
        elif offset + point_count * record_length > data_end:
            where = "the first EVLR" if data_end < size else "the end of the file"
            _fail(path, f"LAS point count {point_count} x record length {record_length} needs "
                        f"{point_count * record_length} bytes from the point data at byte {offset}; "
                        f"{where} is at byte {data_end}")
    return LasHeaderInfo(path=path, file_size=size, version=(major, minor), header_size=header_size,
                         offset_to_point_data=offset, point_format=point_format, compressed=compressed,
                         record_length=record_length, point_count=point_count, scales=scales, offsets=offsets,
                         mins=bounds[1::2], maxs=bounds[0::2], vlrs=vlrs, evlrs=evlrs,
                         start_of_first_evlr=start_evlr, laszip=laszip)


def _walk_records(path: Path, fh, start: int, count: int, stop: int, size: int, *, extended: bool
                  ) -> tuple[VlrInfo, ...]:
    """The ``count`` (E)VLRs from byte ``start``, each header and record inside ``[start, stop)``."""
    kind, head = ("EVLR", _EVLR_HEADER) if extended else ("VLR", _VLR_HEADER)
    if start + count * head > stop:
        where = "the end of the file" if stop == size else "the point data"
        _fail(path, f"LAS header's number of {kind}s ({count}) needs {count * head} bytes of {kind} headers "
                    f"from byte {start}; {where} is at byte {stop}")
    records, at = [], start
    for index in range(count):  # at most (stop - start) / head records, checked above
        fh.seek(at)
        raw = fh.read(head)
        if len(raw) < head or at + head > stop:
            _fail(path, f"LAS {kind} {index} header at byte {at} runs past byte {stop}")
        user = raw[2:18].split(b"\0", 1)[0]
        record_id = struct.unpack_from("<H", raw, 18)[0]
        length = struct.unpack_from("<Q" if extended else "<H", raw, 20)[0]
        if at + head + length > stop:
            _fail(path, f"LAS {kind} {index} ({user.decode('ascii', 'replace')!r}) record length {length} "
                        f"runs past byte {stop}")
        records.append(VlrInfo(user.decode("ascii", "replace"), record_id, at + head, length))
        at += head + length
    return tuple(records)


def _check_laszip(path: Path, fh, vlrs, record_length: int, point_count: int, offset: int, data_end: int,
                  size: int) -> LaszipInfo:
    """The laszip VLR and the chunk table of a LAZ file, checked against the point count and the file."""
    found = [v for v in vlrs if v.user_id.encode() == _LASZIP_USER and v.record_id == _LASZIP_RECORD]
    if not found:
        _fail(path, "LAZ point format (compression bit set) but no laszip VLR")
    vlr = found[0]
    fh.seek(vlr.data_offset)
    record = fh.read(vlr.length)
    if len(record) < 34:
        _fail(path, f"laszip VLR holds {len(record)} bytes; it takes at least 34")
    compressor, _coder, _major, _minor, _rev, _options, chunk_size, _n_special, _special, n_items = \
        struct.unpack_from("<HHBBHIIqqH", record, 0)
    if len(record) != 34 + 6 * n_items:
        _fail(path, f"laszip VLR's number of items ({n_items}) needs {34 + 6 * n_items} bytes; it holds {len(record)}")
    items = tuple(struct.unpack_from("<HHH", record, 34 + 6 * i) for i in range(n_items))
    if sum(item[1] for item in items) != record_length:
        _fail(path, f"laszip VLR's item sizes add up to {sum(item[1] for item in items)} bytes, the LAS point "
                    f"data record length is {record_length}")
    if compressor not in (1, 2, 3):
        _fail(path, f"laszip VLR's compressor {compressor} is not one of 1-3")
    if chunk_size == 0:
        _fail(path, "laszip VLR's chunk size is 0")
    if compressor == 1:  # pointwise: no chunks, no chunk table
        packed = data_end - offset
        if point_count > LAZ_MAX_POINTS_PER_BYTE * packed:
            _fail(path, f"LAS point count {point_count} in {packed} compressed bytes is more than "
                        f"{LAZ_MAX_POINTS_PER_BYTE} points per byte")
        return LaszipInfo(compressor, chunk_size, items, record, -1, ())
    table, chunks = _read_chunk_table(path, fh, record, offset, data_end, size)
    packed = table - offset - 8
    if sum(b for _, b in chunks) > packed:
        _fail(path, f"LAZ chunk table's chunk sizes add up to {sum(b for _, b in chunks)} bytes; "
                    f"the compressed points hold {packed}")
    if chunk_size != _VARIABLE_CHUNKS:
        chunks = tuple((min(chunk_size, max(point_count - i * chunk_size, 0)), b) for i, (_, b) in enumerate(chunks))
        capacity = len(chunks) * chunk_size
        if point_count > capacity or (chunks and point_count <= capacity - chunk_size):
            _fail(path, f"LAS point count {point_count} does not fill the LAZ chunk table's {len(chunks)} "
                        f"chunks of {chunk_size} points")
    elif sum(p for p, _ in chunks) != point_count:
        _fail(path, f"LAS point count {point_count} differs from the {sum(p for p, _ in chunks)} points "
                    f"of the LAZ chunk table")
    for index, (points, nbytes) in enumerate(chunks):
        # a decompressor allocates a fixed-size chunk's whole size, even for the last, partial one
        allotted = points if chunk_size == _VARIABLE_CHUNKS else chunk_size
        if allotted > LAZ_MAX_POINTS_PER_BYTE * nbytes:
            if chunk_size == _VARIABLE_CHUNKS:
                _fail(path, f"LAZ chunk {index} holds {points} points in {nbytes} bytes, more than "
                            f"{LAZ_MAX_POINTS_PER_BYTE} points per byte")
            _fail(path, f"laszip VLR's chunk size {chunk_size} is more than {LAZ_MAX_POINTS_PER_BYTE} points per "
                        f"byte of LAZ chunk {index} ({nbytes} bytes)")
    if compressor == 3:
        _check_layers(path, fh, items, record_length, offset + 8, chunks)
    return LaszipInfo(compressor, chunk_size, items, record, table, chunks)


_LAYERS = {10: 9, 11: 1, 12: 2, 13: 1}
"""Layers of each layered (v3) laszip item in a chunk: a point's 9, RGB 1, RGB and NIR 2, a wave packet 1
(an extra bytes item, type 14, has one layer per byte)."""


def _check_layers(path: Path, fh, items, record_length: int, start: int, chunks) -> None:
    """Each layered chunk's own header: its point count and layer sizes against the chunk's bytes.

    A chunk opens with its first point (raw), its point count and the byte size of every layer;
    a decompressor allocates each layer's size before it reads it.
    """
    layers = sum(size if kind == 14 else _LAYERS.get(kind, 0) for kind, size, _ in items)
    head = record_length + 4 + 4 * layers
    at = start
    for index, (points, nbytes) in enumerate(chunks):
        if points:
            if head > nbytes:
                _fail(path, f"LAZ chunk {index} of {nbytes} bytes cannot hold its first point, point count and "
                            f"{layers} layer sizes ({head} bytes)")
            fh.seek(at + record_length)
            count, *sizes = struct.unpack(f"<{1 + layers}I", fh.read(4 + 4 * layers))
            if count != points:
                _fail(path, f"LAZ chunk {index} says it holds {count} points; the chunk table and point count "
                            f"give it {points}")
            if head + sum(sizes) > nbytes:
                _fail(path, f"LAZ chunk {index}'s layer sizes add up to {sum(sizes)} bytes; the chunk holds "
                            f"{nbytes - head} after its first point and layer sizes")
        at += nbytes


def _read_chunk_table(path: Path, fh, record: bytes, offset: int, data_end: int, size: int
                      ) -> tuple[int, tuple[tuple[int, int], ...]]:
    """(offset of the chunk table, its (points, bytes) entries); each chunk takes a byte at least."""
    fh.seek(offset)
    raw = fh.read(8)
    if len(raw) < 8:
        _fail(path, f"LAZ point data at byte {offset} has no chunk table offset")
    table = struct.unpack("<q", raw)[0]
    if table == -1:  # written at the end of the file by a writer that could not seek back
        fh.seek(size - 8)
        table = struct.unpack("<q", fh.read(8))[0]
        data_end = min(data_end, size - 8)
    if table < offset + 8 or table + 8 > data_end:
        _fail(path, f"LAZ chunk table offset {table} is not between the point data at byte {offset + 8} "
                    f"and byte {data_end - 8}")
    fh.seek(table)
    version, n_chunks = struct.unpack("<II", fh.read(8))
    if version != 0:
        _fail(path, f"LAZ chunk table version {version} is not 0")
    if n_chunks > table - offset - 8:
        _fail(path, f"LAZ chunk table's number of chunks ({n_chunks}) is more than the "
                    f"{table - offset - 8} bytes of compressed points could hold")
    if n_chunks == 0:
        return table, ()
    try:
        import lazrs
    except ImportError:  # laspy then says LAZ needs a backend
        return table, ()
    fh.seek(table)
    stream = io.BytesIO(fh.read(data_end - table))
    try:
        entries = lazrs.read_chunk_table_only(stream, lazrs.LazVlr(record))
    except BaseException as exc:  # lazrs's errors, and a Rust panic (a BaseException), in one line
        if not isinstance(exc, Exception) and not is_panic(exc):
            raise
        _fail(path, f"LAZ chunk table is unreadable ({one_line(exc)})")
    if len(entries) != n_chunks:
        _fail(path, f"LAZ chunk table holds {len(entries)} chunks, its header says {n_chunks}")
    return table, tuple((int(p), int(b)) for p, b in entries)
