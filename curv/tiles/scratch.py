"""A tiled run's scratch folder: the points of each tile, each finished tile's rows, what the run is.

Layout (every file written whole under a temporary name, then renamed, so a file that exists is
complete)::

    run.json                 what the run is (input, its size and time, the job, the plan): a
                             folder left by another run is cleared, one left by this run resumed
    coordinates.f8           a compressed input's coordinates (and normals) as float64 columns
    plan.pkl                 the tiles (boxes, counts) and the whole input's grid frame
    points/NNNNNN.bin        each tile's core points: records (id, x, y, z[, nx, ny, nz]), ids ascending
    faces/NNNNNN.bin         a mesh's faces with a vertex in the tile: (face id, v0, ..., vk-1), k the
                             longest face's corners (3 for triangles), -1 padding the shorter
    rows/NNNNNN.npy          a finished tile: its core points' results (:data:`ROW_DTYPE`)
    rows/NNNNNN.json         its coordinate steps and points per reason (written just before)
    overlap/NNNNNN.npy       a finished tile's halo normals (the orientation across tiles)

A tile is finished when its ``rows`` file exists; an interrupted run resumes from the others.
The workers of a cluster read and write this folder: on a cluster it must be on a file system
they all see (docs/LARGE_SCANS.md).
"""

from __future__ import annotations

import json
import os
import pickle
import shutil
from pathlib import Path

import numpy as np

__all__ = ["Scratch", "ROW_DTYPE", "OVERLAP_DTYPE", "point_dtype", "FACE_DTYPE", "face_dtype", "rows_to_columns",
           "columns_to_rows", "read_rows", "write_array"]

ROW_DTYPE = np.dtype([("id", "<i8"), ("k1", "<f8"), ("k2", "<f8"), ("d1", "<f4", (3,)), ("d2", "<f4", (3,)),
                      ("normals", "<f4", (3,)), ("k1_se", "<f4"), ("k2_se", "<f4"), ("valid", "u1"),
                      ("reason", "u1"), ("part", "<i4"), ("rooting", "<f4", (3,))])
"""A tile's result row: k1 and k2 in full (H and K are computed from them as in memory); the
directions, normals and standard errors in float32, the precision every output writes them in;
the part of the tile's region its normal was oriented in and the normal the propagation turned
there (:mod:`curv.tiles.orient`)."""

OVERLAP_DTYPE = np.dtype([("id", "<i8"), ("normal", "<f4", (3,)), ("part", "<i4")])
"""A tile's halo point as that tile saw it: its number, its normal and the part it was oriented in."""

FACE_DTYPE = np.dtype([("face", "<i8"), ("v", "<i8", (3,))])
"""A triangle's record in a tile's faces file."""


def face_dtype(width: int = 3) -> np.dtype:
    """A face's record in a tile's faces file: its number in the mesh and its ``width`` corners
    (the mesh's longest face's; -1 pads a shorter one). :data:`FACE_DTYPE` for triangles."""
    return FACE_DTYPE if width == 3 else np.dtype([("face", "<i8"), ("v", "<i8", (int(width),))])

_VERSION = 3  # 2: rows and overlaps carry their part, 3: rows their rooting normal


def point_dtype(normals: bool) -> np.dtype:
    """A tile's point record: its number in the input, its coordinates, and its normal if the file has them."""
    fields = [("id", "<i8"), ("xyz", "<f8", (3,))]
    if normals:
        fields.append(("normal", "<f8", (3,)))
    return np.dtype(fields)


def columns_to_rows(ids: np.ndarray, columns: dict) -> np.ndarray:
    """A (c,) :data:`ROW_DTYPE` array of a tile's kept rows."""
    out = np.empty(ids.size, ROW_DTYPE)
    out["id"] = ids
    for name in ROW_DTYPE.names[1:]:
        out[name] = columns[name]
    return out


def rows_to_columns(rows: np.ndarray) -> dict:
    """The result columns (float64, as :class:`curv.Curvature` names them) of :data:`ROW_DTYPE` rows."""
    out = {}
    for name in ROW_DTYPE.names[1:]:
        values = rows[name]
        out[name] = values.astype(np.float64) if values.dtype.kind == "f" else values
    out["valid"] = rows["valid"].astype(bool)
    return out


def write_array(path: Path, array: np.ndarray) -> None:
    """``np.save`` to a temporary name beside ``path``, then renamed: a file that exists is whole."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "wb") as fh:
            np.save(fh, array, allow_pickle=False)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _header(fh):
    """``(shape, dtype)`` of a ``.npy`` file, its position left at the data."""
    fmt = np.lib.format
    version = fmt.read_magic(fh)
    read = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
    shape, _, dtype = read(fh)
    return shape, dtype


def read_rows(path: Path, start: int = 0, count: int | None = None) -> np.ndarray:
    """Rows ``start:start+count`` of a saved (c,) structured array, read from the file (no memory map)."""
    with open(path, "rb") as fh:
        shape, dtype = _header(fh)
        total = shape[0]
        count = total - start if count is None else max(0, min(count, total - start))
        fh.seek(fh.tell() + start * dtype.itemsize)
        return np.fromfile(fh, dtype=dtype, count=count)


def _array_length(path: Path) -> int:
    with open(path, "rb") as fh:
        shape, _ = _header(fh)
    return int(shape[0])


class Scratch:
    """A run's scratch folder (module notes)."""

    def __init__(self, folder):
        self.folder = Path(folder)

    # --- what the run is ---------------------------------------------------------------------
    def identity(self, source_path: Path, job_call: dict, tile_size: int) -> dict:
        st = source_path.stat()
        return {"version": _VERSION, "input": str(source_path.resolve()), "size": st.st_size,
                "mtime_ns": st.st_mtime_ns, "job": repr(sorted(job_call.items())), "tile_size": int(tile_size)}

    def open(self, identity: dict) -> bool:
        """Make the folder ready for ``identity``: True when it holds a plan of this same run (resume),
        False when it was empty or held another run's files (cleared)."""
        marker = self.folder / "run.json"
        if marker.is_file():
            try:
                same = json.loads(marker.read_text()) == identity
            except (OSError, ValueError):
                same = False
            if same and (self.folder / "plan.pkl").is_file():
                return True
        if self.folder.exists():
            self.clear()
        self.folder.mkdir(parents=True, exist_ok=True)
        for sub in ("points", "faces", "rows", "overlap"):
            (self.folder / sub).mkdir(exist_ok=True)
        tmp = marker.with_name(".run.json.tmp")
        tmp.write_text(json.dumps(identity))
        os.replace(tmp, marker)
        return False

    def clear(self) -> None:
        """Remove the run's files (and the folder, when nothing else is in it)."""
        for name in ("run.json", "coordinates.f8", "triangles.i8", "plan.pkl"):
            (self.folder / name).unlink(missing_ok=True)
        for sub in ("points", "faces", "rows", "overlap"):
            shutil.rmtree(self.folder / sub, ignore_errors=True)
        for tmp in self.folder.glob(".*.tmp"):
            tmp.unlink(missing_ok=True)
        try:
            self.folder.rmdir()
        except OSError:
            pass

    # --- the plan -----------------------------------------------------------------------------
    def save_plan(self, plan) -> None:
        tmp = self.folder / ".plan.pkl.tmp"
        with open(tmp, "wb") as fh:
            pickle.dump(plan, fh)
        os.replace(tmp, self.folder / "plan.pkl")

    def load_plan(self):
        with open(self.folder / "plan.pkl", "rb") as fh:
            return pickle.load(fh)

    # --- the tiles' points ----------------------------------------------------------------------
    def points_path(self, tile: int) -> Path:
        return self.folder / "points" / f"{tile:06d}.bin"

    def faces_path(self, tile: int) -> Path:
        return self.folder / "faces" / f"{tile:06d}.bin"

    def append(self, path: Path, records: np.ndarray) -> None:
        with open(path, "ab") as fh:
            fh.write(records.tobytes())

    def read_points(self, tile: int, dtype: np.dtype) -> np.ndarray:
        path = self.points_path(tile)
        return np.fromfile(path, dtype=dtype) if path.is_file() else np.empty(0, dtype)

    def read_faces(self, tile: int, dtype: np.dtype = FACE_DTYPE) -> np.ndarray:
        path = self.faces_path(tile)
        return np.fromfile(path, dtype=dtype) if path.is_file() else np.empty(0, dtype)

    # --- finished tiles -------------------------------------------------------------------------
    def rows_path(self, tile: int) -> Path:
        return self.folder / "rows" / f"{tile:06d}.npy"

    def overlap_path(self, tile: int) -> Path:
        return self.folder / "overlap" / f"{tile:06d}.npy"

    def info_path(self, tile: int) -> Path:
        return self.folder / "rows" / f"{tile:06d}.json"

    def write_info(self, tile: int, info: dict) -> None:
        """A finished tile's facts (its coordinate steps, its points per reason), written whole."""
        path = self.info_path(tile)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(info))
        os.replace(tmp, path)

    def read_info(self, tile: int) -> dict:
        return json.loads(self.info_path(tile).read_text())

    def forget(self, tile: int) -> None:
        """Make a finished tile unfinished (to run it again): its rows file first."""
        for path in (self.rows_path(tile), self.overlap_path(tile), self.info_path(tile)):
            path.unlink(missing_ok=True)

    def finished(self, tile: int) -> bool:
        return self.rows_path(tile).is_file()

    def rows_count(self, tile: int) -> int:
        return _array_length(self.rows_path(tile))
