"""Normals and borders of a point cloud: local PCA, consistent orientation, the open-scan border.

1. **PCA** (one kernel, :func:`local_frames`): over each point's range support (the ball of
   ``k`` spacings through the neighbour graph, :mod:`curv.core.ranges`), the eigenvector of the
   smallest eigenvalue of the covariance about the centroid is the unoriented normal. The same
   pass measures the largest **angular gap** between the support's offsets projected on that
   plane: about pi on the rim of an open scan, small inside (:func:`border_points`; a point a
   fraction of a spacing inside the rim, whose gap the points between it and the rim hide, is found
   by its one-sided support instead, :mod:`.rim`).
2. **Orientation** (:func:`orient_normals`), by one of four rules (:data:`ORIENTATIONS`):

   - ``"up"``: every normal with nz >= 0, point by point (the convention of PDAL's
     ``filters.normal`` for aerial and terrestrial scans). Nothing propagates, so one bad point
     or a fold cannot turn a whole region over, and a tile of a scan is oriented as the whole
     scan is. A normal within :data:`GRAZING_COSINE` of horizontal (a wall, a fence) has no
     decidable "up": it is left undecided (step 3), never guessed.
   - ``"top"``: Hoppe et al. 1992 (Surface reconstruction from unorganized points, §3.3): a
     minimum spanning tree of the neighbour graph with weights ``1 - |n_p . n_q|`` (so that the
     propagation crosses nearly parallel normals first), walked from one root per connected
     part, flipping each normal to agree with its parent; the root is the part's highest point,
     its normal turned up (+z). On a closed object the top's outward normal is up, so this is
     outward; on an open patch it is up where the patch is a height field. Kruskal's algorithm
     in numba (the edges in the order of a stable radix sort of their weights, a union-find
     forest) and a breadth-first walk of each part's tree: no sparse matrices are built.
   - ``"outward"``: the same propagation, each part's root the point farthest from the part's
     centroid, turned away from it (closed objects).
   - a viewpoint (x, y, z): every normal towards it (a scanner's position), without propagation.

   **The default** (:func:`default_orientation`): ``"up"`` for a georeferenced cloud (LAS/LAZ:
   aerial and terrestrial LiDAR in a map's coordinates; on such scans one wrong turn of the
   propagation flipped most of a file: 95.5 % of ``autzen_trim.laz``'s normals pointed down),
   ``"top"`` for any other cloud (objects, closed or not, and synthetic patches). An estimate's
   ``info["orientation"]`` says which rule ran.
3. **Ambiguity.** After the propagation, a point whose oriented normal agrees clearly
   (|cos| >= :data:`AGREE_COSINE`) with fewer graph neighbours than disagree with it, or with
   none, cannot be oriented by its neighbourhood (a thin sheet, a fold, a sparse spot). With
   ``"up"``, where the side comes from the vertical and not from the neighbours, a point that
   as many of its :data:`curv.core.neighbour_graph.GRAPH_NEIGHBOURS` nearest clearly oppose as agree with
   (and at least one) is undecided: only normals within 60 degrees of horizontal can oppose
   each other once both are up, so these are the sides of a wall or a fence whose normals
   wobble across the horizontal. With ``"up"`` or a viewpoint, a normal seen edge-on (``|cos| <``
   :data:`GRAZING_COSINE` with the vertical or the view ray) is undecided too. Such points get a
   NaN normal and ``Reason.ORIENTATION`` in an estimate: no guess.
4. ``method="jet"`` (the default): the PCA normals, oriented, then refined by the jet fit that
   :func:`curv.fitted_normals.fitted_normals` uses on meshes (:func:`curv.estimators.jet.fit_jet`).
5. **One pass.** Steps 1 and 4 and the line check of an estimate (:func:`support_spread`) read
   nested supports of the same point (R2 inside R3), so one kernel (:func:`.one_pass._one_pass`) searches
   each point's ball once, at the largest radius, and takes every support from it. It walks the
   points in the grid's cell order and reads their coordinates there (:func:`curv.core.grid_balls.grid_gather`),
   so that neighbours are near in memory; in the cloud's own order (random for a scan saved
   unsorted) every neighbour was a cache miss. The jet is fitted with the unoriented PCA normal
   as its reference: a fit turned the other way is the same fit with its sign changed exactly,
   so the normal is turned afterwards, once the orientation is known. For a jet or qs estimate at
   the normals' range the pass keeps what the estimator reads instead of searching and fitting
   again (``keep_fits_at``, :mod:`curv.estimators._handover`): the jet fits themselves, or qs fitted
   on their support in the frame of the fitted normal. Its line check is the one at the fits'
   range; the one without the neighbours' normals (``mru``, ``an``) is measured when asked, over
   the pass's grid, so its sums run in the pass's order (:func:`.one_pass.owe_spreads`). Each ball
   is read from its cell's block, without the cells farther than the radius
   (:func:`curv.core.grid_blocks.cell_runs`): the same points in the same order.
6. **Grid order.** An estimate of a whole cloud runs on its twin in grid order
   (:func:`grid_ordered`) and maps the rows back: the neighbour graph, the orientation and the
   estimators' kernels then read neighbours that are near in memory too (a cloud saved in random
   order made each of their neighbour reads a cache miss).
7. **Coordinates on a grid** (:mod:`.quantised`): a fit over fewer than :data:`MIN_SUPPORT_STEPS`
   steps of the grid the coordinates are stored on (a LAS file's scale) sees its stairs; the
   normals are fitted over at least that radius, and the estimates over narrower supports are
   ``SINGULAR``.

Modules: :mod:`.frames` (the local frame of one support: moments, PCA, gap, spread),
:mod:`.one_pass` (the pass over every point: :func:`local_frames`, :func:`support_spread`),
:mod:`.orientation` (:func:`orient_normals`, :func:`default_orientation`), :mod:`.normals`
(:func:`point_normals`, :func:`border_points`, :func:`border_radii`), :mod:`.rim` (one-sided supports
on the rim), :mod:`.grid_order` (:func:`grid_ordered`), :mod:`.quantised` (:func:`support_floor`,
:func:`quantised_supports`).
"""

from __future__ import annotations

from .frames import MIN_SPREAD
from .grid_order import grid_ordered
from .normals import (BORDER_GAP, BORDER_RANGE, NORMAL_METHODS, NORMAL_RANGE, ONE_SIDED_GAP, PointNormals, border_points,
                      border_radii, border_test_radii, point_normals)
from .one_pass import local_frames, support_spread
from .orientation import (AGREE_COSINE, GRAZING_COSINE, ORIENTATIONS, default_orientation, describe_orientation,
                          keep_tree, orient_normals, spanning_tree)
from .quantised import MIN_SUPPORT_STEPS, quantised_supports, range_above_grid, support_floor

__all__ = ["PointNormals", "point_normals", "grid_ordered", "local_frames", "orient_normals", "keep_tree", "spanning_tree",
           "default_orientation",
           "describe_orientation", "border_points", "border_radii", "border_test_radii", "ORIENTATIONS",
           "support_spread", "support_floor", "quantised_supports", "range_above_grid",
           "MIN_SPREAD", "MIN_SUPPORT_STEPS", "ONE_SIDED_GAP", "BORDER_RANGE",
           "NORMAL_RANGE", "BORDER_GAP", "AGREE_COSINE", "GRAZING_COSINE", "NORMAL_METHODS"]
