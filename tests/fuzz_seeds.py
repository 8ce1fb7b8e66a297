"""Valid small files of every format curv reads, and the seeded mutations the reader fuzzer makes of them.

:func:`seed_files` makes one or more valid small files of every format ``curv.load`` reads (PLY
ascii and binary, meshes and clouds; OBJ; OFF; STL ascii and binary; glTF and GLB; XYZ, TXT, CSV;
PCD ascii, binary and binary_compressed; PTS, Leica and Expe; LAS and LAZ), each with the byte
where its header ends and the offsets of its binary header's numbers; :func:`real_las_seeds` adds
laspy's sample files. :func:`make_case` mutates one of them, from a seeded random stream:
truncation in every region (inside the header, at its end, inside the body, the last byte), bytes
of the header flipped, a header number replaced by 0, 1, 2^31, 2^40 or a negative value, trailing
garbage, a valid header with a foreign body, bytes of the body flipped. :mod:`tests.fuzzing` reads
the cases.
"""

from __future__ import annotations

import io
import json
import os
import re
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

NUMBERS = (0, 1, 2**31, 2**40, -1, -2**31, -2**40)
"""What a header number is replaced by."""

MUTATIONS = ("truncate", "header_flip", "header_number", "header_number", "trailing_garbage",
             "foreign_body", "body_flip")
"""Mutation kinds, drawn uniformly (header numbers twice as often: they make the runaway promises)."""


@dataclass
class Seed:
    """A valid file to mutate."""

    name: str
    format: str
    """The format's label in the report (``"PLY binary"``, ``"LAZ"``, ...)."""
    suffix: str
    data: bytes
    header_end: int
    """Bytes up to the end of the header (the whole file for a format that is all header)."""
    fields: list[tuple[int, str]] = field(default_factory=list)
    """(offset, struct code) of the binary header's numbers (``"<I"``, ``"<Q"``, ``"<d"``, ...)."""
    text_header: bool = True
    """Whether the header is text whose integers are numbers to replace."""


# --- seeds --------------------------------------------------------------------------------------

def _sphere():
    import trimesh

    s = trimesh.creation.icosphere(2, radius=1.5)
    return np.asarray(s.vertices), np.asarray(s.faces), s


def _cloud(n=200, seed=3):
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    normals = p / np.linalg.norm(p, axis=1)[:, None]
    return (2.0 * normals).astype(np.float32).astype(np.float64), normals.astype(np.float32).astype(np.float64)


def _end_of(data: bytes, marker: bytes) -> int:
    at = data.index(marker) + len(marker)
    return data.index(b"\n", at) + 1


def _ply_seeds() -> list[Seed]:
    from plyfile import PlyData, PlyElement

    vertices, faces, _ = _sphere()
    vert = np.array([tuple(v) for v in vertices], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    face = np.array([(f,) for f in faces.tolist()], dtype=[("vertex_indices", "i4", (3,))])
    points, normals = _cloud()
    cloud = np.empty(len(points), dtype=[(c, "f4") for c in ("x", "y", "z", "nx", "ny", "nz")])
    for i, c in enumerate("xyz"):
        cloud[c], cloud[f"n{c}"] = points[:, i], normals[:, i]
    seeds = []
    for text in (True, False):
        label = "PLY ascii" if text else "PLY binary"
        for name, elements in (("mesh", [PlyElement.describe(vert, "vertex"), PlyElement.describe(face, "face")]),
                               ("cloud", [PlyElement.describe(cloud, "vertex")])):
            buffer = io.BytesIO()
            PlyData(elements, text=text).write(buffer)
            data = buffer.getvalue()
            seeds.append(Seed(f"{label} {name}", label, ".ply", data, _end_of(data, b"end_header")))
    return seeds


def _text_mesh_seeds() -> list[Seed]:
    vertices, faces, mesh = _sphere()
    obj = "".join(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in vertices)
    obj += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)
    off = f"OFF\n{len(vertices)} {len(faces)} 0\n" + "".join(f"{x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in vertices)
    off += "".join(f"3 {a} {b} {c}\n" for a, b, c in faces)
    ascii_stl = mesh.export(file_type="stl_ascii")
    ascii_stl = ascii_stl.encode() if isinstance(ascii_stl, str) else ascii_stl
    binary_stl = mesh.export(file_type="stl")
    off = off.encode()
    return [Seed("OBJ", "OBJ", ".obj", obj.encode(), len(obj) // 8),  # OBJ has no header: its first lines
            Seed("OFF", "OFF", ".off", off, off.index(b"\n", 4) + 1),
            Seed("STL ascii", "STL ascii", ".stl", ascii_stl, ascii_stl.index(b"\n", ascii_stl.index(b"facet")) + 1),
            Seed("STL binary", "STL binary", ".stl", binary_stl, 84, fields=[(80, "<I")], text_header=False)]


def _gltf_seeds() -> list[Seed]:
    import trimesh
    from trimesh.exchange import gltf

    _, _, mesh = _sphere()
    doc = json.loads(gltf.export_gltf(trimesh.Scene(mesh), embed_buffers=True)["model.gltf"])
    doc["buffers"] = doc.pop("buffers")  # the data URI last: every number before it is the header's
    text = json.dumps(doc).encode()
    glb = mesh.export(file_type="glb")
    json_length = struct.unpack_from("<I", glb, 12)[0]
    bin_at = 20 + json_length
    return [Seed("glTF", "glTF", ".gltf", text, text.index(b'"buffers"')),  # the numbers before the data URI
            Seed("GLB", "GLB", ".glb", glb, bin_at + 8,
                 fields=[(8, "<I"), (12, "<I"), (bin_at, "<I")])]


def _point_text_seeds() -> list[Seed]:
    points, normals = _cloud()
    table = np.hstack([points, normals])
    plain = "".join(" ".join(f"{v:.9g}" for v in row) + "\n" for row in table)
    header = "x y z nx ny nz\n" + plain
    comma = "x,y,z\n" + "".join(",".join(f"{v:.9g}" for v in row[:3]) + "\n" for row in table)
    return [Seed("XYZ", "XYZ", ".xyz", plain.encode(), len(plain) // 8),
            Seed("TXT", "TXT", ".txt", header.encode(), len(header) // 8),
            Seed("CSV", "CSV", ".csv", comma.encode(), len(comma) // 8)]


def _pcd_seeds() -> list[Seed]:
    from tests.test_points_io import _pcd

    points, normals = _cloud()
    seeds = []
    for kind, label in (("ascii", "PCD ascii"), ("binary", "PCD binary"), ("binary_compressed", "PCD compressed")):
        folder = Path(os.environ.get("TMPDIR", "/tmp"))
        path = folder / f".curv-fuzz-seed-{os.getpid()}.pcd"
        try:
            data = _pcd(path, points, normals, kind).read_bytes()
        finally:
            path.unlink(missing_ok=True)
        end = _end_of(data, b"\nDATA")
        fields = [(end, "<I"), (end + 4, "<I")] if kind == "binary_compressed" else []
        seeds.append(Seed(label, label, ".pcd", data, end + (8 if fields else 0), fields=fields))
    return seeds


def _pts_seeds() -> list[Seed]:
    points, normals = _cloud()
    rng = np.random.default_rng(5)
    intensity = rng.integers(-2048, 2048, len(points))
    colours = rng.integers(0, 256, (len(points), 3))
    leica = f"{len(points)}\n" + "".join(f"{x:.6f} {y:.6f} {z:.6f} {i} {r} {g} {b}\n" for (x, y, z), i, (r, g, b)
                                         in zip(points, intensity, colours))
    record = np.zeros(len(points), dtype=[("p", "<f4", 3), ("r", "<f4"), ("n", "<f4", 3), ("c", "u1", 4)])
    record["p"], record["r"], record["n"], record["c"] = points, 0.01, normals, 255
    head = (f"[Expe/PointSet/Binary/0.1]\nproperty position 12\nproperty radius 4\nproperty normal 12\n"
            f"property color 4\nnofpoints {len(points)}\ndata\n").encode()
    ascii_head = (f"[Expe/PointSet/Ascii/0.2]\nproperty position 3 r32\nproperty normal 3 r32\n"
                  f"nofpoints {len(points)}\ndata\n")
    ascii_rows = "".join(f"{p[0]:.6f},{p[1]:.6f},{p[2]:.6f} ; {n[0]:.6f},{n[1]:.6f},{n[2]:.6f}\n"
                         for p, n in zip(points, normals))
    return [Seed("PTS Leica", "PTS Leica", ".pts", leica.encode(), leica.index("\n") + 1),
            Seed("PTS Expe binary", "PTS Expe", ".pts", head + record.tobytes(), len(head)),
            Seed("PTS Expe ascii", "PTS Expe", ".pts", (ascii_head + ascii_rows).encode(), len(ascii_head))]


def _las_fields(data: bytes) -> tuple[int, list[tuple[int, str]]]:
    """(end of the header region, the numbers of a LAS/LAZ header, its VLRs' lengths and the chunk table)."""
    header_size, offset, n_vlrs, fmt_id = struct.unpack_from("<HIIB", data, 94)
    fields = [(94, "<H"), (96, "<I"), (100, "<I"), (104, "<B"), (105, "<H"), (107, "<I"), (131, "<d"), (155, "<d")]
    if data[25] >= 4:
        fields += [(235, "<Q"), (243, "<I"), (247, "<Q")]
    at = header_size
    for _ in range(n_vlrs):
        fields.append((at + 20, "<H"))
        user = data[at + 2:at + 18].split(b"\0")[0]
        length = struct.unpack_from("<H", data, at + 20)[0]
        if user == b"laszip encoded":
            fields += [(at + 54 + 12, "<I"), (at + 54 + 32, "<H"), (at + 54 + 36, "<H")]  # chunk size, items
        at += 54 + length
    end = offset
    if fmt_id & 0x80:
        table = struct.unpack_from("<q", data, offset)[0]
        fields += [(offset, "<q"), (table + 4, "<I")]
        end = offset + 8
    return end, fields


def _las_seeds() -> list[Seed]:
    import laspy

    points, normals = _cloud()
    seeds = []
    for name, suffix, version, fmt, extra in (("LAS 1.2", ".las", "1.2", 3, False),
                                               ("LAS 1.4 normals", ".las", "1.4", 6, True),
                                               ("LAZ 1.2", ".laz", "1.2", 3, False),
                                               ("LAZ 1.4 normals", ".laz", "1.4", 7, True)):
        header = laspy.LasHeader(point_format=fmt, version=version)
        header.scales = np.array([1e-4, 1e-4, 1e-4])
        header.offsets = np.zeros(3)
        if extra:
            header.add_extra_dims([laspy.ExtraBytesParams(name=c, type=np.float32) for c in ("nx", "ny", "nz")])
        las = laspy.LasData(header)
        las.x, las.y, las.z = points.T
        if extra:
            las.nx, las.ny, las.nz = normals.T
        buffer = io.BytesIO()
        las.write(buffer, do_compress=suffix == ".laz")
        data = buffer.getvalue()
        end, fields = _las_fields(data)
        seeds.append(Seed(name, suffix.lstrip(".").upper(), suffix, data, end, fields=fields, text_header=False))
    return seeds + _curvlab_las_seeds(seeds)


def _curvlab_las_seeds(las_seeds: list[Seed]) -> list[Seed]:
    """What curvlab's LAS/LAZ writer makes of the 1.2 and 1.4 seeds: their records with the curvature
    as extra bytes (:mod:`curv.formats.laswrite`), read back as any LAS file is."""
    import tempfile

    from curv.formats.laswrite import GROUPS, write_las

    def values(start, stop):
        m = stop - start
        i = np.arange(start, stop, dtype=np.float64)
        return {"k1": i, "k2": -i, "d1": np.tile([1.0, 0, 0], (m, 1)), "d2": np.tile([0, 1.0, 0], (m, 1)),
                "normals": np.tile([0, 0, 1.0], (m, 1)), "valid": np.ones(m, bool), "reason": np.zeros(m, np.uint8),
                "k1_se": i, "k2_se": i}

    out = []
    with tempfile.TemporaryDirectory() as folder:
        for seed in las_seeds:
            if seed.name not in ("LAS 1.2", "LAZ 1.4 normals"):
                continue
            source = Path(folder) / f"in{seed.suffix}"
            source.write_bytes(seed.data)
            written = Path(folder) / f"out{seed.suffix}"
            write_las(written, source, values, groups=GROUPS)
            data = written.read_bytes()
            end, fields = _las_fields(data)
            out.append(Seed(f"{seed.name} written by curvlab", seed.format, seed.suffix, data, end, fields=fields,
                            text_header=False))
    return out


def real_las_seeds(folder) -> list[Seed]:
    """laspy's own sample files (real aerial LiDAR) under ``folder``, as seeds, the small ones (<= 100 kB)."""
    seeds = []
    for path in sorted(Path(folder).glob("*.la[sz]")):
        data = path.read_bytes()
        if len(data) > 100_000:
            continue
        end, fields = _las_fields(data)
        seeds.append(Seed(f"laspy {path.name}", f"{path.suffix.lstrip('.').upper()} (laspy samples)",
                          path.suffix.lower(), data, end, fields=fields, text_header=False))
    return seeds


def seed_files() -> list[Seed]:
    """One or more valid small files of every format curv reads."""
    return (_ply_seeds() + _text_mesh_seeds() + _gltf_seeds() + _point_text_seeds() + _pcd_seeds()
            + _pts_seeds() + _las_seeds())


# --- mutations ----------------------------------------------------------------------------------

def _encode(value, code: str) -> bytes:
    """``value`` in a binary field: negatives in two's complement, too large saturated, floats as they are."""
    if code[-1] in "fd":
        return struct.pack(code, float(value))
    bits = struct.calcsize(code) * 8
    signed = code[-1].islower()
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
    if not signed and value < 0:
        value &= hi
    return struct.pack(code, min(max(value, lo), hi))


def _mutate(seed: Seed, kind: str, rng: np.random.Generator, seeds: list[Seed]) -> tuple[bytes, str]:
    data, end = bytearray(seed.data), min(seed.header_end, len(seed.data))
    if kind == "truncate":
        regions = [(1, max(end, 2)), (end, end + 1), (end + 1, max(len(data), end + 2)), (len(data) - 1, len(data))]
        lo, hi = regions[rng.integers(len(regions))]
        at = int(rng.integers(lo, max(hi, lo + 1)))
        return bytes(data[:max(at, 1)]), f"truncate at {at} of {len(data)}"
    if kind == "header_flip":
        spots = rng.integers(0, max(end, 1), size=int(rng.integers(1, 5)))
        for at in spots:
            data[at] ^= int(rng.integers(1, 256))
        return bytes(data), f"flip header bytes {sorted(int(s) for s in spots)}"
    if kind == "header_number":
        value = int(NUMBERS[rng.integers(len(NUMBERS))])
        texts = [m for m in re.finditer(rb"\d+", bytes(data[:end]))] if seed.text_header else []
        choices = len(texts) + len(seed.fields)
        if choices == 0:
            return _mutate(seed, "header_flip", rng, seeds)
        pick = int(rng.integers(choices))
        if pick < len(texts):
            m = texts[pick]
            return bytes(data[:m.start()]) + str(value).encode() + bytes(data[m.end():]), \
                f"header number at {m.start()} ({m.group().decode()}) -> {value}"
        offset, code = seed.fields[pick - len(texts)]
        if offset + struct.calcsize(code) > len(data):
            return bytes(data), "no change (field beyond the file)"
        data[offset:offset + struct.calcsize(code)] = _encode(value, code)
        return bytes(data), f"header field {code} at {offset} -> {value}"
    if kind == "trailing_garbage":
        size = int(rng.integers(1, 512))
        junk = rng.integers(0, 256, size, dtype=np.uint8).tobytes() if rng.random() < 0.5 else \
            " ".join(str(int(v)) for v in rng.integers(-10**6, 10**6, size // 4 + 1)).encode() + b"\n"
        return bytes(data) + junk, f"{len(junk)} bytes of trailing garbage"
    if kind == "foreign_body":
        other = seeds[int(rng.integers(len(seeds)))]
        if rng.random() < 0.5 and other is not seed:
            body, what = other.data[other.header_end:], f"the body of {other.name}"
        else:
            size = int(rng.integers(0, 2 * max(len(data) - end, 16)))
            body, what = rng.integers(0, 256, size, dtype=np.uint8).tobytes(), f"{size} random bytes"
        return bytes(data[:end]) + body, f"header with {what}"
    if kind == "body_flip":
        if len(data) <= end:
            return _mutate(seed, "header_flip", rng, seeds)
        spots = rng.integers(end, len(data), size=int(rng.integers(1, 9)))
        for at in spots:
            data[at] ^= int(rng.integers(1, 256))
        return bytes(data), f"flip {len(spots)} body bytes"
    raise ValueError(kind)


@dataclass
class Case:
    index: int
    seed: Seed
    mutation: str
    data: bytes


def make_case(index: int, seeds: list[Seed], master_seed: int = 0) -> Case:
    """Case ``index``: seed ``index % len(seeds)`` mutated by a stream seeded with (master_seed, index)."""
    rng = np.random.default_rng([master_seed, index])
    seed = seeds[index % len(seeds)]
    kind = MUTATIONS[int(rng.integers(len(MUTATIONS)))]
    data, what = _mutate(seed, kind, rng, seeds)
    return Case(index, seed, f"{kind}: {what}", data)
