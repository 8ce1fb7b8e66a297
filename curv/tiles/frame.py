"""The whole input's grid, passed to its tiles: what makes a tile's arithmetic the whole call's.

An estimate of a whole point cloud runs on the cloud's twin in grid order
(:func:`curv.point_normals.grid_ordered`): the points sorted by the cell of a uniform grid (its
lower corner the cloud's least coordinates, its cell edge chosen from a sample of the cloud,
:func:`curv.core.grid.build_grid`), ties in their file order. The nearest-neighbour search scans
that grid too, and breaks ties in distance by its scan order. A tile that laid its own grid over
its own points would order them differently and, where two neighbours lie at exactly the same
distance (common on scans quantised to a millimetre or a centimetre), keep another one: another
spacing, another border test, another result. So a tile is built **in the whole cloud's grid
order** and searches **the whole cloud's cells** (:func:`framed_cloud`): its points are the whole
twin's restricted to the tile, its neighbour search scans the same cells in the same order, and
every point whose reach lies inside the tile (:mod:`curv.tiles.reach`) gets the whole call's
neighbours, ties included.

The support balls of the estimators and of the normals are searched in grids whose cell edge
follows the median radius over the cloud (:meth:`curv.PointCloud.ball_grid`): a tile's median is
its own, so the points of a support may be visited in another order and their sums added in
another order. That changes the last bits of a value (a few units in the last place), never
which points a support holds; results equal the whole call's to rounding there.

A mesh keeps its numbering in a tile (its vertices in the whole mesh's order, its faces in the
whole mesh's order), so a tile's neighbour lists, edge tables and sums over corners run in the
whole call's order: bit for bit. A whole mesh numbered too scattered for the caches is estimated
on its twin in grid order (:meth:`curv.Mesh.scattered_order`); its tiles then take that order too
(:class:`TileMesh`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.grid import cell_sample_step, sample_cell_size
from ..core.neighbour_graph import GRAPH_NEIGHBOURS
from ..core.mesh import Mesh
from ..core.pointcloud import PointCloud

__all__ = ["GridFrame", "frame_of", "frame_from_sample", "grid_order", "TileMesh", "framed_cloud", "tile_mesh"]


@dataclass(frozen=True)
class GridFrame:
    """The whole input's grid: its lower corner and cell edge (:func:`curv.core.grid.build_grid`).

    Attributes
    ----------
    origin : (3,) float64
        The least coordinates of the whole input.
    cell : float
        The cell edge the whole input's grid takes (``k`` neighbours a cell, 10 for a cloud's
        neighbour graph and for a mesh's locality order alike).
    """

    origin: tuple
    cell: float

    @property
    def lower(self) -> np.ndarray:
        return np.asarray(self.origin, dtype=np.float64)


def frame_of(points: np.ndarray, k: int = GRAPH_NEIGHBOURS) -> GridFrame:
    """The frame of an input held in memory: what ``build_grid(points, k)`` lays."""
    points = np.asarray(points, dtype=np.float64)
    n = points.shape[0]
    lo, hi = points.min(axis=0), points.max(axis=0)
    return frame_from_sample(points[::cell_sample_step(n)], n, lo, hi, k)


def frame_from_sample(sample: np.ndarray, n: int, lo, hi, k: int = GRAPH_NEIGHBOURS) -> GridFrame:
    """The frame of ``n`` points with bounds ``lo``, ``hi`` from every
    :func:`curv.core.grid.cell_sample_step`-th of them in their order (a file read a chunk at a time)."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    extent = float((hi - lo).max())
    cell = sample_cell_size(np.asarray(sample, np.float64), int(n), extent, k)
    return GridFrame(tuple(float(v) for v in lo), float(cell))


def grid_order(points: np.ndarray, ids: np.ndarray, frame: GridFrame) -> np.ndarray:
    """(m,) the order of ``points`` (rows of the whole input numbered ``ids``) in the whole input's
    grid order: by cell ``(ix, iy, iz)`` of ``frame``, then by ``ids``."""
    cells3 = np.floor((np.asarray(points, np.float64) - frame.lower) / frame.cell).astype(np.int64)
    return np.lexsort((np.asarray(ids), cells3[:, 2], cells3[:, 1], cells3[:, 0]))


def framed_cloud(points: np.ndarray, normals, ids: np.ndarray, frame: GridFrame, *, georeferenced: bool = False,
                 step: float | None = None):
    """These rows of a larger cloud as a :class:`curv.PointCloud` in the larger cloud's grid order,
    searching its grid (:attr:`curv.PointCloud.grid_frame`), estimated as it is (it is the whole
    call's twin restricted to these points), and the order it holds them in: ``(cloud, order)``,
    cloud row i being ``ids[order[i]]``. ``georeferenced`` and ``step`` (the coordinates' step) are
    the larger cloud's (None: the step measured on these points)."""
    from ..point_normals.grid_order import mark_ordered

    order = grid_order(points, ids, frame)
    cloud = PointCloud(points[order], None if normals is None else normals[order], georeferenced=georeferenced,
                       grid_frame=(frame.lower, frame.cell), coordinate_step=step)
    mark_ordered(cloud)
    return cloud, order


class TileMesh(Mesh):
    """A part of a larger mesh, numbered in the order the whole call estimates the whole mesh in:
    never renumbered again (:meth:`curv.Mesh.scattered_order` is False)."""

    def scattered_order(self, *, sample: int = 4096) -> bool:
        return False


def tile_mesh(vertices: np.ndarray, faces, ids: np.ndarray, frame: GridFrame | None):
    """A :class:`TileMesh` of the vertices ``ids`` of a larger mesh and ``faces`` (indices into
    ``vertices``), numbered as the whole call numbers them: ``(mesh, order)``, mesh vertex i being
    ``ids[order[i]]``. ``frame`` is the whole mesh's locality grid when the whole mesh is estimated
    in grid order (scattered), else None: the whole mesh's own order."""
    order = np.argsort(ids, kind="stable") if frame is None else grid_order(vertices, ids, frame)
    rank = np.empty(order.size, np.int64)
    rank[order] = np.arange(order.size)
    if isinstance(faces, list):
        faces = [rank[f] for f in faces]
    else:
        faces = np.asarray(faces, np.int64)
        faces = np.where(faces >= 0, rank[np.maximum(faces, 0)], -1)  # -1 pads a shorter polygon
    return TileMesh(vertices[order], faces), order
