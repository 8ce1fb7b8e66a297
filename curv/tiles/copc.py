"""A COPC file's points inside a box, read through its octree: only the chunks the box meets.

A COPC file (Cloud Optimized Point Cloud: a LAZ 1.4 file whose compressed chunks are the nodes of
an octree, indexed by a hierarchy of node keys, file offsets and point counts) can be read a
region at a time. :class:`CopcInput` answers the region fetches of :mod:`curv.tiles.regions`
(a :class:`curv.tiles.engine.Piece`: the points inside the box, their numbers in the file, their
normals) by decompressing only the nodes whose cube meets the box (lazrs, laspy's COPC structures),
instead of the whole file.

A point's number is its place in the file, as laspy's reader (and :func:`curv.load`) number them:
the chunks lie in the file one after the other, so the points of a node start after every point of
the nodes stored before it (the hierarchy's offsets give that order, its counts the numbers).

The whole file's grid (:class:`curv.tiles.frame.GridFrame`: its least coordinates and the cell
chosen from every :func:`curv.core.knn.cell_sample_step`-th point in the file's order) is what
makes a region's neighbour search the whole call's, ties in distance included; it needs those
points, so :func:`iter_whole_frame` makes one pass over the file that decompresses the x, y and z
layers only (LAZ 1.4's layered chunks; not the other dimensions, nothing written), once per file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Generator

import numpy as np

from ..core.errors import LoadError
from ..core.jit import Progress
from ..core.paths import one_line
from .engine import Piece
from .frame import GridFrame, frame_from_sample
from .plan import Region

__all__ = ["is_copc", "CopcInput", "iter_whole_frame"]

_ENTRY = np.dtype([("level", "<i4"), ("x", "<i4"), ("y", "<i4"), ("z", "<i4"), ("offset", "<u8"),
                   ("size", "<i4"), ("count", "<i4")])
"""A COPC hierarchy entry (VoxelKey, offset, byte size, point count; -1 points: a child page)."""


def is_copc(path) -> bool:
    """Whether ``path`` is a COPC file (a LAZ whose first VLR is the COPC info record)."""
    path = Path(path)
    if path.suffix.lower() != ".laz":
        return False
    try:
        import laspy
        import lazrs  # noqa: F401 - COPC is read with lazrs only

        with laspy.open(path) as reader:
            vlrs = reader.header.vlrs
            return bool(len(vlrs)) and vlrs[0].user_id == "copc" and vlrs[0].record_id == 1
    except Exception:  # noqa: BLE001 - not a readable LAZ: the ordinary reader says why
        return False


class CopcInput:
    """A COPC file read a region at a time (module notes).

    Parameters
    ----------
    path : str or Path

    Attributes
    ----------
    n : int
        Points in the file.
    has_normals : bool
        The file's own normals, as extra bytes (the names :func:`curv.load` reads).
    nodes_read : int
        Octree nodes decompressed by the last :meth:`fetch` (of ``n_nodes``).
    """

    def __init__(self, path):
        import laspy
        from laspy.copc import CopcReader

        from .sources import _normal_names

        self.path = Path(path)
        try:
            with CopcReader.open(self.path) as reader:
                header = reader.header
                info = reader.copc_info
                self._laszip = bytes(reader.laszip_vlr.record_data)
                reader.source.seek(info.hierarchy_root_offset)
                entries = self._hierarchy(reader.source, info.hierarchy_root_offset, info.hierarchy_root_size)
        except LoadError:
            raise
        except Exception as exc:  # noqa: BLE001 - laspy's and lazrs's errors, in one line
            raise LoadError(f"{self.path}: not a readable COPC file ({one_line(exc)})") from None
        self._format = header.point_format
        self._scales, self._offsets = np.asarray(header.scales), np.asarray(header.offsets)
        self.n = int(header.point_count)
        self._normals = _normal_names(header.point_format.extra_dimension_names)
        self.has_normals = self._normals is not None
        nodes = np.sort(entries[entries["count"] > 0], order="offset")
        if int(nodes["count"].sum()) != self.n:
            raise LoadError(f"{self.path}: its COPC hierarchy holds {int(nodes['count'].sum())} points but its "
                            f"header says {self.n}")
        self._nodes = nodes
        self._starts = np.concatenate([[0], np.cumsum(nodes["count"].astype(np.int64))[:-1]])
        side = 2.0 * float(info.halfsize) / 2.0 ** nodes["level"].astype(np.float64)
        keys = np.stack([nodes["x"], nodes["y"], nodes["z"]], axis=1).astype(np.float64)
        root = np.asarray(info.center, np.float64) - float(info.halfsize)
        self._lo = root + keys * side[:, None]
        self._hi = self._lo + side[:, None]
        # a point may sit on its node's side, and a cube's side is computed in floating point
        self._margin = float(self._scales.max()) + 1e-9 * float(info.halfsize)
        self.n_nodes = int(nodes.size)
        self.nodes_read = 0
        self._laspy = laspy

    def _hierarchy(self, fh, offset: int, size: int) -> np.ndarray:
        """Every entry of the hierarchy, its child pages read too."""
        pages, out = [(offset, size)], []
        while pages:
            at, length = pages.pop()
            fh.seek(at)
            data = fh.read(length)
            if len(data) != length or length % _ENTRY.itemsize:
                raise LoadError(f"{self.path}: its COPC hierarchy page at byte {at} is cut short")
            page = np.frombuffer(data, _ENTRY)
            child = page["count"] == -1
            pages.extend((int(o), int(s)) for o, s in zip(page["offset"][child], page["size"][child]))
            out.append(page[~child])
        return np.concatenate(out)

    def _meeting(self, region: Region) -> np.ndarray:
        """The nodes (rows of the node table) whose cube meets ``region``."""
        keep = np.ones(self._nodes.size, bool)
        for a in range(3):
            if not region.open_lo[a]:
                keep &= self._hi[:, a] + self._margin >= region.lo[a]
            if not region.open_hi[a]:
                keep &= self._lo[:, a] - self._margin <= region.hi[a]
        return np.flatnonzero(keep)

    def fetch(self, region: Region) -> Piece:
        """Every point of the file inside ``region``, in the file's order, numbered as in the file."""
        rows = self._meeting(region)
        ids, xyz, normals = self._read_nodes(rows)
        inside = region.contains(xyz)
        order = np.flatnonzero(inside)[np.argsort(ids[inside], kind="stable")]
        return Piece(np.ascontiguousarray(ids[order]), np.ascontiguousarray(xyz[order]),
                     None if normals is None else np.ascontiguousarray(normals[order]))

    def levels_holding(self, points: int) -> int:
        """The shallowest octree level whose nodes, with every node above them, hold at least
        ``points`` points (the deepest level where the whole file holds fewer)."""
        levels = self._nodes["level"].astype(np.int64)
        held = np.cumsum(np.bincount(levels, weights=self._nodes["count"].astype(np.float64)))
        return min(int(np.searchsorted(held, points, side="left")), held.size - 1)

    def fetch_levels(self, deepest: int) -> Piece:
        """Every point of the nodes at octree levels 0..``deepest``, in the file's order.

        A COPC writer puts a spatially even thinning of the cloud in its coarse levels (each level
        about the points of the one above at half the spacing), so these are a preview of the whole
        file read from a fraction of its chunks."""
        ids, xyz, normals = self._read_nodes(np.flatnonzero(self._nodes["level"] <= deepest))
        order = np.argsort(ids, kind="stable")
        return Piece(ids[order], xyz[order], None if normals is None else normals[order])

    def _read_nodes(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """``(ids, xyz, normals)`` of every point of the nodes ``rows`` (rows of the node table),
        decompressed with the coordinates and the normals' extra bytes only."""
        import lazrs

        laspy = self._laspy
        self.nodes_read = int(rows.size)
        nodes = self._nodes[rows]
        counts = nodes["count"].astype(np.int64)
        record = np.zeros(int(counts.sum()) * self._format.size, np.uint8)
        selection = laspy.DecompressionSelection.XY_RETURNS_CHANNEL | laspy.DecompressionSelection.Z
        if self.has_normals:
            selection |= laspy.DecompressionSelection.ALL_EXTRA_BYTES
        try:
            with open(self.path, "rb") as fh:
                compressed = bytearray(int(nodes["size"].astype(np.int64).sum()))
                view, at = memoryview(compressed), 0
                for offset, size in zip(nodes["offset"], nodes["size"]):
                    fh.seek(int(offset))
                    if fh.readinto(view[at:at + int(size)]) != int(size):
                        raise LoadError(f"{self.path}: the chunk at byte {int(offset)} is cut short (a truncated file)")
                    at += int(size)
            table = [(int(c), int(s)) for c, s in zip(counts, nodes["size"])]
            lazrs.decompress_points_with_chunk_table(bytes(compressed), self._laszip, record, table,
                                                     laspy.DecompressionSelection(selection).to_lazrs())
        except LoadError:
            raise
        except Exception as exc:  # noqa: BLE001 - a corrupt chunk, in one line
            raise LoadError(f"{self.path}: its points cannot be read ({one_line(exc)})") from None
        packed = laspy.PackedPointRecord.from_buffer(record, self._format)
        points = laspy.ScaleAwarePointRecord(packed.array, self._format, self._scales, self._offsets)
        ids = np.repeat(self._starts[rows], counts) + (np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts))
        xyz = np.empty((ids.size, 3))
        for i, c in enumerate("xyz"):
            xyz[:, i] = points[c]
        normals = None
        if self.has_normals:
            normals = np.column_stack([np.asarray(points[c], np.float64) for c in self._normals])
        return ids, xyz, normals


def iter_whole_frame(path, n: int) -> Generator[float, None, tuple[tuple, GridFrame]]:
    """One pass over a LAS/LAZ file's coordinates only (module notes): yields the fraction done,
    returns ``((least, greatest), frame)``, the whole file's bounds and grid."""
    from ..core.knn import GRAPH_NEIGHBOURS, cell_sample_step
    from .sources import CHUNK, LasSource, ScanTally

    source = LasSource(Path(path), coordinates_only=True)
    tally = ScanTally(cell_sample_step(n))
    for start, pts, _ in source.chunks(CHUNK):
        tally.add(start, pts)
        yield Progress(tally.n / max(n, 1), "reading the file's coordinates (its grid)")
    if tally.n == 0:
        raise LoadError(f"{path}: has no points")
    return (tally.lo, tally.hi), frame_from_sample(tally.sample, n, tally.lo, tally.hi, GRAPH_NEIGHBOURS)
