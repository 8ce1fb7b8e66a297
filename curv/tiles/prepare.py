"""Before the tiles run: scan the input, plan the tiles, put each tile's points in its own file.

Three passes over the input (:class:`curv.tiles.sources.Source`), each a chunk at a time:

1. **scan**: the count, the bounds and the sample the whole input's grid comes from
   (:mod:`curv.tiles.frame`); a compressed input is copied as plain columns on the way;
2. **count**: the points per cell of a fine grid (:class:`curv.tiles.plan.Histogram`), from which
   the tiles are cut (:func:`curv.tiles.plan.plan_tiles`);
3. **bucket**: each point appended to its tile's file, in the input's order (so every tile's
   points are sorted by their number); a mesh's faces go to the file of every tile that holds one
   of their vertices (a polygon mesh's padded with -1 to its longest face, as :class:`curv.Mesh`
   pads them).

:class:`FileInput` then answers a tile's region from those files (:meth:`FileInput.fetch`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Generator

import numpy as np

from ..core.jit import Progress
from ..core.grid import cell_sample_step
from ..core.neighbour_graph import GRAPH_NEIGHBOURS
from ..core.mesh import scatter_sample, scattered_corners
from .engine import Piece
from .frame import GridFrame, frame_from_sample
from .plan import Histogram, Region, TilePlan, plan_tiles
from .scratch import Scratch, face_dtype, point_dtype
from .sources import CHUNK, Source

__all__ = ["Prepared", "iter_prepare", "FileInput"]


@dataclass
class Prepared:
    """A planned run: the tiles, the whole input's grid, and how to read a tile's region.

    Attributes
    ----------
    plan : TilePlan
    frame : GridFrame or None
        The whole input's grid (a point cloud), or a whole mesh's locality grid when it is
        estimated in grid order (else None).
    n : int
        Points (vertices).
    is_mesh, has_normals : bool
    face_width : int
        A mesh's longest face's corners (the width of the tiles' face records).
    """

    plan: TilePlan
    frame: GridFrame | None
    n: int
    is_mesh: bool
    has_normals: bool
    face_width: int = 3


class FileInput:
    """A planned input's points read back from the scratch folder, a region at a time (picklable:
    it travels to a cluster's workers, which read the same folder)."""

    def __init__(self, scratch: Scratch, prepared: Prepared, source_path: Path):
        self.folder = scratch.folder
        self.tiles = prepared.plan.tiles
        self.histogram_cell = prepared.plan.histogram.cell
        self.is_mesh = prepared.is_mesh
        self.dtype = point_dtype(prepared.has_normals)
        self.has_normals = prepared.has_normals
        self.face_dtype = face_dtype(prepared.face_width)
        self.source_path = Path(source_path)
        self._source = None

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_source"] = None  # a memory map is opened again where it is used
        return state

    def _meeting(self, region: Region) -> list:
        eps = 1e-9 * self.histogram_cell
        out = []
        for t in self.tiles:
            lo, hi = np.asarray(t.lo), np.asarray(t.hi)
            if ((~region.open_hi) & (lo - eps > region.hi)).any() or ((~region.open_lo) & (hi + eps < region.lo)).any():
                continue
            out.append(t.index)
        return out

    def fetch(self, region: Region) -> Piece:
        scratch = Scratch(self.folder)
        parts = []
        meeting = self._meeting(region)
        for t in meeting:
            records = scratch.read_points(t, self.dtype)
            parts.append(records[region.contains(records["xyz"])])
        records = np.concatenate(parts) if parts else np.empty(0, self.dtype)
        records = records[np.argsort(records["id"], kind="stable")]
        ids = np.ascontiguousarray(records["id"])
        points = np.ascontiguousarray(records["xyz"])
        normals = np.ascontiguousarray(records["normal"]) if self.has_normals else None
        if not self.is_mesh:
            return Piece(ids, points, normals)
        dtype = self.face_dtype
        faces = np.concatenate([scratch.read_faces(t, dtype) for t in meeting]) if meeting else np.empty(0, dtype)
        corners = faces["v"]
        touched = np.isin(corners, ids).any(axis=1)  # -1 (padding) is no point's number
        faces = faces[touched]
        faces = faces[np.unique(faces["face"], return_index=True)[1]]  # in the mesh's order, each once
        corners = faces["v"]
        ring = np.setdiff1d(np.unique(corners), ids, assume_unique=True)
        if ring.size and ring[0] < 0:
            ring = ring[1:]
        if ring.size:
            all_ids = np.concatenate([ids, ring])
            all_points = np.concatenate([points, self._vertices_at(ring)])
            sort = np.argsort(all_ids, kind="stable")
            ids, points = all_ids[sort], all_points[sort]
        local = np.searchsorted(ids, corners)
        if corners.shape[1] != 3:
            local[corners < 0] = -1
        return Piece(ids, points, None, local)

    def _vertices_at(self, ids: np.ndarray) -> np.ndarray:
        if self._source is None:
            stat = self.source_path.stat()
            self._source = _reopened(str(self.source_path), str(self.folder), stat.st_mtime_ns, stat.st_size)
        return self._source.vertices_at(ids)


@functools.lru_cache(maxsize=4)
def _reopened(path: str, folder: str, mtime_ns: int, size: int) -> Source:
    """The input opened once per process for all the tiles a worker runs (each tile's task brings
    its own :class:`FileInput`): opening a binary PLY of triangles reads its faces' list lengths
    through the whole face block (2.3 s and 2.5 GB of file pages for a 100M-vertex mesh, once per
    tile before). The file's time and size are in the key, so a file written again is opened again."""
    from .sources import reopen

    return reopen(Path(path), Path(folder))


def _mesh_frame(source: Source, scan) -> GridFrame | None:
    """A whole mesh's locality grid when the whole call would estimate it in grid order
    (:meth:`curv.Mesh.scattered_order`), else None."""
    picked = scatter_sample(source.n_faces)
    corners = source.faces_at(picked)[:, :3]  # every face has three corners at least
    if not scattered_corners(source.n, corners):
        return None
    return frame_from_sample(scan.sample, scan.n, scan.lo, scan.hi)


def iter_prepare(source: Source, scratch: Scratch, tile_size: int) -> Generator[float, None, Prepared]:
    """Scan, count and bucket ``source`` into ``scratch`` (module notes): yields the fraction done
    (with a message per pass), returns the :class:`Prepared` run (also saved in the folder)."""
    n = source.n
    yield Progress(0.0, "reading the input")
    scan = source.scan(scratch.folder, cell_sample_step(n))
    if scan.n == 0:
        from ..core.errors import LoadError

        raise LoadError(f"{source.path}: has no points")
    yield Progress(0.3, "planning the tiles")
    if source.is_mesh:
        frame = _mesh_frame(source, scan)
    else:
        frame = frame_from_sample(scan.sample, scan.n, scan.lo, scan.hi, GRAPH_NEIGHBOURS)
    histogram = Histogram.over(scan.lo, scan.hi)
    for start, pts, _ in source.chunks():
        histogram.add(pts)
        yield Progress(0.3 + 0.2 * (start + pts.shape[0]) / n, "planning the tiles")
    plan = plan_tiles(histogram, tile_size, (scan.lo, scan.hi))
    dtype = point_dtype(source.has_normals)
    tile_file = scratch.folder / "tile_of.i4" if source.is_mesh else None
    tile_of_all = np.lib.format.open_memmap(tile_file, mode="w+", dtype=np.int32, shape=(n,)) if tile_file else None
    for start, pts, normals in source.chunks():
        tiles = plan.tile_of(pts)
        records = np.empty(pts.shape[0], dtype)
        records["id"] = np.arange(start, start + pts.shape[0])
        records["xyz"] = pts
        if normals is not None:
            records["normal"] = normals
        if tile_of_all is not None:
            tile_of_all[start:start + pts.shape[0]] = tiles
        order = np.argsort(tiles, kind="stable")
        cuts = np.flatnonzero(np.diff(tiles[order])) + 1
        for group in np.split(order, cuts):
            if group.size:
                scratch.append(scratch.points_path(int(tiles[group[0]])), records[group])
        yield Progress(0.5 + (0.5 if not source.is_mesh else 0.25) * (start + pts.shape[0]) / n, "sorting points into tiles")
    width = source.face_width() if source.is_mesh else 3
    if source.is_mesh:
        tile_of_all.flush()
        dtype = face_dtype(width)
        for start, faces in source.face_chunks():
            owners = np.asarray(tile_of_all[faces.ravel()]).reshape(faces.shape)
            if width != 3:
                owners[faces < 0] = -1  # padding: in no tile
            records = np.empty(faces.shape[0], dtype)
            records["face"] = np.arange(start, start + faces.shape[0])
            records["v"] = faces
            # each face once per distinct tile among its vertices
            for column in range(width):
                first = owners[:, column] >= 0
                for other in range(column):
                    first &= owners[:, column] != owners[:, other]
                rows = np.flatnonzero(first)
                tiles = owners[rows, column]
                order = np.argsort(tiles, kind="stable")
                cuts = np.flatnonzero(np.diff(tiles[order])) + 1
                for group in np.split(order, cuts):
                    if group.size:
                        scratch.append(scratch.faces_path(int(tiles[group[0]])), records[rows[group]])
            yield Progress(0.75 + 0.25 * (start + faces.shape[0]) / max(source.n_faces, 1), "sorting faces into tiles")
        del tile_of_all
        tile_file.unlink(missing_ok=True)
    prepared = Prepared(plan, frame, n, source.is_mesh, source.has_normals, width)
    scratch.save_plan(prepared)
    yield Progress(1.0, "")
    return prepared
