"""A point cloud's twin in its grid's cell order (module notes, 6)."""

from __future__ import annotations

from ..core.knn import GRAPH_NEIGHBOURS, build_grid
from ..core.pointcloud import PointCloud
from ..geometry.neighbourhood import cached_with_mesh

__all__ = ["grid_ordered"]


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
        order = build_grid(cloud.points, GRAPH_NEIGHBOURS)[0][3]
        normals = None if cloud.normals is None else cloud.normals[order]
        twin = PointCloud(cloud.points[order], normals)
        cached_with_mesh(twin, "grid order", lambda: None)
        cloud.same_points_as(twin, order)
        return twin, order

    return cached_with_mesh(cloud, "grid order", build)
