"""Building ahead of the first estimate what every estimate of an input reads first."""

from __future__ import annotations

import numpy as np

from .core.support import support_of

__all__ = ["prepare"]


def prepare(data) -> np.ndarray | None:
    """Build what every estimate of ``data`` reads first and keep it with ``data``.

    A mesh: its walk over the corners (vertex flags, neighbour lists, the default normals). A point
    cloud: its neighbour search, on the grid-ordered twin its whole-cloud estimates run on. An
    application calls this in a worker thread right after loading, so that the first estimate and
    the first picture (which shades with the same normals) do not each wait for it.

    Parameters
    ----------
    data : curv.Mesh or curv.PointCloud

    Returns
    -------
    (n, 3) float64 or None
        A mesh's default vertex normals (Max's weights, read-only; the ones ``curv.estimate`` uses
        without ``normals=``; NaN where a vertex has none); None for a point cloud.
    """
    if support_of(data).grid_twin:  # a cloud: its estimates run on its twin in grid order
        from .point_normals import grid_ordered

        grid_ordered(data)
        return None
    from .geometry.normals import cached_max_normals

    return cached_max_normals(data)
