"""Tiles over an input held in memory: the same engine as a file's, without the files.

:func:`estimate_tiled` cuts a :class:`curv.PointCloud` or :class:`curv.Mesh` into tiles
(:mod:`curv.tiles.plan`), estimates each with :func:`curv.tiles.engine.iter_run_tile` (here, or on
a Dask cluster when given a ``client``) and puts the kept rows together: a :class:`curv.Curvature`
equal to ``curv.estimate``'s (module notes of :mod:`curv.tiles.frame` say where to rounding). It is
how the tests check the engine on inputs of every kind, and what the viewer's region and a
library user with a large array in memory can call.
"""

from __future__ import annotations

import time
from typing import Generator

import numpy as np

from ..core.jit import Progress, run_to_end
from ..core.mesh import Mesh
from ..core.result import Curvature
from ..core.support import support_of
from .engine import ROW_FIELDS, Job, Piece, TileRows, iter_run_tile, step_redo, whole_step
from .orient import Overlap, Parts, disagreeing, group_roots, part_signs, spans_tiles, turned, undecided
from .frame import GridFrame, frame_of
from .plan import Histogram, Region, TilePlan, plan_tiles

__all__ = ["estimate_tiled", "iter_estimate_tiled", "plan_for", "halo_for", "InMemoryInput"]


class InMemoryInput:
    """An input held in memory, answering the engine's region fetches (a mask over every point)."""

    def __init__(self, shape, normals: np.ndarray | None = None):
        self.shape = shape
        self.points = np.asarray(shape.vertices)
        self.cloud = support_of(shape).kind == "points"  # a tile of it is a cloud of its own (curv.tiles.frame)
        own = shape.normals if self.cloud else None
        self.normals = own if normals is None else np.asarray(normals, np.float64)
        if not self.cloud:
            self.faces = shape.faces if not shape.is_triangular else shape.face_indices.reshape(-1, 3)

    def fetch(self, region: Region) -> Piece:
        inside = region.contains(self.points)
        if self.cloud:
            ids = np.flatnonzero(inside)
            return Piece(ids, self.points[ids], None if self.normals is None else self.normals[ids])
        faces = self.faces
        touched = np.where(faces >= 0, inside[np.maximum(faces, 0)], False).any(axis=1)
        kept = faces[touched]
        used = np.zeros(self.points.shape[0], bool)
        used[kept[kept >= 0]] = True
        ids = np.flatnonzero(used | inside)
        local = np.searchsorted(ids, np.maximum(kept, 0))
        local = np.where(kept >= 0, local, -1)
        return Piece(ids, self.points[ids], None, local)


def plan_for(points: np.ndarray, tile_size: int) -> TilePlan:
    """The tiles of ``points`` (n, 3) held in memory (:func:`curv.tiles.plan.plan_tiles`)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    hist = Histogram.over(lo, hi)
    hist.add(points)
    return plan_tiles(hist, int(tile_size), (lo, hi))


def halo_for(shape, job: Job, sample: int = 20000) -> float:
    """A first halo width for every tile: twice the 99th percentile of the reach of the points of one
    window (about ``sample`` points around the input's median point). Where a tile needs more, its
    engine redoes those points (:mod:`curv.tiles.engine`); this only sets how often."""
    points = np.asarray(shape.vertices)
    n = points.shape[0]
    if n <= sample:
        reach = job.reach(shape, None)
    else:
        centre = np.median(points[:: max(1, n // 4096)], axis=0)
        near = np.argpartition(np.linalg.norm(points - centre, axis=1), sample)[:sample]
        from .engine import shape_of

        source = InMemoryInput(shape)
        window = source.fetch(Region.around(points[near].min(axis=0), points[near].max(axis=0), 0.0,
                                            (points.min(axis=0), points.max(axis=0))))
        part, _ = shape_of(window, frame_of(points) if source.cloud else None, points=source.cloud)
        reach = job.reach(part, None)
    finite = reach[np.isfinite(reach)]
    return 2.0 * float(np.percentile(finite, 99)) if finite.size else 0.0


def iter_estimate_tiled(shape, method: str | None = None, range=None, *, tile_size: int = 1_000_000,
                        halo: float | None = None, client=None, normals=None,
                        **keywords) -> Generator[float, None, Curvature]:
    """:func:`estimate_tiled` step by step: yields the fraction done, returns the :class:`Curvature`."""
    from ..convert import as_input
    from ..estimators import default_estimator

    shape = as_input(shape)
    if method is None:
        method = default_estimator(shape)
    array_normals = normals if normals is not None and not isinstance(normals, str) else None
    if array_normals is not None:
        array_normals = np.asarray(array_normals, np.float64)
        if array_normals.shape != (shape.n_vertices, 3):
            from ..core.errors import MeshError

            raise MeshError(f"normals must have shape ({shape.n_vertices}, 3), got {array_normals.shape}")
    job = Job.checked(method, range, **({} if array_normals is not None else {"normals": normals}), **keywords)
    source = InMemoryInput(shape, array_normals)
    if array_normals is not None and not source.cloud:
        from ..core.errors import EstimatorError

        raise EstimatorError("a tiled estimate of a mesh takes normals= as 'fit' (or its own Max normals)")
    points = source.points
    plan = plan_for(points, tile_size)
    tile_of = plan.tile_of(points)
    cloud = source.cloud
    georeferenced = bool(getattr(shape, "georeferenced", False))
    job = job.for_input(points=cloud, georeferenced=georeferenced)
    frame = frame_of(points) if cloud else _mesh_frame(shape)
    if halo is None:
        halo = halo_for(shape, job)
    n = points.shape[0]
    out = _Assembly(n, len(plan.tiles))
    t0 = time.perf_counter()
    yield Progress(0.0)
    tasks = [(t.index, np.flatnonzero(tile_of == t.index), (t.lo, t.hi)) for t in plan.tiles]
    overlap = cloud and spans_tiles(job, has_normals=source.normals is not None)
    settings = dict(halo=halo, points=cloud, overlap=overlap, georeferenced=georeferenced)
    yield from _run_tiles(tasks, plan, source, job, frame, settings, client, out, None, 0.0, 0.95 if cloud else 1.0)
    if cloud:
        # the whole cloud's coordinate step is known once every tile has run: a tile that used
        # another one where it matters runs again with it (curv.tiles.engine.step_redo)
        step = whole_step(out.infos)
        again = [] if step is None else [task for task in tasks if step_redo(out.infos[task[0]], step)]
        if again:
            yield from _run_tiles(again, plan, source, job, frame, settings, client, out, step, 0.95, 1.0)
    if overlap:
        out.orient(tile_of, points, len(plan.tiles), job.keywords.get("orient"))
    return out.result(job, shape, time.perf_counter() - t0, len(plan.tiles))


def _run_tiles(tasks, plan, source, job, frame, settings, client, out, step, lo, hi):
    """Run ``tasks`` (index, core, box), here or on ``client``, into ``out``; progress on ``lo``..``hi``."""
    if client is None:
        for i, (index, core, box) in enumerate(tasks):
            gen = iter_run_tile(core, box, plan.bounds, source.fetch, job, frame, step=step, **settings)
            while True:
                try:
                    progress = next(gen)
                except StopIteration as stop:
                    out.add(index, stop.value)
                    break
                yield Progress(lo + (hi - lo) * (i + float(progress)) / len(tasks), getattr(progress, "message", ""))
        return
    import uuid

    from .driver import Runner

    shared = client.scatter(source, broadcast=True)  # the input travels to each worker once, not per tile
    run_id = uuid.uuid4().hex[:8]
    calls = [(index, core, box, plan.bounds, shared, job, frame, step, settings) for index, core, box in tasks]
    # through the driver's runner: a tile that keeps failing, or a cluster left without workers, ends
    # the call in one line (curv.tiles.driver) instead of waiting forever
    runner = Runner(client=client)
    results = runner.iter_run(_run_tile_task, calls, keys=[f"curv-tile-{run_id}-{call[0]}" for call in calls])
    for done, (result, _) in enumerate(results, 1):
        out.add(*result)
        yield Progress(lo + (hi - lo) * done / len(tasks))


def _run_tile_task(index, core, box, bounds, source, job, frame, step, settings) -> tuple[int, TileRows]:
    return index, run_to_end(iter_run_tile(core, box, bounds, source.fetch, job, frame, step=step, **settings))


def _mesh_frame(mesh: Mesh) -> GridFrame | None:
    """The whole mesh's locality grid when a whole-mesh estimate runs in grid order, else None."""
    return frame_of(mesh.vertices) if mesh.scattered_order() else None


class _Assembly:
    """The whole input's result columns, filled tile by tile."""

    def __init__(self, n: int, n_tiles: int):
        self.n = n
        self.k1, self.k2 = np.full(n, np.nan), np.full(n, np.nan)
        self.d1, self.d2, self.normals = (np.full((n, 3), np.nan) for _ in range(3))
        self.valid = np.zeros(n, bool)
        self.reason = np.zeros(n, np.uint8)
        self.k1_se, self.k2_se = np.full(n, np.nan), np.full(n, np.nan)
        self.part = np.zeros(n, np.int64)
        self.rooting = np.full((n, 3), np.nan)
        self.filled = np.zeros(n, bool)
        self.infos = [{} for _ in range(n_tiles)]

    def add(self, index: int, rows: TileRows) -> None:
        """Tile ``index``'s rows (again, for a tile run a second time)."""
        for name, values in rows.columns.items():
            getattr(self, name)[rows.ids] = values
        self.filled[rows.ids] = True
        self.infos[index] = rows.info

    def columns(self, rows) -> dict:
        return {name: getattr(self, name)[rows] for name in ROW_FIELDS}

    def put(self, rows, columns: dict) -> None:
        for name, values in columns.items():
            getattr(self, name)[rows] = values

    def orient(self, tile_of: np.ndarray, points: np.ndarray, n_tiles: int, orient: str) -> None:
        """Turn the tiles' parts so that they agree on their overlaps (:mod:`curv.tiles.orient`)."""
        overlaps = [Overlap(t, *info["overlap"]) for t, info in enumerate(self.infos) if "overlap" in info]
        counts = np.zeros(n_tiles, np.int64)
        np.maximum.at(counts, tile_of, self.part + 1)
        for ov in overlaps:  # a part of a region may hold halo points only
            counts[ov.tile] = max(counts[ov.tile], int(ov.parts.max(initial=-1)) + 1)
        parts = Parts(counts)
        node = parts.of(tile_of, self.part)

        def owner_of(ids):
            return node[ids]

        def normal_of(ids):
            return self.normals[ids]

        def roots(group):
            return group_roots(group, orient, lambda: iter([(node, points, self.rooting)]))

        signs = part_signs(parts, lambda: iter(overlaps), owner_of, normal_of, roots)
        bad = disagreeing(lambda: iter(overlaps), parts, signs, owner_of, normal_of)
        flip = np.flatnonzero(signs[node] < 0)
        self.put(flip, turned(self.columns(flip)))
        self.put(bad, undecided(self.columns(bad)))

    def result(self, job: Job, shape, seconds: float, tiles: int) -> Curvature:
        if not self.filled.all():
            raise RuntimeError(f"{int((~self.filled).sum())} points were in no tile (a bug in the plan)")
        from ..core.ranges import resolve
        from ..estimators import get_spec

        rng = resolve(get_spec(job.method), job.range, job.keywords.get("radius"), job.keywords.get("knn"))
        first = self.infos[0].get("estimate_info", {}) if self.infos else {}
        info = {**first, "seconds": seconds, "tiles": tiles, "region": self.n,
                "tile_points": int(sum(i["points"] for i in self.infos)),
                "redone": int(sum(i["redone"] for i in self.infos))}
        for key in ("border_points", "coincident_points", "ambiguous_normals", "one_sided_normals"):
            info.pop(key, None)  # whole-input counts a tile cannot give (the reason codes count them)
        return Curvature(k1=self.k1, k2=self.k2, d1=self.d1, d2=self.d2, normals=self.normals, valid=self.valid,
                         reason=self.reason, method=job.method, range=rng.value, info=info,
                         k1_se=self.k1_se, k2_se=self.k2_se)


def estimate_tiled(shape, method: str | None = None, range=None, *, tile_size: int = 1_000_000,
                   halo: float | None = None, client=None, **keywords) -> Curvature:
    """Estimate an input held in memory tile by tile: the same :class:`Curvature` as
    :func:`curv.estimate` (:mod:`curv.tiles`' notes say where it is equal to rounding).

    Parameters
    ----------
    shape : Mesh, PointCloud, or what :func:`curv.estimate` takes
        Other libraries' meshes and clouds (trimesh, pyvista, meshio, an (n, 3) array) through
        :func:`curv.convert.as_input`.
    method, range, **keywords
        As in :func:`curv.estimate`, the default estimator the input kind's (not ``vertices=`` or
        ``smooth=``; ``features=`` an angle).
    tile_size : int
        Points (vertices) per tile, at most about.
    halo : float, optional
        The first halo width in the input's units; default from the reach of a window of points
        (:func:`halo_for`). Any width gives the same result: a narrower one only makes the engine
        redo more points.
    client : distributed.Client, optional
        Run the tiles on this Dask cluster (the input is sent to each worker once).
    """
    return run_to_end(iter_estimate_tiled(shape, method, range, tile_size=tile_size, halo=halo, client=client,
                                          **keywords))
