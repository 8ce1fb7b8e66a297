"""How far an estimate at a point reads: the one owner of that question, asking the owners of each part.

An estimate at p depends on the positions (and, on a mesh, the faces) of other points through a
chain of balls: its support (:func:`curv.core.ranges.ball_radii`), the normals of the support's
points (each from its own fit and frames, :mod:`curv.point_normals`), the spacing of every point
involved (its nearest neighbours, :mod:`curv.core.knn`), on a mesh each vertex's 1-ring (its
normal, its flags, its longest edge) and the noise level pooled over edge neighbours
(:mod:`curv.uncertainty.pooling`). The **reach** of p is the largest ``|q - p| + r`` over every
ball ``B(q, r)`` that chain reads: every point whose data can change p's result lies within it.

A tile (:mod:`curv.tiles.engine`) holds every point of its region; a point's result there equals
the whole input's when its reach, computed *in the tile*, is at most its distance to the region's
edge (its room). The computation is its own certificate: each term of the chain is exact when the
balls before it lie inside the region (a kNN distance found inside a ball that lies inside the
region is the true one, and so on outwards), and every term enters the maximum, so a reach at most
the room proves each of them exact. Where it is larger the point is redone on a wider region.

The rule per input:

* **Points** (``spacing`` = distance to the 6th nearest, ``G`` = :data:`curv.core.neighbour_graph.GRAPH_NEIGHBOURS`):
  ``knn(q)`` = distance to q's G-th nearest (spacing, neighbours, coincidence);
  ``calm(q)`` = the largest ``|j - q| + knn(j)`` over q and its G nearest (the border test's unit
  reads the neighbours' spacings, :func:`curv.point_normals.border_radii`);
  ``own(q)`` = the largest of ``calm(q)``, the border test's ball (:data:`~curv.point_normals.BORDER_RANGE`;
  where q's angular gap sends it to the one-sided test, that test's ball, twice as wide:
  :func:`curv.point_normals.border_test_radii`),
  the normals' fit ball (``fit_range``, at least :func:`curv.point_normals.support_floor`) and
  the line check's balls at
  :data:`~curv.point_normals.NORMAL_RANGE`: everything q's normal and flags read;
  with an orientation by rule (up, the spanning trees), which checks a normal against its G
  nearest's, ``own(q)`` also takes ``|j - q| + own(j)`` over them;
  ``reach(p)`` = the largest of ``own(p)``, the support radius and, for the estimators that read
  their neighbours' normals (``an``, ``mru``: the neighbours' normals and the line check over
  usable neighbours), ``|q - p| + own(q)`` over the support.
  Normals oriented up or towards a viewpoint are decided point by point; the spanning-tree
  orientation (``orient="outward"``) is global and is made consistent across tiles separately
  (:mod:`curv.tiles.orient`).
* **Meshes** (``L(q)`` = the longest edge of q's 1-ring: a vertex's normal, flags and ring are
  exact when its faces are all in the tile): ``chain(q)`` = ``L(q)``, or with fitted normals the
  largest ``|j - q| + L(j)`` over the fit's ball; ``reach0(p)`` = the largest of the support radius
  (the 1-ring for ``meyer`` and ``ru``) and ``|q - p| + chain(q)`` over the support's ball (the
  walk stays inside it; faces crossing the sphere reach one edge beyond); with pooled standard
  errors ``reach(p)`` also takes ``|j - p| + reach0(j)`` over p's edge neighbours j.

The maxima over a ball run in one numba kernel over the points in their grid (:func:`ball_max`).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit_parallel, launch, prange, slice_bounds, threads
from ..core.grid import build_grid
from ..core.grid_balls import grid_ball
from ..core.neighbour_graph import GRAPH_NEIGHBOURS
from ..core.mesh import Mesh
from ..core.pointcloud import PointCloud
from ..core.support import support_of
from ..core.ranges import Range, ball_radii, resolve
from ..estimators import get_spec
from ..geometry.neighbourhood import latest_with_mesh, new_queues

__all__ = ["ball_max", "point_reach", "normal_reach", "tree_reach", "floored_radii", "mesh_reach", "support_reach"]


@jit_parallel
def _ball_max_kernel(centres, radii, values, cells, coords, x, y, z, queues, out):
    parts = queues.shape[0]
    for t in prange(parts):
        queue = queues[t]
        start, stop = slice_bounds(0, centres.size, t, parts)
        for i in range(start, stop):
            p = centres[i]
            r = radii[p]
            best = max(r, values[p])
            if not (r >= 0.0) or not math.isfinite(best):
                out[i] = math.inf
                continue
            count = grid_ball(p, r * r, cells, coords, x, y, z, queue)
            for j in range(1, count):
                q = queue[j]
                dx, dy, dz = x[q] - x[p], y[q] - y[p], z[q] - z[p]
                best = max(best, math.sqrt(dx * dx + dy * dy + dz * dz) + values[q])
            out[i] = best


def ball_max(points: np.ndarray, radii: np.ndarray, values: np.ndarray, centres: np.ndarray | None = None) -> np.ndarray:
    """For each centre p: the largest of ``radii[p]``, ``values[p]`` and ``|q - p| + values[q]`` over
    the points q within ``radii[p]`` of p (inf where a radius or value is not finite).

    Parameters
    ----------
    points : (n, 3) float64
    radii, values : (n,) float64
    centres : (c,) int64, optional
        Default every point.

    Returns
    -------
    (c,) float64, or (n,) without ``centres``.
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    n = points.shape[0]
    centres = np.arange(n, dtype=np.int64) if centres is None else np.ascontiguousarray(centres, dtype=np.int64)
    radii = np.ascontiguousarray(radii, dtype=np.float64)
    values = np.ascontiguousarray(values, dtype=np.float64)
    out = np.empty(centres.size)
    if centres.size == 0:
        return out
    finite = radii[centres][np.isfinite(radii[centres])]
    r = float(np.median(finite)) if finite.size else 0.0
    cell = 1.25 * r if r > 0 else None
    cells, coords = build_grid(points, cell=cell)
    x, y, z = (np.ascontiguousarray(points[:, c]) for c in range(3))
    parts = max(1, min(threads(), centres.size))
    launch(_ball_max_kernel, centres, radii, values, cells, coords, x, y, z, new_queues(n, parts), out)
    return out


# --- point clouds -------------------------------------------------------------------------------

def _knn_reach(cloud: PointCloud) -> np.ndarray:
    """(n,) distance to each point's G-th nearest: the ball its nearest-neighbour search reads."""
    return np.asarray(cloud.kth_distance(GRAPH_NEIGHBOURS), dtype=np.float64)


def _calm_reach(cloud: PointCloud, knn: np.ndarray) -> np.ndarray:
    """(n,) the largest ``|j - q| + knn(j)`` over q and its G nearest j."""
    indices, distances = cloud.nearest
    found = indices >= 0
    through = np.where(found, distances + knn[np.maximum(indices, 0)], 0.0)
    return np.maximum(knn, through.max(axis=1) if through.shape[1] else knn)


def _normal_ranges(fit_range) -> list:
    """The ranges of the balls a point's normal and flags read: the fit's, the border test's and
    the line checks' at the default range (:mod:`curv.point_normals`)."""
    from ..point_normals import BORDER_RANGE, NORMAL_RANGE

    jet = get_spec("jet")
    return [(resolve(jet, fit_range), False), (resolve(jet, NORMAL_RANGE), False), (resolve(jet, NORMAL_RANGE), True),
            (resolve(jet, BORDER_RANGE), False)]


def _own_reach(cloud: PointCloud, fit_range) -> np.ndarray:
    """(n,) what a point's own normal, border test and line checks read (module notes, ``own``)."""
    from ..point_normals import border_test_radii, support_floor

    knn = _knn_reach(cloud)
    own = _calm_reach(cloud, knn)
    # on coordinates stored on a coarse grid the normals are fitted over at least this radius
    np.maximum(own, support_floor(cloud), out=own)
    # the border flag's balls: the gap test's (BORDER_RANGE times the calm spacing; the plain R3
    # ball is below it) and, where the gap is wide, the one-sided test's, twice as wide
    np.maximum(own, border_test_radii(cloud), out=own)
    for rng, uses_normals in _normal_ranges(fit_range):
        np.maximum(own, ball_radii(cloud, rng, uses_normals=uses_normals), out=own)
    return own


def _with_neighbours(cloud: PointCloud, own: np.ndarray) -> np.ndarray:
    """(n,) the largest of ``own[q]`` and ``|j - q| + own[j]`` over q's G nearest j: a normal whose
    orientation is checked against its nearest points' normals reads theirs."""
    indices, distances = cloud.nearest
    through = np.where(indices >= 0, distances + own[np.maximum(indices, 0)], 0.0)
    return np.maximum(own, through.max(axis=1) if through.shape[1] else own)


def normal_reach(cloud: PointCloud, *, fit_range=2, orient="up") -> np.ndarray:
    """(n,) how far what decides each point's normal and flags reads (module notes, ``own``; with an
    orientation by rule, its nearest points' too): a normal whose reach is within its room is the
    whole call's."""
    by_rule = isinstance(orient, str)

    def build():
        own = _own_reach(cloud, fit_range)
        return _with_neighbours(cloud, own) if by_rule else own

    # a tile asks twice for one region (the halo's votes, then its core's reach): 0.5 s of 8.9 at 1M
    return latest_with_mesh(cloud, "normal reach", (fit_range, by_rule), build)


def tree_reach(cloud: PointCloud, *, fit_range=2) -> np.ndarray:
    """(n,) how far what places a point in the orientation's spanning tree reads: its nearest (the
    neighbour graph's edges), their spacings (the calm spacing) and the ball of its unoriented
    normal (the border test's PCA, or a PCA at ``fit_range``, at least the support floor). Where
    it is within a region's room, the point's edges and their weights are the whole call's
    (:func:`curv.point_normals.keep_tree`)."""
    from ..point_normals import border_radii, support_floor

    reach = _calm_reach(cloud, _knn_reach(cloud))
    np.maximum(reach, border_radii(cloud), out=reach)
    np.maximum(reach, support_floor(cloud), out=reach)
    np.maximum(reach, ball_radii(cloud, resolve(get_spec("jet"), fit_range), uses_normals=False), out=reach)
    return reach


def floored_radii(cloud: PointCloud, job) -> np.ndarray:
    """(n,) the narrower of the two radii the quantisation checks compare with
    :func:`curv.point_normals.support_floor` at each point: the normals' fit and the estimate's
    support (a :class:`curv.tiles.engine.Job`)."""
    spec = get_spec(job.method)
    kw = job.keywords
    fit = ball_radii(cloud, resolve(get_spec("jet"), kw.get("fit_range", 2)), uses_normals=False)
    rng = resolve(spec, job.range, kw.get("radius"), kw.get("knn"))
    return np.minimum(fit, ball_radii(cloud, rng, uses_normals=spec.uses_normals))


def point_reach(cloud: PointCloud, method: str, rng: Range, *, fit_range=2, orient="up", centres=None) -> np.ndarray:
    """(c,) reach of an estimate of ``method`` at range ``rng`` at each centre of a point cloud
    (module notes), in the cloud's units; every point without ``centres``.

    ``fit_range`` is the range of the estimated normals; the file's normals read nothing, but the
    border test and line checks still run, so it enters either way (a wider bound, never a narrower).
    An orientation by rule (``"up"``, and the spanning trees) checks each normal against its nearest
    points' normals: their reach enters too; a viewpoint decides each normal alone.
    """
    spec = get_spec(method)
    own = normal_reach(cloud, fit_range=fit_range, orient=orient)
    radii = ball_radii(cloud, rng, uses_normals=spec.uses_normals)
    centres = np.arange(cloud.n_points, dtype=np.int64) if centres is None else np.asarray(centres, np.int64)
    if spec.uses_normals:
        return ball_max(cloud.points, radii, own, centres)
    return np.maximum(own[centres], radii[centres])


# --- meshes -------------------------------------------------------------------------------------

def _ring_values(mesh: Mesh, values: np.ndarray) -> np.ndarray:
    """(n,) the largest of ``values[p]`` and ``|j - p| + values[j]`` over p's edge neighbours j."""
    indptr, ring = mesh.neighbour_lists
    rows = np.repeat(np.arange(mesh.n_vertices), np.diff(indptr))
    through = np.linalg.norm(mesh.vertices[ring] - mesh.vertices[rows], axis=1) + values[ring]
    out = np.asarray(values, dtype=np.float64).copy()
    np.maximum.at(out, rows, through)
    return out


def mesh_reach(mesh: Mesh, method: str, rng: Range | None, *, fitted_normals: bool = False, fit_range=2,
               pooled: bool = False, centres=None) -> np.ndarray:
    """(c,) reach of an estimate of ``method`` at range ``rng`` on a mesh (module notes).

    Parameters
    ----------
    fitted_normals : bool
        The normals are local jet fits at ``fit_range`` (``normals="fit"``).
    pooled : bool
        The standard errors pool the noise level over edge neighbours (the fits ``nc``, ``qs``,
        ``an``, ``mru`` with ``standard_errors=True``).
    """
    spec = get_spec(method)
    n = mesh.n_vertices
    longest = np.asarray(mesh.longest_edge, dtype=np.float64)
    chain = longest
    if fitted_normals:
        fit = ball_radii(mesh, resolve(get_spec("jet"), fit_range), uses_normals=False)
        chain = ball_max(mesh.vertices, fit, longest)
    if spec.has_support:
        radii = ball_radii(mesh, rng, uses_normals=spec.uses_normals)
    else:  # the fixed 1-ring formulas read their ring and its vertices' normals
        radii = longest
    if pooled:  # a centre's reach takes its ring's: every vertex's is needed
        reach = _ring_values(mesh, ball_max(mesh.vertices, radii, chain))
        return reach if centres is None else reach[np.asarray(centres, np.int64)]
    return ball_max(mesh.vertices, radii, chain, None if centres is None else np.asarray(centres, np.int64))


def support_reach(shape, method: str, range=None, *, radius=None, knn=None, normals=None, fit_range=2,
                  orient=None, standard_errors: bool = False, centres=None) -> np.ndarray:
    """How far an estimate ``curv.estimate(shape, method, range, ...)`` at each point reads (module notes).

    Parameters
    ----------
    shape : Mesh or PointCloud
    method, range, radius, knn, normals, fit_range, orient, standard_errors
        As in :func:`curv.estimate`.
    centres : (c,) int, optional
        Only these points; default every point.

    Returns
    -------
    (c,) or (n,) float64
        In the shape's units; inf where a support has no finite radius (fewer points than ``knn``).
    """
    spec = get_spec(method)
    rng = resolve(spec, range, radius, knn)
    if support_of(shape).kind == "points":
        if orient is None:
            from ..point_normals import default_orientation

            orient = default_orientation(shape)
        return point_reach(shape, method, rng, fit_range=fit_range, orient=orient, centres=centres)
    fitted = isinstance(normals, str) and normals == "fit"
    return mesh_reach(shape, method, rng if spec.has_support else None, fitted_normals=fitted, fit_range=fit_range,
                      pooled=bool(standard_errors and spec.pools_errors), centres=centres)
