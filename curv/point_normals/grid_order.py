"""A point cloud's twin in its grid's cell order (module notes, 6)."""

from __future__ import annotations

import numpy as np

from ..core.grid import build_grid, in_sorted_order
from ..core.neighbour_graph import GRAPH_NEIGHBOURS
from ..core.pointcloud import PointCloud
from ..geometry.neighbourhood import cached_with_mesh

__all__ = ["grid_ordered", "mark_ordered"]


def grid_ordered(cloud: PointCloud):
    """The cloud with its points in its grid's cell order, and that order (module notes, 6).

    Returns
    -------
    (twin, order) or None
        ``twin`` a :class:`PointCloud` of ``cloud.points[order]`` (and its normals), ``order``
        (n,) int64 read-only; None for a twin itself (it is in that order). Made once per cloud
        and kept with it, so that the twin's own caches (neighbours, frames, normals) serve every
        estimate of the cloud.
    """
    def build():
        grid = cloud.grid if cloud.grid_frame is not None else build_grid(cloud.points, GRAPH_NEIGHBOURS)
        order, origin = grid[0][3], grid[1][0]
        normals = None if cloud.normals is None else cloud.normals[order]
        # the twin searches the cloud's own cells: the same neighbours, ties in distance broken alike,
        # and a part of the cloud in the same order searches them too (curv.tiles). Its points are
        # the grid's sorted coordinates and its grid is this one in its order: no second sort.
        twin = PointCloud(np.column_stack(grid[1][1:]), normals, georeferenced=cloud.georeferenced,
                          grid_frame=(origin[:3], origin[3]))
        twin.adopt_grid(in_sorted_order(grid))
        mark_ordered(twin)
        cloud.same_points_as(twin, order)
        return twin, order

    return cached_with_mesh(cloud, "grid order", build)


def mark_ordered(cloud: PointCloud) -> None:
    """Say that ``cloud`` is already in its grid's order (a twin, or a part of one laid in the whole
    cloud's grid: :attr:`curv.PointCloud.grid_frame`): an estimate runs on it as it is."""
    cached_with_mesh(cloud, "grid order", lambda: None)
