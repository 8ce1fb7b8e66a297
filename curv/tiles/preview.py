"""A preview of an input too large to draw: every k-th point of a cloud (a COPC file's coarse octree
levels), a mesh's vertices clustered.

The viewer draws a few million points or vertices interactively; a 100M-point scan opens as a
preview (:func:`read_preview`) read a chunk at a time, so the whole file is never in memory:

* a **point cloud**: every ``stride``-th point in the file's order (a flight line's order thins
  evenly), with its normals if the file has them;
* a **COPC file**: the points of its octree's coarse levels, which its writer made a spatially
  even thinning: levels 0..L, the first that hold the count, thinned to it by taking every k-th
  point (each level holds about 4 times the points above it on a surface, so k < 5 mostly); only
  those chunks are decompressed, not the whole file;
* a **mesh**: its vertices clustered on a uniform grid whose cells hold about the asked count
  (each cluster at its vertices' mean position) and its triangles between three different
  clusters, each once: the shape at a coarser resolution (a cluster may join two sheets, so the
  preview can have non-manifold edges the file does not). A polygon is cut into the fan of
  triangles from its first corner first: the preview of a quad or polygon mesh is a triangle mesh.

What the preview shows is said with it (:attr:`Preview.words`): ``1,000,000 of 100,000,000 points
shown (every 100th)``. Estimates on a preview are estimates of the preview; the full resolution is
read around a point (:mod:`curv.tiles.regions`) or for the whole file (:func:`curv.tiles.estimate_file`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.mesh import Mesh
from ..core.pointcloud import PointCloud
from ..core.support import support_of
from .sources import open_source

__all__ = ["Preview", "read_preview", "file_size", "PREVIEW_POINTS"]

PREVIEW_POINTS = 2_000_000
"""Points (vertices) a preview holds at most: what the viewer draws and picks without stalls."""


@dataclass(frozen=True)
class Preview:
    """A preview of a large input.

    Attributes
    ----------
    shape : PointCloud or Mesh
    total : int
        Points (vertices) in the file.
    path : Path
    stride : int
        For a cloud: every ``stride``-th point (of a COPC file's levels); 0 for a clustered mesh.
    levels : int or None
        For a COPC file: the points of its octree's levels 0..``levels`` are thinned.
    """

    shape: object
    total: int
    path: Path
    stride: int = 0
    levels: int | None = None

    @property
    def shown(self) -> int:
        return int(self.shape.n_vertices)

    @property
    def words(self) -> str:
        """``1,000,000 of 100,000,000 points shown (every 100th)``."""
        if not support_of(self.shape).has_faces:  # a cloud: every k-th point, not clusters
            how = f"every {_ordinal(self.stride)}" if self.stride > 1 else "all"
            if self.levels is not None and self.shown < self.total:
                how = f"octree levels 0-{self.levels}" + (f", every {_ordinal(self.stride)}" if self.stride > 1 else "")
            return f"{self.shown:,} of {self.total:,} points shown ({how})"
        return f"{self.shown:,} of {self.total:,} vertices shown (clustered)"


def _ordinal(k: int) -> str:
    suffix = "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{suffix}"


def file_size(path) -> tuple[int, int] | None:
    """``(points or vertices, faces)`` a LAS/LAZ or PLY file's header declares, without reading
    its data; None for other files (read whole) or a header that says nothing."""
    from ..formats.pointio import peek_points
    from ..io import peek_counts

    path = Path(path)
    if path.suffix.lower() in (".las", ".laz"):
        n = peek_points(path)
        return None if n is None else (n, 0)
    if path.suffix.lower() == ".ply":
        return peek_counts(path)
    return None


def read_preview(path, max_points: int = PREVIEW_POINTS) -> Preview:
    """A :class:`Preview` of ``path`` (LAS/LAZ, binary PLY) holding at most about ``max_points``
    (module notes). Raises :class:`curv.LoadError` for an unreadable file; ``ValueError`` for one
    that cannot be read a chunk at a time (read it whole)."""
    from .copc import CopcInput, is_copc

    path = Path(path)
    if is_copc(path):
        copc = CopcInput(path)
        levels = copc.levels_holding(max_points)
        piece = copc.fetch_levels(levels)
        stride = max(1, -(-piece.ids.size // max_points))
        cloud = PointCloud(piece.points[::stride], None if piece.normals is None else piece.normals[::stride])
        return Preview(cloud, copc.n, path, stride, levels)
    source = open_source(path)
    if source is None:
        raise ValueError(f"{path}: is read whole (not LAS/LAZ or a PLY read a chunk at a time)")
    if source.is_mesh:
        return Preview(_clustered(source, max_points), source.n, path)
    stride = max(1, -(-source.n // max_points))
    points, normals = [], []
    for start, pts, nrm in source.chunks():
        first = (-start) % stride
        points.append(pts[first::stride])
        if nrm is not None:
            normals.append(nrm[first::stride])
    cloud = PointCloud(np.concatenate(points), np.concatenate(normals) if normals else None)
    return Preview(cloud, source.n, path, stride)


def _fan(faces: np.ndarray) -> np.ndarray:
    """(t, 3) the triangles of (m, k) polygons padded with -1, each cut into the fan from its first corner."""
    if faces.shape[1] == 3:
        return faces
    fans = [np.stack([faces[:, 0], faces[:, j], faces[:, j + 1]], axis=1) for j in range(1, faces.shape[1] - 1)]
    triangles = np.concatenate(fans)
    return triangles[triangles[:, 2] >= 0]


def _clustered(source, max_vertices: int) -> Mesh:
    """A mesh's vertices clustered on a grid of about ``max_vertices`` occupied cells, its faces
    between three clusters (module notes)."""
    from .plan import Histogram

    scan = source.scan(None, max(1, source.n // 65536))
    hist = Histogram.over(scan.lo, scan.hi)
    for _, pts, _ in source.chunks():
        hist.add(pts)
    occupied = int((hist.counts > 0).sum())
    # a surface: cells of edge c hold ~ c^2; scale the counting grid's cell to the wanted count, then
    # by what each try gave (the counting grid's cells may be few and coarse)
    cell = hist.cell * max(1.0, np.sqrt(occupied / max(max_vertices, 1)))
    cluster = np.empty(source.n, np.int64)
    for _ in range(8):
        dims = np.maximum(np.ceil((scan.hi - scan.lo) / cell).astype(np.int64), 1)
        for start, pts, _ in source.chunks():
            c = np.clip(np.floor((pts - scan.lo) / cell).astype(np.int64), 0, dims - 1)
            cluster[start:start + pts.shape[0]] = (c[:, 0] * dims[1] + c[:, 1]) * dims[2] + c[:, 2]
        keys, inverse = np.unique(cluster, return_inverse=True)
        if keys.size <= 1.25 * max_vertices:
            break
        cell *= np.sqrt(keys.size / max_vertices)
    cluster = inverse
    sums = np.zeros((keys.size, 3))
    counts = np.zeros(keys.size)
    for start, pts, _ in source.chunks():
        ids = cluster[start:start + pts.shape[0]]
        for axis in range(3):
            sums[:, axis] += np.bincount(ids, pts[:, axis], minlength=keys.size)
        counts += np.bincount(ids, minlength=keys.size)
    vertices = sums / np.maximum(counts, 1)[:, None]
    kept = np.empty((0, 3), np.int64)
    for _, faces in source.face_chunks():
        f = cluster[_fan(faces)]
        f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
        # each face once whatever its first corner, keeping its orientation
        roll = np.argmin(f, axis=1)
        f = np.stack([f[np.arange(f.shape[0]), (roll + k) % 3] for k in range(3)], axis=1)
        kept = np.unique(np.concatenate([kept, f]), axis=0)
    used = np.zeros(keys.size, bool)
    used[kept.ravel()] = True
    rank = np.cumsum(used) - 1
    return Mesh(vertices[used], rank[kept])
