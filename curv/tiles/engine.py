"""One tile: read its region, estimate it, keep the rows whose whole support lay inside, redo the rest.

A tile's **core** is the points the plan gave it (:class:`curv.tiles.plan.TilePlan`); its region
is its box widened by a halo (:class:`curv.tiles.plan.Region`). :func:`iter_run_tile` estimates the
region's points as the whole call would (:mod:`curv.tiles.frame`: the whole input's order and
grid), asks :func:`curv.tiles.reach.support_reach` how far each core point's estimate read, and
keeps the core points whose reach is within their room (their distance to the region's closed
sides): their rows are the whole call's. The others are never kept as they are: they are
estimated again (``vertices=`` those points) on a wider region around them, the halo twice as
wide as their own reach, until every one is kept; a region that reaches every side of the input
holds all of it, so this ends.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Generator

import numpy as np

from ..core.errors import EstimatorError
from ..core.jit import Progress
from ..core.pointcloud import PointCloud
from ..core.validity import Reason
from .frame import GridFrame, framed_cloud, tile_mesh
from .orient import turned
from .plan import Region
from .reach import support_reach

__all__ = ["Job", "Piece", "TileRows", "iter_run_tile", "shape_of", "step_redo", "whole_step", "ROW_FIELDS",
           "empty_rows"]

ROW_FIELDS = ("k1", "k2", "d1", "d2", "normals", "valid", "reason", "k1_se", "k2_se", "part", "rooting")
"""The per-point columns of a result a tile hands back (as :class:`curv.Curvature` names them), and
for the orientation across tiles (:mod:`curv.tiles.orient`) ``part``, the part of the tile's region
each normal was oriented in, and ``rooting``, the normal the propagation turned there (the one a
root is chosen and turned by: :func:`curv.point_normals.spanning_tree`); 0 and NaN where the
normals are decided point by point."""

_RESULT_FIELDS = ROW_FIELDS[:-2]

_TILED_KEYWORDS = {"radius", "knn", "normals", "normal_weighting", "fit_range", "orient", "standard_errors",
                   "features", "block_size"}
"""Keywords of :func:`curv.estimate` a tiled run passes on to every tile."""


@dataclass(frozen=True)
class Job:
    """What every tile estimates: :func:`curv.estimate`'s method, range and keywords.

    ``normals`` may be None, ``"fit"`` or ``"pca"`` (arrays are the input's, handed to each tile
    with its points); ``features`` an angle. What a tile cannot run is refused by :meth:`checked`.
    """

    method: str
    range: object = None
    keywords: dict = field(default_factory=dict)

    @classmethod
    def checked(cls, method: str, range=None, **keywords) -> "Job":
        """A job, or an :class:`EstimatorError` naming what tiles cannot do."""
        from ..core.ranges import resolve
        from ..estimators import get_spec

        spec = get_spec(method)
        resolve(spec, range, keywords.get("radius"), keywords.get("knn"))
        if keywords.get("vertices") is not None:
            raise EstimatorError("a tiled estimate covers every point; estimate a region with curv.estimate(vertices=)")
        if keywords.get("smooth") not in (None, "none"):
            raise EstimatorError("smooth= is not tiled: its smoothing passes reach further with every iteration; "
                                 "estimate such an input whole")
        features = keywords.get("features")
        if features is not None and (isinstance(features, (bool, np.bool_)) or np.ndim(features) != 0):
            raise EstimatorError("a tiled estimate takes features= as an angle (a per-edge mask is numbered by the "
                                 "whole mesh's edges)")
        normals = keywords.get("normals")
        if normals is not None and not isinstance(normals, str):
            raise EstimatorError("a tiled estimate takes normals= as 'fit' or 'pca' (or the input's own normals)")
        for name in ("smooth", "smooth_iterations", "smooth_strength", "vertices"):
            keywords.pop(name, None)
        return cls(method, range, dict(keywords))

    def for_input(self, *, points: bool, georeferenced: bool = False) -> "Job":
        """This job with a point cloud's default orientation made explicit
        (:func:`curv.point_normals.default_orientation` of the whole input: ``"up"`` for a
        georeferenced scan, ``"top"`` otherwise), so that every tile orients as the whole call."""
        if not points or self.keywords.get("orient") is not None:
            return self
        from ..point_normals import default_orientation

        stand_in = PointCloud(np.zeros((1, 3)), georeferenced=georeferenced)
        return Job(self.method, self.range, {**self.keywords, "orient": default_orientation(stand_in)})

    @property
    def call(self) -> dict:
        """The keywords of :func:`curv.iter_estimate` (the method and range included)."""
        return {"method": self.method, "range": self.range, **self.keywords}

    def reach(self, shape, centres) -> np.ndarray:
        """:func:`curv.tiles.reach.support_reach` of this job at ``centres`` of ``shape``."""
        kw = self.keywords
        return support_reach(shape, self.method, self.range, radius=kw.get("radius"), knn=kw.get("knn"),
                             normals=kw.get("normals"), fit_range=kw.get("fit_range", 2),
                             orient=kw.get("orient"), standard_errors=kw.get("standard_errors", False),
                             centres=centres)


@dataclass
class Piece:
    """The points of a region, as a fetch hands them to a tile.

    Attributes
    ----------
    ids : (m,) int64
        The points' numbers in the whole input, ascending.
    points : (m, 3) float64
    normals : (m, 3) float64 or None
        The input's own normals, if it has them.
    faces : (f, k) int64 or None
        A mesh's faces that have a vertex in the region (indices into ``ids``; -1 pads polygons),
        in the whole mesh's order; their other vertices are among ``ids`` too.
    """

    ids: np.ndarray
    points: np.ndarray
    normals: np.ndarray | None = None
    faces: np.ndarray | None = None


Fetch = Callable[[Region], Piece]
"""``fetch(region)``: every point of the input inside ``region`` (a mesh's: and its faces' vertices)."""


@dataclass
class TileRows:
    """The kept rows of a tile: its core points' results, by their numbers in the whole input.

    Attributes
    ----------
    ids : (c,) int64
        Ascending.
    columns : dict
        :data:`ROW_FIELDS` arrays of c rows.
    info : dict
        ``points`` read (core and halo, every pass), ``passes``, ``redone`` (core points estimated
        again on a wider region), ``halo`` (the first pass's), ``seconds``, and the estimate's own
        info entries (its normals' label, ...).
    """

    ids: np.ndarray
    columns: dict
    info: dict


def empty_rows() -> dict:
    return {"k1": np.empty(0), "k2": np.empty(0), "d1": np.empty((0, 3)), "d2": np.empty((0, 3)),
            "normals": np.empty((0, 3)), "valid": np.empty(0, bool), "reason": np.empty(0, np.uint8),
            "k1_se": np.empty(0), "k2_se": np.empty(0), "part": np.empty(0, np.int64), "rooting": np.empty((0, 3))}


def shape_of(piece: Piece, frame: GridFrame | None, *, points: bool, georeferenced: bool = False,
             step: float | None = None):
    """The tile's shape in the whole call's order, and that order (shape row i = piece row order[i]);
    a cloud's ``georeferenced`` and coordinate ``step`` are the whole input's (None: measured)."""
    if points:
        return framed_cloud(piece.points, piece.normals, piece.ids, frame, georeferenced=georeferenced, step=step)
    return tile_mesh(piece.points, piece.faces, piece.ids, frame)


def _steps(shape, job: Job, kept_rows: np.ndarray) -> tuple:
    """``(used, certified, least radius)`` of a cloud's pass: the coordinate step the estimate used,
    the step measured over the kept points' nearest (their neighbours are the whole call's, so the
    smallest over every tile is the whole cloud's :attr:`curv.PointCloud.coordinate_step`), and the
    narrowest radius the quantisation checks compare with the support floor."""
    from ..core.neighbour_graph import neighbour_steps
    from .reach import floored_radii

    nearest = np.full_like(shape.nearest[0], -1)
    nearest[kept_rows] = shape.nearest[0][kept_rows]
    certified = float(neighbour_steps(shape.points, nearest).min()) if kept_rows.size else np.inf
    return float(shape.coordinate_step), certified, float(np.min(floored_radii(shape, job), initial=np.inf))


def _estimate(shape, job: Job, centres) -> Generator[float, None, object]:
    from ..api import iter_estimate

    call = job.call
    return (yield from iter_estimate(shape, call.pop("method"), call.pop("range"), vertices=centres, **call))


def _region_parts(shape, trusted: np.ndarray) -> np.ndarray:
    """(n,) int64: the part of the region each point's normal was oriented in, numbered 0, 1, ...:
    the trees of the propagation's forest (:func:`curv.point_normals.spanning_tree`) cut at every
    edge with an end not ``trusted`` (:func:`curv.tiles.reach.tree_reach` beyond its room). Such an
    edge may be missing from the whole input's neighbour graph (near the region's edge a point links
    to the nearest it has), and a part joined through it may be two parts of the whole call's: at 4M
    terrain points, roofs were turned down with the ground they were joined to. The forest over the
    trusted points is the minimum one of their own edges (:func:`curv.point_normals.keep_tree`), so a
    part of the whole call that the region holds whole is one part here, with the whole call's tree.
    All 0 when no forest was kept."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from ..point_normals import spanning_tree

    tree = spanning_tree(shape)
    n = shape.n_vertices
    if tree is None:
        return np.zeros(n, np.int64)
    ptr, adj, _ = tree
    rows = np.repeat(np.arange(n), np.diff(ptr))
    keep = trusted[rows] & trusted[adj]
    graph = coo_matrix((np.ones(int(keep.sum()), np.int8), (rows[keep], adj[keep])), shape=(n, n)).tocsr()
    return connected_components(graph, directed=False)[1].astype(np.int64)


def _rooting(shape) -> np.ndarray:
    """(n, 3): the normals the region's propagation turned (:func:`curv.point_normals.spanning_tree`),
    NaN when none was kept."""
    from ..point_normals import spanning_tree

    tree = spanning_tree(shape)
    return np.full((shape.n_vertices, 3), np.nan) if tree is None else tree[2]


def _halo_votes(shape, job, region, ids: np.ndarray, core_ids: np.ndarray, normals: np.ndarray, labels: np.ndarray):
    """``(ids, normals, labels)`` of a pass's points outside the tile's core whose normal it decided
    as the whole call does (their reach within the region): they vote on how this tile's parts and
    the others' agree (:func:`curv.tiles.orient.part_signs`). Every pass votes: a narrow first halo
    may decide none, and a redo's wider region then links the tile to its neighbours."""
    from .reach import normal_reach

    at = np.minimum(np.searchsorted(core_ids, ids), max(core_ids.size - 1, 0))
    outside = np.flatnonzero(core_ids[at] != ids) if core_ids.size else np.arange(ids.size)
    reach = normal_reach(shape, fit_range=job.keywords.get("fit_range", 2), orient=job.keywords.get("orient"))
    outside = outside[reach[outside] <= region.room(shape.vertices[outside])]
    return ids[outside], normals[outside], labels[outside]


def _aligned_parts(first: tuple, ids: np.ndarray, normals: np.ndarray, labels: np.ndarray, used: int):
    """A later pass's parts matched to the first pass's: ``(turn (n,), labels (n,), used)``.

    Each part of the later pass follows the first pass's part it shares the strongest vote with
    (their normals at the points both regions hold, as :func:`curv.tiles.orient.part_signs` votes):
    its rows take that part's label and are turned (``turn`` -1) where the two disagree. A part
    that shares no voting point with the first pass takes a label of its own (``used`` onwards).

    Parameters
    ----------
    first : ((m,) int64, (m, 3) float64, (m,) int64)
        The first pass's points (ascending numbers), their normals and part labels.
    ids, normals, labels : (n,) int64, (n, 3) float64, (n,) int64
        This pass's points (numbers), normals and part labels (0 .. P-1), in its shape's order.
    used : int
        Labels given so far.
    """
    from .orient import AGREE

    first_ids, first_normals, first_labels = first
    n_parts = int(labels.max(initial=-1)) + 1
    at = np.minimum(np.searchsorted(first_ids, ids), max(first_ids.size - 1, 0))
    rows = np.flatnonzero(first_ids[at] == ids) if first_ids.size else np.empty(0, np.int64)
    cos = np.einsum("ij,ij->i", normals[rows], first_normals[at[rows]])
    vote = (cos >= AGREE) | (cos <= -AGREE)
    rows, cos = rows[vote], cos[vote]
    width = int(first_labels.max(initial=-1)) + 1
    pairs, inverse = np.unique(labels[rows] * width + first_labels[at[rows]], return_inverse=True)
    yes = np.bincount(inverse, weights=cos >= AGREE, minlength=pairs.size)
    margin = 2.0 * yes - np.bincount(inverse, minlength=pairs.size)
    mine, theirs = pairs // max(width, 1), pairs % max(width, 1)
    strongest = np.lexsort((-np.abs(margin), mine))  # each part's strongest vote first
    lead = strongest[np.unique(mine[strongest], return_index=True)[1]]
    lead = lead[margin[lead] != 0]
    part_label = np.full(n_parts, -1, np.int64)
    part_turn = np.ones(n_parts, np.int64)
    part_label[mine[lead]] = theirs[lead]
    part_turn[mine[lead]] = np.where(margin[lead] > 0, 1, -1)
    alone = np.flatnonzero(part_label < 0)
    part_label[alone] = used + np.arange(alone.size)
    return part_turn[labels], part_label[labels], used + alone.size


def _faceless(piece: Piece, rows: np.ndarray) -> dict:
    """The rows of vertices in a region that no face touches: isolated, as :func:`curv.estimate`
    marks them (DEGENERATE, no normal, NaN)."""
    c = rows.size
    nan3 = np.full((c, 3), np.nan)
    return {"k1": np.full(c, np.nan), "k2": np.full(c, np.nan), "d1": nan3, "d2": nan3.copy(), "normals": nan3.copy(),
            "valid": np.zeros(c, bool), "reason": np.full(c, Reason.DEGENERATE, np.uint8),
            "k1_se": np.full(c, np.nan), "k2_se": np.full(c, np.nan), "part": np.zeros(c, np.int64),
            "rooting": nan3.copy()}


def iter_run_tile(core_ids: np.ndarray, box: tuple, bounds: tuple, fetch: Fetch, job: Job, frame: GridFrame | None,
                  *, halo: float, points: bool, overlap: bool = False, georeferenced: bool = False,
                  step: float | None = None) -> Generator[float, None, TileRows]:
    """Estimate one tile (module notes): yields the fraction done, returns its :class:`TileRows`.

    Parameters
    ----------
    core_ids : (c,) int64
        The tile's points (ascending numbers in the whole input).
    box : ((3,), (3,))
        The tile's box.
    bounds : ((3,), (3,))
        The whole input's least and greatest coordinates.
    fetch : callable
        ``fetch(region) -> Piece``.
    job : Job
    frame : GridFrame or None
        The whole cloud's grid (points), or the whole mesh's locality grid when it is estimated in
        grid order (None: its own order).
    halo : float
        The first pass's halo width.
    points : bool
        The input is a point cloud.
    overlap : bool
        Also hand back the normals of the first pass's halo points (``info["overlap"]``: ids and
        normals), for the orientation across tiles (:mod:`curv.tiles.orient`).
    georeferenced, step : bool, float
        A cloud's: the whole input's flag, and the whole cloud's coordinate step when known (None:
        each pass measures its own and reports it in ``info["steps"]``, :func:`step_redo`).
    """
    t0 = time.perf_counter()
    pending = core = np.asarray(core_ids, np.int64)
    total = max(pending.size, 1)
    lo, hi = (np.asarray(b, np.float64) for b in box)
    h = float(halo)
    ids_out, parts = [], []
    info = {"points": 0, "passes": 0, "redone": 0, "halo": h}
    first, used, seen = None, 0, []  # overlap: the first pass's points by number, normals and parts; parts used
    while pending.size:
        region = Region.around(lo, hi, h, bounds)
        piece = fetch(region)
        info["points"] += int(piece.ids.size)
        info["passes"] += 1
        if info["passes"] > 1:
            info["redone"] += int(pending.size)
        at = np.searchsorted(piece.ids, pending)
        if not (at < piece.ids.size).all() or not np.array_equal(piece.ids[np.minimum(at, piece.ids.size - 1)], pending):
            raise RuntimeError("a tile's region does not hold its own points (the fetch and the plan disagree)")
        if not points and (piece.faces is None or piece.faces.size == 0):
            ids_out.append(pending)
            parts.append(_faceless(piece, pending))
            break
        shape, order = shape_of(piece, frame, points=points, georeferenced=georeferenced, step=step)
        rank = np.empty(order.size, np.int64)
        rank[order] = np.arange(order.size)
        centres = rank[at]  # the pending points' rows of the shape
        whole = 2 * centres.size >= shape.n_vertices
        done_before = 1.0 - pending.size / total
        trusted = None
        if overlap:
            from ..point_normals import keep_tree
            from .reach import tree_reach

            # its parts are turned one by one (curv.tiles.orient), each a tree of the whole call's edges
            trusted = tree_reach(shape, fit_range=job.keywords.get("fit_range", 2)) <= region.room(shape.vertices)
            keep_tree(shape, trusted)
        gen = _estimate(shape, job, None if whole else np.sort(centres))
        while True:
            try:
                progress = next(gen)
            except StopIteration as stop:
                res = stop.value
                break
            yield Progress(done_before + (1.0 - done_before) * 0.9 * float(progress), getattr(progress, "message", ""))
        if not info.get("estimate_info"):
            info["estimate_info"] = {k: v for k, v in res.info.items() if isinstance(v, (str, int, float, bool))}
        labels = turn = None
        if overlap:
            ids_here = piece.ids[order]
            labels = _region_parts(shape, trusted)
            normals_here = np.asarray(res.normals)
            if info["passes"] == 1:
                by_id = np.argsort(ids_here)
                first = (ids_here[by_id], normals_here[by_id], labels[by_id])
                used = int(labels.max(initial=-1)) + 1
            else:
                # another region's trees: each of its parts is turned to agree with the first pass's
                turn, labels, used = _aligned_parts(first, ids_here, normals_here, labels, used)
                normals_here = normals_here * turn[:, None]
            seen.append(_halo_votes(shape, job, region, ids_here, core, normals_here, labels))
        reach = job.reach(shape, centres)
        room = region.room(shape.vertices[centres])
        kept = reach <= room
        rows = centres[kept]
        if points:
            info.setdefault("steps", []).append(_steps(shape, job, rows))
        ids_out.append(pending[kept])
        columns = {name: np.asarray(getattr(res, name))[rows] for name in _RESULT_FIELDS}
        columns["part"] = np.zeros(rows.size, np.int64) if labels is None else labels[rows]
        columns["rooting"] = np.full((rows.size, 3), np.nan) if labels is None else _rooting(shape)[rows]
        if turn is not None:
            over = np.flatnonzero(turn[rows] < 0)
            flipped = turned({name: values[over] for name, values in columns.items()})
            for name, values in flipped.items():
                columns[name][over] = values
        parts.append(columns)
        failing = ~kept
        if not failing.any():
            break
        # the rest again, on a region around them twice as wide as the widest of their reaches
        far = shape.vertices[centres[failing]]
        lo, hi = far.min(axis=0), far.max(axis=0)
        wanted = reach[failing]
        h = max(2.0 * h, 2.0 * float(np.max(wanted[np.isfinite(wanted)], initial=0.0)))
        if not np.isfinite(wanted).all() or region.everything:
            h = np.inf
        pending = pending[failing]
        del shape, res, piece
    if seen:
        halo_ids = np.concatenate([v[0] for v in seen])
        by_id = np.argsort(halo_ids, kind="stable")
        info["overlap"] = tuple(np.concatenate([v[k] for v in seen])[by_id] for k in range(3))
    ids = np.concatenate(ids_out) if ids_out else np.empty(0, np.int64)
    sort = np.argsort(ids, kind="stable")
    columns = {name: np.concatenate([p[name] for p in parts])[sort] for name in parts[0]} if parts else empty_rows()
    info["seconds"] = time.perf_counter() - t0
    yield Progress(1.0)
    return TileRows(ids[sort], columns, info)


def whole_step(infos) -> float | None:
    """The whole cloud's coordinate step from its tiles' infos (the smallest certified step of any
    pass), or None for a mesh."""
    certified = [c for info in infos for _, c, _ in info.get("steps", ())]
    return min(certified) if certified else None


def step_redo(info: dict, step: float) -> bool:
    """Whether a tile must run again with the whole cloud's coordinate ``step``: some pass used
    another step and a radius the quantisation checks read lies between the two support floors
    (only then can a decision differ; on coordinates of full precision both floors are far below
    every radius)."""
    from ..point_normals import MIN_SUPPORT_STEPS

    for used, _, least in info.get("steps", ()):
        if used != step and MIN_SUPPORT_STEPS * max(used, step) > least:
            return True
    return False
