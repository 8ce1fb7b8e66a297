"""The point-cloud model: a surface sampled as points, with or without normals, and no faces.

A point cloud offers the estimators what a mesh offers them, so that one kernel per estimator
serves both: positions (``vertices``), an ``adjacency`` (here the
symmetric graph of each point's :data:`curv.core.neighbour_graph.GRAPH_NEIGHBOURS` nearest, along which normals are
oriented), a ``grid`` that gives every support exactly (the ball around the point, as the mesh's
search gives the ball's connected vertices), and the per-vertex flags the API reads (``isolated_vertices``, ``nonmanifold_vertices``,
``coincident_points``). What a point's range unit is (its spacing) is :mod:`curv.core.ranges`' rule.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .errors import MeshError
from .grid import build_grid
from .knn import nearest_neighbours
from .neighbour_graph import GRAPH_NEIGHBOURS, neighbour_steps, symmetric_graph

__all__ = ["PointCloud", "PointSet", "as_positions"]


def as_positions(data, one: str = "point", many: str = "points", whole: str = "point cloud") -> np.ndarray:
    """(n, 3) float64 read-only copy of ``data``: the positions of a point cloud or of a mesh's vertices.

    Parameters
    ----------
    data : (n, 3) array_like
        Finite coordinates, at least one row.
    one, many, whole : str
        The words the errors use for one row, several rows and what they belong to
        (``"vertex"``, ``"vertices"``, ``"mesh"`` for a mesh).

    Raises
    ------
    MeshError
        One line naming what is wrong: not numeric, not (n, 3), empty, or the first row with a NaN
        or infinite coordinate.
    """
    try:
        p = np.array(data, dtype=np.float64, copy=True)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{many} are not numeric: {exc}") from None
    if p.ndim != 2 or p.shape[1] != 3:
        raise MeshError(f"{many} must have shape (n, 3), got {p.shape}")
    if p.shape[0] == 0:
        raise MeshError(f"{whole} has no {many}")
    bad = ~np.isfinite(p)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        kind = "a NaN" if np.isnan(p[row, col]) else "an infinite"
        more = int(bad.any(axis=1).sum()) - 1
        extra = f" (and {more} more {many})" if more else ""
        raise MeshError(f"{one} {row} has {kind} coordinate{extra}")
    p.setflags(write=False)
    return p


class PointSet:
    """Read-only (n, 3) positions: what a :class:`PointCloud` and a :class:`curv.Mesh` share, under the
    names the estimators' kernels read (``vertices``, ``n_vertices``)."""

    _vertices: np.ndarray

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64 positions (read-only)."""
        return self._vertices

    @property
    def n_vertices(self) -> int:
        return int(self._vertices.shape[0])


class PointCloud(PointSet):
    """Points sampled on a surface, with optional per-point normals (e.g. from the file).

    Parameters
    ----------
    points : (n, 3) array_like
        Point positions; finite.
    normals : (n, 3) array_like, optional
        Per-point normals as given (rows of zero length or NaN are allowed: such points have no
        usable normal). None when the input has none.
    georeferenced : bool
        The points are a scan in a map's coordinates with z up (aerial or terrestrial LiDAR; the
        LAS/LAZ reader says so): estimated normals are then turned up at every point by default
        (:func:`curv.point_normals.default_orientation`).
    grid_frame : (origin (3,), cell), optional
        Lay the grids over these points from this lower corner (at most their least coordinates),
        the neighbour grid with this cell edge: the grid of a larger cloud these points are a part
        or a reordering of (its twin in grid order, a tile), so that the searches visit the same
        cells in the same order and break ties in distance alike. Default: the points' own.
    coordinate_step : float, optional
        The step of the grid the coordinates are stored on (:attr:`coordinate_step`), when it is
        known for a larger cloud these points are a part of (a tile): the same resolution, the same
        quantisation checks. Default: measured on these points.

    The arrays are read-only copies: a point cloud is immutable, like :class:`curv.Mesh`.
    """

    def __init__(self, points, normals=None, *, georeferenced: bool = False, grid_frame=None, coordinate_step=None):
        self._vertices = as_positions(points)
        self._georeferenced = bool(georeferenced)
        self.grid_frame = None if grid_frame is None else (np.asarray(grid_frame[0], np.float64).reshape(3),
                                                            float(grid_frame[1]))
        if coordinate_step is not None:
            self.__dict__["coordinate_step"] = float(coordinate_step)  # the cached value, given
        if normals is None:
            self._normals = None
        else:
            nrm = np.array(normals, dtype=np.float64, copy=True)
            if nrm.shape != self._vertices.shape:
                raise MeshError(f"normals must have shape {self._vertices.shape}, got {nrm.shape}")
            nrm.setflags(write=False)
            self._normals = nrm

    points = PointSet.vertices
    """(n, 3) float64 positions (read-only); ``vertices`` is the same array."""
    n_points = PointSet.n_vertices

    @property
    def normals(self) -> np.ndarray | None:
        """(n, 3) float64 normals given with the points (read-only), or None."""
        return self._normals

    @property
    def georeferenced(self) -> bool:
        """Whether the points are a scan in a map's coordinates with z up (see the class notes)."""
        return self._georeferenced

    @cached_property
    def grid(self):
        """The uniform grid over the points (:func:`curv.core.grid.build_grid`), made once: it answers the
        nearest-neighbour queries and every ball support of an estimate."""
        if self.grid_frame is not None:
            origin, cell = self.grid_frame
            return build_grid(self._vertices, GRAPH_NEIGHBOURS, cell=cell, origin=origin)
        return build_grid(self._vertices, GRAPH_NEIGHBOURS)

    def ball_grid(self, radii: np.ndarray):
        """A grid whose cells suit balls of these radii (cell edge ~1.25 x their median), cached.

        A ball then spans one ring of cells around its centre's cell for most points, so a
        support is searched among about four times its own size. Cell edges are rounded to
        steps of 2^(1/4), so that nearby radii share a grid.
        """
        r = float(np.median(radii))
        if not (np.isfinite(r) and r > 0):
            return self.grid
        step = round(4.0 * np.log2(1.25 * r))
        cache = self.__dict__.setdefault("_ball_grids", {})
        if step not in cache:
            if len(cache) >= 4:
                cache.pop(next(iter(cache)))
            origin = None if self.grid_frame is None else self.grid_frame[0]
            cache[step] = build_grid(self._vertices, cell=2.0 ** (step / 4.0), origin=origin)
        return cache[step]

    @cached_property
    def nearest(self) -> tuple[np.ndarray, np.ndarray]:
        """The :data:`~curv.core.neighbour_graph.GRAPH_NEIGHBOURS` nearest other points of every point (computed once).

        Returns
        -------
        indices : (n, G) int64
            Nearest first; -1 where the cloud has fewer than G other points.
        distances : (n, G) float64
            Ascending (inf with -1). Read-only.
        """
        indices, distances = nearest_neighbours(self._vertices, GRAPH_NEIGHBOURS, self.grid)
        for arr in (indices, distances):
            arr.setflags(write=False)
        return indices, distances

    def adopt_grid(self, grid) -> None:
        """Take ``grid`` as :attr:`grid`: a grid of these same points in this order, made elsewhere
        (:func:`curv.core.grid.in_sorted_order` of the grid of the cloud this one is the grid-ordered
        twin of: the grid this cloud would build in its :attr:`grid_frame`, without sorting again)."""
        cells, coords = grid
        if cells[3].size != self.n_points or not all(np.array_equal(coords[1 + a], self._vertices[:, a])
                                                      for a in range(3)):
            raise ValueError("a grid of other points")
        self.__dict__["grid"] = grid

    def same_points_as(self, twin: "PointCloud", order: np.ndarray) -> None:
        """Read this cloud's distances to its nearest points from ``twin``, the same points in another
        order (twin row i is this cloud's row ``order[i]``, an (n,) int array): the distances are the
        same, so a search made on the twin serves this cloud too instead of being made again
        (:meth:`kth_distance`, :attr:`isolated_vertices`, :attr:`coincident_points`)."""
        self.__dict__["_twin"] = (twin, np.asarray(order))

    def kth_distance(self, k: int) -> np.ndarray:
        """(n,) float64 distance from every point to its k-th nearest other point (inf if none).

        Cached per k (read-only); k up to :data:`~curv.core.neighbour_graph.GRAPH_NEIGHBOURS` reads :attr:`nearest`,
        or the twin's distances after :meth:`same_points_as`.
        """
        k = int(k)
        if k < 1:
            raise ValueError(f"k must be >= 1, got {k}")
        cache = self.__dict__.setdefault("_kth", {})
        if k not in cache:
            twin = self.__dict__.get("_twin")
            if twin is not None:
                out = np.empty(self.n_points)
                out[twin[1]] = twin[0].kth_distance(k)
            elif k <= GRAPH_NEIGHBOURS:
                out = np.ascontiguousarray(self.nearest[1][:, k - 1])
            else:
                out = np.ascontiguousarray(nearest_neighbours(self._vertices, k, self.grid)[1][:, -1])
            out.setflags(write=False)
            cache[k] = out
        return cache[k]

    @cached_property
    def coordinate_step(self) -> float:
        """The resolution the coordinates are stored with: the step of their grid, 0.0 for floats of
        full precision.

        Per axis, the smallest non-zero coordinate difference between a point and its nearest
        points (:func:`curv.core.neighbour_graph.neighbour_steps`); the step is the finest of the three (an
        axis that never varies is exact: 0.0, and rounding along the others only moves points
        within the surface). E.g. 0.01 for a LAS file whose points lie on a
        1 cm grid, about 1e-6 of the spacing for full-precision floats. An axis whose step is
        coarser than that is a sampling lattice (a raster's x and y, with the heights measured
        exactly there), not a rounding of the positions. A support only a few steps wide sees the
        grid's stairs rather than the surface (:mod:`curv.point_normals`, the quantisation check).
        """
        twin = self.__dict__.get("_twin")
        if twin is not None:
            return twin[0].coordinate_step
        return float(neighbour_steps(self._vertices, self.nearest[0]).min())

    @cached_property
    def adjacency(self) -> sp.csr_matrix:
        """(n, n) int8 CSR neighbour graph: p and q are joined if either is among the other's
        :data:`~curv.core.neighbour_graph.GRAPH_NEIGHBOURS` nearest (symmetric, sorted indices).

        Normals are oriented along it (:mod:`curv.point_normals`); supports come from the grid.
        """
        indptr, neighbours = symmetric_graph(self.nearest[0])
        n = self.n_points
        return sp.csr_matrix((np.ones(neighbours.size, np.int8), neighbours, indptr), shape=(n, n))

    @cached_property
    def nonmanifold_vertices(self) -> np.ndarray:
        """(n,) bool, all False: points have no faces to be non-manifold (for code shared with meshes)."""
        out = np.zeros(self.n_points, bool)
        out.setflags(write=False)
        return out

    @cached_property
    def isolated_vertices(self) -> np.ndarray:
        """(n,) bool: points without any other point (a cloud of one point)."""
        twin = self.__dict__.get("_twin")
        if twin is not None:
            out = np.empty(self.n_points, dtype=bool)
            out[twin[1]] = twin[0].isolated_vertices
        else:
            out = self.nearest[0][:, 0] < 0
        out.setflags(write=False)
        return out

    @cached_property
    def coincident_points(self) -> np.ndarray:
        """(n,) bool: points at exactly the position of a point with a smaller index.

        The first of each group of coincident points stands for it; the repeats carry no
        information of their own (``Reason.DEGENERATE`` in an estimate, and the fits skip them as
        neighbours since their offset has no tangent part).
        """
        twin = self.__dict__.get("_twin")
        if twin is None:
            indices, distances = self.nearest
            rows = np.arange(self.n_points)
        else:  # the twin's search, its rows and neighbours named by this cloud's indices
            (indices, distances), rows = twin[0].nearest, twin[1]
            indices = np.where(indices >= 0, rows[indices], -1)
        ahead = (distances == 0.0) & (indices >= 0) & (indices < rows[:, None])
        out = np.empty(self.n_points, dtype=bool)
        out[rows] = ahead.any(axis=1)
        out.setflags(write=False)
        return out

    def __repr__(self) -> str:
        with_normals = "with normals" if self._normals is not None else "without normals"
        where = ", georeferenced" if self._georeferenced else ""
        return f"PointCloud({self.n_points} points, {with_normals}{where})"
