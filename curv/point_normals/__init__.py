"""Normals and borders of a point cloud: local PCA, consistent orientation, the open-scan border.

1. **PCA** (one kernel, :func:`local_frames`): over each point's range support (the ball of
   ``k`` spacings through the neighbour graph, :mod:`curv.core.ranges`), the eigenvector of the
   smallest eigenvalue of the covariance about the centroid is the unoriented normal. The same
   pass measures the largest **angular gap** between the support's offsets projected on that
   plane: about pi on the rim of an open scan, small inside (:func:`border_points`; a point a
   fraction of a spacing inside the rim, whose gap the points between it and the rim hide, is found
   by its one-sided support instead, :mod:`.rim`).
2. **Orientation** (:func:`orient_normals`): Hoppe et al. 1992 (Surface reconstruction from
   unorganized points, §3.3): a minimum spanning tree of the neighbour graph with weights
   ``1 - |n_p . n_q|`` (so that the propagation crosses nearly parallel normals first), walked from
   one root per connected part, flipping each normal to agree with its parent. Kruskal's
   algorithm in numba (the edges in the order of a stable radix sort of their weights, a union-find
   forest) and a breadth-first walk of each part's tree: no sparse matrices are built. The root of a part
   is its highest point, its normal turned up (+z), as in Hoppe; ``"outward"`` turns it away from
   the part's centroid instead (closed scans), and a viewpoint orients every normal towards it
   (a scanner's position) without propagation.
3. **Ambiguity.** A point whose oriented normal agrees clearly (|cos| >= :data:`AGREE_COSINE`)
   with fewer neighbours than disagree with it, or with none, cannot be oriented by its
   neighbourhood (a thin sheet, a fold, a sparse spot); with a viewpoint, a point seen edge-on
   (``|cos| <`` :data:`GRAZING_COSINE`). Such points get a NaN normal and ``Reason.ORIENTATION``
   in an estimate: no guess.
4. ``method="jet"`` (the default): the PCA normals, oriented, then refined by the jet fit that
   :func:`curv.fitted_normals.fitted_normals` uses on meshes (:func:`curv.estimators.jet.fit_jet`).
5. **One pass.** Steps 1 and 4 and the line check of an estimate (:func:`support_spread`) read
   nested supports of the same point (R2 inside R3), so one kernel (:func:`.one_pass._one_pass`) searches
   each point's ball once, at the largest radius, and takes every support from it. It walks the
   points in the grid's cell order and reads their coordinates there (:func:`curv.core.knn.grid_gather`),
   so that neighbours are near in memory; in the cloud's own order (random for a scan saved
   unsorted) every neighbour was a cache miss. The jet is fitted with the unoriented PCA normal
   as its reference: a fit turned the other way is the same fit with its sign changed exactly,
   so the normal is turned afterwards, once the orientation is known.
6. **Grid order.** An estimate of a whole cloud runs on its twin in grid order
   (:func:`grid_ordered`) and maps the rows back: the neighbour graph, the orientation and the
   estimators' kernels then read neighbours that are near in memory too (a cloud saved in random

Modules: :mod:`.frames` (the local frame of one support: moments, PCA, gap, spread),
:mod:`.one_pass` (the pass over every point: :func:`local_frames`, :func:`support_spread`),
:mod:`.orientation` (:func:`orient_normals`), :mod:`.normals` (:func:`point_normals`,
:func:`border_points`, :func:`border_radii`), :mod:`.rim` (one-sided supports on the rim),
:mod:`.grid_order` (:func:`grid_ordered`).
"""

from __future__ import annotations

from .frames import MIN_SPREAD
from .grid_order import grid_ordered
from .normals import (BORDER_GAP, BORDER_RANGE, NORMAL_METHODS, NORMAL_RANGE, ONE_SIDED_GAP, PointNormals, border_points,
                      border_radii, point_normals)
from .one_pass import local_frames, support_spread
from .orientation import AGREE_COSINE, GRAZING_COSINE, orient_normals

__all__ = ["PointNormals", "point_normals", "grid_ordered", "local_frames", "orient_normals", "border_points", "border_radii",
           "support_spread",
           "MIN_SPREAD", "ONE_SIDED_GAP", "BORDER_RANGE",
           "NORMAL_RANGE", "BORDER_GAP", "AGREE_COSINE", "GRAZING_COSINE", "NORMAL_METHODS"]
