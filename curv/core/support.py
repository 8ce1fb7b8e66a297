"""The support provider: what an estimate asks of its input, answered by the input's kind.

A mesh and a point cloud offer the estimators the same arrays (positions, a search structure,
flags), but some questions have an answer per kind: what a range's unit is (a vertex's longest
1-ring edge, a point's spacing), what a support search walks (the mesh's edges, a cloud's grid),
whether the input has faces (creases, smoothing, pooled errors over edge neighbours, one walk
widening over several ranges, face cells in an export), which estimators run on it, how its rows
are named in messages. :func:`support_of` is the one place that tells the kinds apart; every other
module asks the provider it returns.

A new input kind is one :class:`Support` subclass (its answers) and a line in :func:`support_of`;
the places that run a whole path of their own per kind (a cloud's normals and orientation set-up,
the advisor's per-kind candidates, the tiles' fetches) choose it by :attr:`Support.kind`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .errors import EstimatorError
from .pointcloud import PointCloud

__all__ = ["Support", "MeshSupport", "CloudSupport", "support_of", "EdgeSearch", "GridSearch", "SPACING_NEIGHBOUR"]

SPACING_NEIGHBOUR = 6
"""A point's spacing (its range unit) is the distance to its 6th nearest other point
(:mod:`curv.core.ranges`, module notes)."""


class EdgeSearch(NamedTuple):
    """Supports that walk the input's edges (:func:`curv.geometry.neighbourhood.expansion_adjacency`)."""

    indptr: np.ndarray
    """(n+1,) int64."""
    indices: np.ndarray
    """(a,) int64."""


class GridSearch(NamedTuple):
    """Supports that are balls through a grid (:func:`curv.core.knn.build_grid`)."""

    cells: tuple
    """``(cell_keys, cell_start, dims, order)`` int64 arrays."""
    coords: tuple
    """``(origin_and_size, xs, ys, zs)`` float64 arrays."""


class Support:
    """The answers one input kind gives (the base class states the questions).

    Attributes
    ----------
    kind : str
        ``"mesh"`` or ``"points"``: the key of the tables kept per kind
        (:data:`curv.estimators.DEFAULT_ESTIMATORS`) and of the paths run per kind.
    items : str
        What its rows are called in messages (``"vertices"``, ``"points"``).
    unit_words : str
        What its range unit is, in words.
    has_faces : bool
        It has faces and edges: supports walk the edges (one walk widens over several ranges),
        creases and smoothing read them, standard errors pool over edge neighbours, exports
        write its faces.
    grid_twin : bool
        Its estimates run on its twin sorted by grid cell (:func:`curv.point_normals.grid_ordered`),
        whatever its numbering.
    whole_radii : bool
        Its support search reads every row's radius (a cloud's ball grid is sized by their
        median), so an estimate over a region still asks for all of them.
    """

    kind = ""
    items = ""
    unit_words = ""
    has_faces = False
    grid_twin = False
    whole_radii = False

    def __init__(self, shape):
        self.shape = shape

    def unit_lengths(self) -> np.ndarray:
        """(n,) float64 range unit of every row (:mod:`curv.core.ranges`)."""
        raise NotImplementedError

    def knn_distances(self, k: int) -> np.ndarray:
        """(n,) float64 distance of every row to its ``k``-th nearest other row (``knn=k``);
        :class:`~curv.core.errors.EstimatorError` where ``knn`` has no meaning or too few rows."""
        raise NotImplementedError

    def fits_normals(self, normals) -> bool:
        """Whether a call given ``normals=`` (an array, ``"fit"``, ``"pca"`` or None) fits them."""
        return isinstance(normals, str)

    def runs(self, spec) -> bool:
        """Whether the estimator ``spec`` (:class:`curv.estimators.EstimatorSpec`) runs on the input."""
        raise NotImplementedError

    def why_not(self, spec) -> str:
        """Why ``spec`` does not run on the input (``spec`` refused by :meth:`runs`), a clause."""
        raise NotImplementedError

    def search_grid(self, radii: np.ndarray | None) -> GridSearch | None:
        """The grid a support search walks instead of edges (:func:`curv.core.knn.build_grid`; cells
        suited to balls of ``radii`` when given), or None where supports follow edges."""
        return None

    def visit_order(self, radii: np.ndarray):
        """(n,) int64 order in which a whole estimate visits the rows (neighbours one after another,
        sharing what is in the cache), or None for the input's own order."""
        return None


class MeshSupport(Support):
    """A :class:`curv.Mesh`: supports walk its edges, a vertex's unit is its longest 1-ring edge."""

    kind = "mesh"
    items = "vertices"
    unit_words = "the longest 1-ring edge"
    has_faces = True

    def unit_lengths(self) -> np.ndarray:
        return self.shape.longest_edge

    def knn_distances(self, k: int) -> np.ndarray:
        raise EstimatorError("knn= is for point clouds; on a mesh give range= or radius=")

    def runs(self, spec) -> bool:
        return not spec.triangles_only or self.shape.is_triangular

    def why_not(self, spec) -> str:
        kinds = sorted(set(self.shape.face_sizes.tolist()) - {3})
        return f"needs a triangle mesh, but the mesh has faces with {kinds} vertices"


class CloudSupport(Support):
    """A :class:`curv.PointCloud`: supports are balls through its grid, a point's unit is its spacing."""

    kind = "points"
    items = "points"
    unit_words = "the distance to the 6th nearest point"
    grid_twin = True
    whole_radii = True

    def unit_lengths(self) -> np.ndarray:
        return self.shape.kth_distance(SPACING_NEIGHBOUR)

    def knn_distances(self, k: int) -> np.ndarray:
        if k >= self.shape.n_points:
            raise EstimatorError(f"knn={k} needs more than {k} points; the cloud has {self.shape.n_points}")
        return self.shape.kth_distance(k)

    def fits_normals(self, normals) -> bool:
        # without normals given or its own (from the file), a cloud's are fitted
        return isinstance(normals, str) or (normals is None and self.shape.normals is None)

    def runs(self, spec) -> bool:
        return bool(spec.takes_points)

    def why_not(self, spec) -> str:
        return "needs a mesh's faces and does not run on point clouds"

    def search_grid(self, radii: np.ndarray | None) -> GridSearch:
        return GridSearch(*(self.shape.grid if radii is None else self.shape.ball_grid(radii)))

    def visit_order(self, radii: np.ndarray):
        # a whole cloud in its grid's cell order: a random-order cloud's kernel ran about 3x slower;
        # every point writes its own rows, so the result is the same
        return self.shape.ball_grid(radii)[0][3]


def support_of(shape) -> Support:
    """The provider of ``shape``'s kind: a :class:`CloudSupport` for a :class:`curv.PointCloud`, else a
    :class:`MeshSupport` (a :class:`curv.Mesh`). Cheap: build it where the input is at hand."""
    return CloudSupport(shape) if isinstance(shape, PointCloud) else MeshSupport(shape)
