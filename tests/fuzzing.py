"""A seeded fuzzer of curv's readers: valid small files of every format, mutated, read in a watched worker.

:func:`seed_files` makes one or more valid small files of every format ``curv.load`` reads (PLY
ascii and binary, meshes and clouds; OBJ; OFF; STL ascii and binary; glTF and GLB; XYZ, TXT, CSV;
PCD ascii, binary and binary_compressed; PTS, Leica and Expe; LAS and LAZ), each with the byte
where its header ends and the offsets of its binary header's numbers. :func:`make_case` mutates
one of them, from a seeded random stream: truncation in every region (inside the header, at its
end, inside the body, the last byte), bytes of the header flipped, a header number replaced by 0,
1, 2^31, 2^40 or a negative value, trailing garbage, a valid header with a foreign body, bytes of
the body flipped.

:func:`run_cases` reads every case in a worker process (``python -m tests.fuzzing --worker``) with
a watchdog that only *detects* a hang (the bound is generous: 30 s plus a second per 100 kB; the
readers are bounded by construction, not by this timeout); the worker runs under a 4 GiB address
space limit, so that an allocation a header made run away surfaces as a failure instead of
swapping the machine. A case must end in a result (finite coordinates, faces in range; with
``estimate``, curvature finite where valid and NaN where not) or a :class:`curv.core.errors.CurvError`
whose message is one line naming the file; with ``cli``, ``curv estimate FILE -o out.ply`` on a
file that does not load must exit 2 with one line, and leave no file in the folder.

The estimate is optional: on a fuzzed cloud with one point moved 2^31 away, ``qs`` took about 100 s
for 200 points (the neighbour search scales with the bounding box), which is the estimators'
matter, not the readers'.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import select
import struct
import subprocess
import sys
import time
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

NUMBERS = (0, 1, 2**31, 2**40, -1, -2**31, -2**40)
"""What a header number is replaced by."""

MUTATIONS = ("truncate", "header_flip", "header_number", "header_number", "trailing_garbage",
             "foreign_body", "body_flip")
"""Mutation kinds, drawn uniformly (header numbers twice as often: they make the runaway promises)."""

WATCHDOG_S = 30.0
WATCHDOG_S_PER_BYTE = 1e-5
MEMORY_LIMIT = 4 << 30
ROOT = Path(__file__).resolve().parents[1]


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
    return seeds


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


# --- the worker: one process reads case after case ---------------------------------------------

def _one_line_error(message: str, path: Path) -> str | None:
    """Why ``message`` is not a proper one-line error naming ``path``; None when it is."""
    if "\n" in message or "\r" in message:
        return "the message has more than one line"
    if str(path) not in message:
        return "the message does not name the file"
    if "not enough memory" in message:
        return "ran out of memory: an allocation was not bounded by the file"
    return None


def _check_result(obj, estimate: bool) -> str | None:
    import curv

    vertices = np.asarray(obj.vertices)
    if not np.isfinite(vertices).all():
        return "a coordinate is not finite"
    if isinstance(obj, curv.Mesh):
        if obj.face_indices.size and (obj.face_indices.min() < 0 or obj.face_indices.max() >= obj.n_vertices):
            return "a face index is out of range"
    elif obj.normals is not None and obj.normals.shape != vertices.shape:
        return "normals of the wrong shape"
    if estimate:
        try:
            res = curv.estimate(obj, "qs", 2)
        except curv.CurvError as exc:
            return "the estimate's error has more than one line" if "\n" in str(exc) else None
        values = np.column_stack([res.k1, res.k2])
        if not np.isfinite(values[res.valid]).all():
            return "a valid point's curvature is not finite"
        if not np.isnan(values[~res.valid]).all():
            return "an invalid point's curvature is not NaN"
    return None


def _run_cli(path: Path) -> str | None:
    """``curv estimate PATH -m qs -o out.ply`` on a file that does not load: exit 2, one line, no file."""
    from curv.cli import main

    out = path.parent / f"{path.stem}-out.ply"
    before = set(path.parent.iterdir())
    err, stdout = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(stdout):
        try:
            code = main(["estimate", str(path), "-m", "qs", "-r", "2", "-o", str(out), "-q"])
        except SystemExit as exc:  # argparse
            code = exc.code
    lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
    left = set(path.parent.iterdir()) - before - {out}
    try:
        if left:
            return f"the CLI left {sorted(p.name for p in left)}"
        if code != 2:
            return f"the CLI exited {code}: {' | '.join(lines)[:300]}"
        if out.exists():
            return "the CLI failed but left an output file"
        if len(lines) != 1 or "Traceback" in err.getvalue():
            return f"the CLI's error is {len(lines)} lines: {' | '.join(lines)[:300]}"
        return None
    finally:
        out.unlink(missing_ok=True)


def check_file(path: Path, *, estimate: bool = False, cli: bool = False) -> dict:
    """Read ``path`` with ``curv.load`` (and optionally estimate, run the CLI); the outcome as a dict."""
    import curv

    t0 = time.perf_counter()
    outcome, detail = "result", ""
    try:
        obj = curv.load(path)
    except curv.CurvError as exc:
        outcome, detail = "error", str(exc)
        problem = _one_line_error(detail, path)
        if problem:
            outcome, detail = "failure", f"{problem}: {detail[:300]!r}"
    except BaseException as exc:  # noqa: BLE001 - the fuzzer's job is to catch these
        if isinstance(exc, KeyboardInterrupt):
            raise
        outcome, detail = "failure", f"traceback: {type(exc).__name__}: {' '.join(str(exc).split())[:300]}"
    else:
        problem = _check_result(obj, estimate)
        if problem:
            outcome, detail = "failure", problem
        else:
            detail = f"{type(obj).__name__} of {obj.n_vertices} points"
    if cli and outcome == "error":  # the CLI on a file that does not load: exit 2, one line, no file left
        problem = _run_cli(path)
        if problem:
            outcome, detail = "failure", problem
    return {"outcome": outcome, "detail": detail, "seconds": time.perf_counter() - t0}


def _worker() -> None:
    """Read JSON requests from stdin, answer each with a JSON line on stdout."""
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # a crash is reported at once, without a core dump
    import tempfile

    import curv  # noqa: F401 - imported once, before the first case

    if "--warm" in sys.argv:  # compile the kernels the estimates run, before the watchdog starts
        with tempfile.TemporaryDirectory(prefix="curv-fuzz-warm-") as folder:
            for seed in seed_files():
                if seed.name in ("PLY binary mesh", "PLY binary cloud"):
                    path = Path(folder) / f"warm{seed.suffix}"
                    path.write_bytes(seed.data)
                    check_file(path, estimate=True)
    out = sys.stdout
    sys.stdout = sys.stderr  # whatever a library prints stays off the answer channel
    out.write(json.dumps({"ready": True}) + "\n")
    out.flush()
    for line in sys.stdin:
        request = json.loads(line)
        answer = check_file(Path(request["path"]), estimate=request["estimate"], cli=request["cli"])
        out.write(json.dumps(answer) + "\n")
        out.flush()


class Worker:
    """A worker process and its answer channel; restarted after a hang or a crash."""

    def __init__(self, warm: bool = False):
        self.proc = None
        self.warm = warm

    def start(self, timeout: float = 1800.0) -> None:
        """Start the worker; a warm one first compiles what the estimates need (minutes after an edit)."""
        env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        flags = ["--worker"] + (["--warm"] if self.warm else [])
        self.proc = subprocess.Popen([sys.executable, "-m", "tests.fuzzing", *flags], cwd=ROOT, env=env,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     text=True, bufsize=1)
        ready = self._answer(timeout)
        if not ready or not ready.get("ready"):
            raise RuntimeError("the fuzz worker did not start")

    def _answer(self, timeout: float) -> dict | None:
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
        if not ready:
            return None
        line = self.proc.stdout.readline()
        return json.loads(line) if line else None

    def ask(self, path: Path, timeout: float, *, estimate: bool, cli: bool) -> dict:
        if self.proc is None or self.proc.poll() is not None:
            self.start()
        self.proc.stdin.write(json.dumps({"path": str(path), "estimate": estimate, "cli": cli}) + "\n")
        self.proc.stdin.flush()
        answer = self._answer(timeout)
        if answer is None:
            try:
                self.proc.wait(timeout=5)  # the end of the answer channel: the worker is dying
            except subprocess.TimeoutExpired:
                pass
            hung = self.proc.poll() is None
            self.stop()
            return {"outcome": "hang" if hung else "crash",
                    "detail": f"no answer within {timeout:.0f} s" if hung else "the worker died",
                    "seconds": timeout}
        return answer

    def stop(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.kill()
            self.proc.wait()
            self.proc = None


@dataclass
class Report:
    """Counts per format and the failures."""

    counts: dict = field(default_factory=lambda: defaultdict(Counter))
    slowest: dict = field(default_factory=lambda: defaultdict(float))
    failures: list = field(default_factory=list)
    bytes_read: int = 0

    def add(self, case: Case, answer: dict) -> None:
        fmt = case.seed.format
        self.counts[fmt]["cases"] += 1
        self.counts[fmt][answer["outcome"]] += 1
        self.slowest[fmt] = max(self.slowest[fmt], answer["seconds"])
        self.bytes_read += len(case.data)
        if answer["outcome"] not in ("result", "error"):
            self.failures.append((case.index, case.seed.name, case.mutation, answer["outcome"], answer["detail"]))

    def table(self) -> str:
        rows = ["| format | cases | results | errors | hangs | failures | slowest case (s) |", "|---|---|---|---|---|---|---|"]
        total = Counter()
        for fmt in sorted(self.counts):
            c = self.counts[fmt]
            total.update(c)
            rows.append(f"| {fmt} | {c['cases']} | {c['result']} | {c['error']} | {c['hang']} | "
                        f"{c['failure'] + c['crash']} | {self.slowest[fmt]:.2f} |")
        rows.append(f"| all | {total['cases']} | {total['result']} | {total['error']} | {total['hang']} | "
                    f"{total['failure'] + total['crash']} | {max(self.slowest.values(), default=0):.2f} |")
        return "\n".join(rows)


def run_cases(n_cases: int, folder: Path, *, master_seed: int = 0, estimate: bool = False, cli_every: int = 0,
              seeds: list[Seed] | None = None, progress=None) -> Report:
    """Read ``n_cases`` mutated files (every ``cli_every``-th through the CLI too) in a watched worker."""
    seeds = seeds or seed_files()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    report, worker = Report(), Worker(warm=estimate)
    try:
        for index in range(n_cases):
            case = make_case(index, seeds, master_seed)
            case_dir = folder / f"case{index % 8}"
            case_dir.mkdir(exist_ok=True)
            path = case_dir / f"case{index}{case.seed.suffix}"
            path.write_bytes(case.data)
            answer = worker.ask(path, WATCHDOG_S + WATCHDOG_S_PER_BYTE * len(case.data), estimate=estimate,
                                cli=bool(cli_every) and index % cli_every == 0)
            report.add(case, answer)
            path.unlink(missing_ok=True)
            if progress is not None:
                progress(index, case, answer)
    finally:
        worker.stop()
    return report


def main(argv=None) -> int:
    import argparse
    import tempfile

    parser = argparse.ArgumentParser(description="Fuzz curv's readers with mutated small files of every format.")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--warm", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=0, help="master seed of the mutations")
    parser.add_argument("--estimate", action="store_true", help="estimate qs R2 on every file that loads")
    parser.add_argument("--cli-every", type=int, default=10, help="run the CLI on every N-th case (0: never)")
    parser.add_argument("--laspy-samples", help="a folder of laspy's sample files, added as seeds")
    args = parser.parse_args(argv)
    if args.worker:
        _worker()
        return 0
    seeds = seed_files() + (real_las_seeds(args.laspy_samples) if args.laspy_samples else [])
    t0 = time.perf_counter()

    def progress(index, case, answer):
        if answer["outcome"] not in ("result", "error"):
            print(f"case {index} ({case.seed.name}; {case.mutation}): {answer['outcome']}: {answer['detail']}",
                  flush=True)
        if (index + 1) % 500 == 0:
            print(f"{index + 1} cases, {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)

    with tempfile.TemporaryDirectory(prefix="curv-fuzz-") as folder:
        report = run_cases(args.cases, Path(folder), master_seed=args.seed, estimate=args.estimate,
                           cli_every=args.cli_every, seeds=seeds, progress=progress)
    print(report.table())
    print(f"{args.cases} cases in {time.perf_counter() - t0:.0f} s; {len(seeds)} seed files")
    return 1 if report.failures else 0


if __name__ == "__main__":
    sys.exit(main())
