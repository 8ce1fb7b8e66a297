"""The point-cloud model: a surface sampled as points, with or without normals, and no faces."""

from __future__ import annotations

import numpy as np

from .errors import MeshError

__all__ = ["PointCloud"]


def _as_points(points) -> np.ndarray:
    """(n, 3) float64 copy of ``points``; a one-line :class:`MeshError` for anything else."""
    try:
        p = np.array(points, dtype=np.float64, copy=True)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"points are not numeric: {exc}") from None
    if p.ndim != 2 or p.shape[1] != 3:
        raise MeshError(f"points must have shape (n, 3), got {p.shape}")
    if p.shape[0] == 0:
        raise MeshError("point cloud has no points")
    bad = ~np.isfinite(p).all(axis=1)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        more = int(bad.sum()) - 1
        raise MeshError(f"point {first} has a NaN or infinite coordinate" + (f" (and {more} more points)" if more else ""))
    return p


class PointCloud:
    """Points sampled on a surface, with optional per-point normals (e.g. from the file).

    Parameters
    ----------
    points : (n, 3) array_like
        Point positions; finite.
    normals : (n, 3) array_like, optional
        Per-point normals as given (rows of zero length or NaN are allowed: such points have no
        usable normal). None when the input has none.

    The arrays are read-only copies: a point cloud is immutable, like :class:`curv.Mesh`.
    """

    def __init__(self, points, normals=None):
        self._points = _as_points(points)
        self._points.setflags(write=False)
        if normals is None:
            self._normals = None
        else:
            nrm = np.array(normals, dtype=np.float64, copy=True)
            if nrm.shape != self._points.shape:
                raise MeshError(f"normals must have shape {self._points.shape}, got {nrm.shape}")
            nrm.setflags(write=False)
            self._normals = nrm

    @property
    def points(self) -> np.ndarray:
        """(n, 3) float64 positions (read-only)."""
        return self._points

    @property
    def vertices(self) -> np.ndarray:
        """The points under the name the estimators' kernels read: (n, 3) float64."""
        return self._points

    @property
    def normals(self) -> np.ndarray | None:
        """(n, 3) float64 normals given with the points (read-only), or None."""
        return self._normals

    @property
    def n_points(self) -> int:
        return int(self._points.shape[0])

    @property
    def n_vertices(self) -> int:
        """Same as :attr:`n_points`, for code that handles meshes and point clouds alike."""
        return self.n_points

    def __repr__(self) -> str:
        with_normals = "with normals" if self._normals is not None else "without normals"
        return f"PointCloud({self.n_points} points, {with_normals})"
