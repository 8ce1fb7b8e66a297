"""File to file: ``curv.tiles.estimate_file(IN, OUT, method, range, ...)``, whatever the input's size.

The run (docs/LARGE_SCANS.md):

1. **Plan** (:mod:`curv.tiles.prepare`): scan the input a chunk at a time, cut it into tiles sized
   by point count, write each tile's points into the run's scratch folder.
2. **Tiles** (:mod:`curv.tiles.driver`, :mod:`curv.tiles.tasks`): every unfinished tile estimated
   on its own, here or on a Dask cluster, its rows saved as it finishes. The rows equal the whole
   call's (:mod:`curv.tiles.engine`).
3. **Orientation across tiles** (only for normals oriented ``outward``: :mod:`curv.tiles.orient`).
4. **Output**, written as it is produced and renamed into place when whole: a LAS/LAZ input's
   records with the curvature added as extra bytes (:mod:`curv.formats.laswrite`), a PLY
   (:mod:`curv.tiles.plyout`) or a VTK ``.vtu``/``.vtp`` (:mod:`curv.tiles.vtkout`), in the input's order.

An interrupted run (Ctrl-C, a lost cluster, a crash) leaves no output and keeps the scratch folder:
the same call again resumes from the finished tiles. A finished run removes its scratch folder.
Inputs that cannot be read a chunk at a time (text, PCD, OBJ, an ASCII polygon PLY, a PLY of other
elements or face properties) are read whole and tiled in memory (:func:`curv.tiles.estimate_tiled`).
"""

from __future__ import annotations

import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Generator

import numpy as np

from ..core.errors import CurvError
from ..core.jit import Progress, run_to_end
from ..core.result import Curvature
from ..core.validity import Reason, describe_reasons
from .budget import Budget, default_budget, parse_memory, plan_budget
from .driver import Runner
from .engine import Job, step_redo, whole_step
from .merge import Rows
from .orient import spans_tiles
from .signs import file_part_signs
from .prepare import FileInput, iter_prepare
from .scratch import Scratch
from .sources import open_source
from .tasks import finished_summary, first_halo, iter_file_tile, run_file_tile

__all__ = ["estimate_file", "iter_estimate_file", "FileRun", "OUTPUT_SUFFIXES", "output_suffixes", "default_scratch"]

OUTPUT_SUFFIXES = {".ply": "binary PLY (what curv.save_ply writes), in the input's order",
                   ".las": "the LAS input's records with the curvature as extra bytes",
                   ".laz": "the same, compressed",
                   ".vtu": "VTK XML unstructured grid (the arrays curv.save_vtu writes), raw appended data",
                   ".vtp": "VTK XML poly data (the arrays curv.save_vtp writes), raw appended data"}


@dataclass
class FileRun:
    """What a file-to-file run did (for its summary).

    Attributes
    ----------
    input, output : Path
    points : int
        Points (vertices) estimated.
    mesh : bool
    tiles, resumed : int
        Tiles, and those already finished by an earlier run of the same call.
    where : str
        Where the tiles ran (:attr:`curv.tiles.driver.Runner.where`).
    budget : Budget or None
    reasons : dict
        Points per :class:`curv.Reason` name (:func:`curv.core.validity.describe_reasons`).
    seconds : dict
        ``plan``, ``tiles``, ``write`` and ``total``.
    read, redone : int
        Points the tiles read (their cores and halos, every pass) and core points redone on a wider region.
    label : Curvature
        An empty result naming the estimate (method, range, info).
    """

    input: Path
    output: Path
    points: int
    mesh: bool
    tiles: int
    resumed: int
    where: str
    budget: Budget | None
    reasons: dict
    seconds: dict
    read: int = 0
    redone: int = 0
    label: Curvature | None = field(default=None, repr=False)

    @property
    def valid(self) -> int:
        return int(self.reasons.get("OK", 0))


def default_scratch(output) -> Path:
    """The scratch folder of a run writing ``output``: ``.NAME.tiles`` beside it."""
    output = Path(output)
    return output.parent / f".{output.name}.tiles"


def output_suffixes(input_path) -> list[str]:
    """The outputs a tiled run of ``input_path`` can write, its own kind first: a LAS/LAZ input's
    records again (``.laz``, ``.las``), then ``.ply``, ``.vtu``, ``.vtp`` (:data:`OUTPUT_SUFFIXES`)."""
    records = [".laz", ".las"] if Path(input_path).suffix.lower() in (".las", ".laz") else []
    return records + [s for s in OUTPUT_SUFFIXES if s not in (".las", ".laz")]


def check_output(input_path: Path, output: Path) -> str:
    """The output's suffix if a run can write it from this input (:func:`output_suffixes`), else a
    one-line :class:`CurvError`."""
    suffix = output.suffix.lower()
    if suffix in output_suffixes(input_path):
        return suffix
    if suffix in (".las", ".laz"):
        raise CurvError(f"{output}: a LAS/LAZ output keeps the input's point records; the input must be "
                        f"LAS/LAZ (write .ply instead)")
    raise CurvError(f"{output}: a tiled run writes {', '.join(OUTPUT_SUFFIXES)}; got {suffix or 'no suffix'}")


def _label(job: Job, info: dict) -> Curvature:
    from ..core.ranges import resolve
    from ..estimators import get_spec

    rng = resolve(get_spec(job.method), job.range, job.keywords.get("radius"), job.keywords.get("knn"))
    empty = np.empty(0)
    return Curvature(k1=empty, k2=empty, d1=np.empty((0, 3)), d2=np.empty((0, 3)), normals=np.empty((0, 3)),
                     valid=np.empty(0, bool), method=job.method, range=rng.value,
                     info={**info, "range_label": rng.label})


class _Coordinates:
    """A source's coordinates read in order, block after block (for the PLY writer)."""

    def __init__(self, source):
        self.chunks = source.chunks()
        self.buffer = np.empty((0, 3))
        self.start = 0

    def __call__(self, start: int, stop: int) -> np.ndarray:
        while self.start + self.buffer.shape[0] < stop:
            first, pts, _ = next(self.chunks)
            keep = self.buffer[start - self.start:] if start > self.start else self.buffer
            self.start = first - keep.shape[0]
            self.buffer = np.concatenate([keep, pts])
        out = self.buffer[start - self.start:stop - self.start]
        return out


def iter_estimate_file(input, output, method: str | None = None, range=None, *, tile_size: int | None = None,
                       memory=None, workers: int | None = None, scheduler: str | None = None, client=None,
                       scratch=None, keep_scratch: bool = False, quantity: str = "mean", cmap=None, clim=None,
                       las_extra=(), **keywords) -> Generator[float, None, FileRun]:
    """:func:`estimate_file` step by step: yields :class:`curv.core.jit.Progress` (its ``message``
    names the phase: tiles done, points a second, time left), returns the :class:`FileRun`."""
    t0 = time.perf_counter()
    input_path, output = Path(input), Path(output)
    if method is None:
        from ..estimators import DEFAULT_ESTIMATORS
        from ..io import is_point_file

        method = DEFAULT_ESTIMATORS["points" if is_point_file(input_path) else "mesh"]
    job = Job.checked(method, range, **keywords)
    source = open_source(input_path)
    georeferenced = input_path.suffix.lower() in (".las", ".laz")  # as the LAS reader says (curv.PointCloud)
    if source is not None:
        job = job.for_input(points=not source.is_mesh, georeferenced=georeferenced)
    check_output(input_path, output)
    total = parse_memory(memory) if memory is not None else default_budget()
    if source is None:
        return (yield from _whole(input_path, output, job, tile_size, client, quantity, cmap, clim, las_extra, t0))
    points = not source.is_mesh
    faces_per_vertex = source.n_faces / max(source.n, 1) if source.is_mesh else 0.0
    elsewhere = client is not None or scheduler is not None
    # on a cluster of your own, the budget is one worker's (its workers are yours to size)
    budget = plan_budget(total, job.method, points=points, faces_per_vertex=faces_per_vertex,
                         workers=1 if elsewhere else workers, tile_size=tile_size)
    folder = Scratch(scratch or default_scratch(output))
    identity = folder.identity(input_path, job.call, budget.tile_size)
    resumed = folder.open(identity)
    if resumed:
        prepared = folder.load_plan()
        if hasattr(source, "attach"):
            source.attach(folder.folder)
    else:
        prepared = yield from _phase(iter_prepare(source, folder, budget.tile_size), 0.0, 0.1)
    t_plan = time.perf_counter() - t0
    plan = prepared.plan
    reader = FileInput(folder, prepared, input_path)
    bounds = plan.bounds
    overlap = points and spans_tiles(job, has_normals=source.has_normals)
    halo = first_halo(reader, job, prepared.frame, bounds)
    n_tiles = len(plan.tiles)
    todo = [t.index for t in plan.tiles if not folder.finished(t.index)]
    done_before = n_tiles - len(todo)
    summaries = {t.index: finished_summary(folder, t.index) for t in plan.tiles if t.index not in set(todo)}
    t1 = time.perf_counter()
    with Runner(workers=1 if elsewhere else min(budget.workers, max(1, len(todo))), worker_bytes=budget.worker_bytes,
                scheduler=scheduler, client=client) as runner:
        where = runner.where
        common = (reader, job, prepared.frame, bounds, halo, overlap, georeferenced)
        yield from _run_tiles(runner, todo, common, None, plan, prepared.n, summaries, t1, 0.1, 0.8 if points else 0.85)
        if points:
            # the whole cloud's coordinate step is known once every tile has run: a tile that used
            # another one where it matters runs again with it (curv.tiles.engine.step_redo)
            step = whole_step(summaries.values())
            again = [] if step is None else [t.index for t in plan.tiles if step_redo(summaries[t.index], step)]
            for t in again:
                folder.forget(t)
            yield from _run_tiles(runner, again, common, step, plan, prepared.n, summaries, t1, 0.8, 0.85)
    read = sum(r.get("read", 0) for r in summaries.values())
    redone = sum(r.get("redone", 0) for r in summaries.values())
    info = next((r["info"] for r in summaries.values() if r.get("info")), {})
    reasons = np.zeros(256, np.int64)
    for r in summaries.values():
        reasons[:len(r["reasons"])] += r["reasons"]
    t_tiles = time.perf_counter() - t1
    parts = signs = bad = None
    if overlap:
        parts, signs, bad, was = file_part_signs(folder, len(prepared.plan.tiles), prepared.has_normals,
                                                 job.keywords.get("orient"))
        np.subtract.at(reasons, was, 1)
        reasons[Reason.ORIENTATION] += bad.size
    t2 = time.perf_counter()
    label = _label(job, info)

    def open_rows():
        return Rows(folder, n_tiles, prepared.n, signs=None if signs is None else (parts, signs), undecided_ids=bad)

    if output.suffix.lower() in (".las", ".laz"):
        from ..formats.laswrite import iter_write_las

        yield from _phase(iter_write_las(output, input_path, open_rows().block, groups=tuple(las_extra)), 0.85, 1.0,
                          "writing")
    elif output.suffix.lower() in (".vtu", ".vtp"):
        from .vtkout import iter_write_vtk

        yield from _phase(iter_write_vtk(output, prepared.n, _Coordinates(source), open_rows,
                                         face_blocks=_face_blocks(source) if source.is_mesh else None,
                                         points=points, label=label, quantity=quantity, cmap=cmap, clim=clim,
                                         face_width=prepared.face_width),
                          0.85, 1.0, "writing")
    else:
        from .plyout import iter_write_ply

        yield from _phase(iter_write_ply(output, prepared.n, _Coordinates(source), open_rows,
                                         n_faces=source.n_faces, face_blocks=_face_blocks(source) if source.is_mesh else None,
                                         points=points, label=label, quantity=quantity, cmap=cmap, clim=clim,
                                         face_width=prepared.face_width),
                          0.85, 1.0, "writing")
    t_write = time.perf_counter() - t2
    if not keep_scratch:
        folder.clear()
    named = describe_reasons(np.repeat(np.arange(256, dtype=np.uint8), reasons))
    return FileRun(input_path, output, prepared.n, source.is_mesh, n_tiles, done_before, where, budget, named,
                   {"plan": t_plan, "tiles": t_tiles, "write": t_write, "total": time.perf_counter() - t0},
                   read=read, redone=redone, label=label)


def _face_blocks(source):
    """``face_blocks()`` for the writers: the source's faces in order, (m, k) int blocks, each call a new pass."""

    def faces():
        for _, block in source.face_chunks():
            yield block

    return faces


def _run_tiles(runner, todo, common, step, plan, n, summaries, t1, lo, hi):
    """Run the tiles ``todo`` through ``runner`` with the coordinate ``step`` (None: each measures its
    own), their summaries into ``summaries``; progress (tiles done, points a second, time left) on
    ``lo``..``hi`` of the whole run."""
    if not todo:
        return
    n_tiles = len(plan.tiles)
    tasks = [(t, *common, step) for t in todo]
    run_id = uuid.uuid4().hex[:8]
    keys = [f"curv-tile-{run_id}-{t}" for t in todo]
    todo_points = sum(plan.tiles[t].count for t in todo)
    done_points, count = 0, 0
    rate, left = 0.0, float("nan")
    finished_before = n_tiles - len(todo)
    yield Progress(lo, f"tiles {finished_before}/{n_tiles}")
    for result, partial in runner.iter_run(run_file_tile, tasks, keys=keys, steps=iter_file_tile):
        running = 0.0 if result is not None else plan.tiles[todo[count]].count * partial  # this process's tile
        if result is not None:
            count += 1
            done_points += plan.tiles[result["tile"]].count
            summaries[result["tile"]] = result
            elapsed = time.perf_counter() - t1
            rate = done_points / elapsed if elapsed > 0 else 0.0
            left = (todo_points - done_points) / rate if rate > 0 else float("nan")
        yield Progress(lo + (hi - lo) * (done_points + running) / max(todo_points, 1),
                       f"tiles {finished_before + count}/{n_tiles}, {_rate(rate)} points/s, {_duration(left)} left")


def _phase(gen, lo: float, hi: float, message: str | None = None):
    """Run ``gen`` to its end, its progress mapped onto ``lo``..``hi``; returns its value."""
    while True:
        try:
            step = next(gen)
        except StopIteration as stop:
            return stop.value
        yield Progress(lo + (hi - lo) * float(step), message if message is not None else getattr(step, "message", ""))


def _rate(value: float) -> str:
    if value >= 1e6:
        return f"{value / 1e6:.2f}M"
    if value >= 1e3:
        return f"{value / 1e3:.0f}k"
    return f"{value:.0f}"


def _duration(seconds: float) -> str:
    if not np.isfinite(seconds):
        return "?"
    if seconds >= 3600:
        return f"{seconds / 3600:.1f} h"
    if seconds >= 60:
        return f"{seconds / 60:.1f} min"
    return f"{seconds:.0f} s"


def _whole(input_path, output, job, tile_size, client, quantity, cmap, clim, las_extra, t0):
    """An input read whole (module notes): estimated in memory, tiled when asked."""
    from ..io import load, save_result
    from .memory import iter_estimate_tiled

    shape = load(input_path)
    t_plan = time.perf_counter() - t0
    call = job.call
    if tile_size is not None or client is not None:
        res = yield from iter_estimate_tiled(shape, call.pop("method"), call.pop("range"), tile_size=tile_size or 1_000_000,
                                             client=client, **call)
    else:
        from ..api import iter_estimate

        res = yield from iter_estimate(shape, call.pop("method"), call.pop("range"), **call)
    t1 = time.perf_counter()
    if output.suffix.lower() in (".las", ".laz"):
        from ..formats.laswrite import save_las

        save_las(output, input_path, res, groups=tuple(las_extra))
    else:
        save_result(output, shape, res, quantity=quantity, cmap=cmap, clim=clim)
    t2 = time.perf_counter()
    return FileRun(input_path, output, shape.n_vertices, not hasattr(shape, "n_points"), res.info.get("tiles", 1), 0,
                   "this process", None, describe_reasons(res.reason),
                   {"plan": t_plan, "tiles": t1 - t_plan - t0, "write": t2 - t1, "total": t2 - t0}, label=res)


def estimate_file(input, output, method: str | None = None, range=None, **keywords) -> FileRun:
    """Estimate a file's curvature into another file, tile by tile when it is large (module notes).

    Parameters
    ----------
    input : str or Path
        A point cloud or mesh file: LAS/LAZ and binary PLY (points, triangles or polygons) are read a chunk at
        a time, whatever their size; other formats are read whole.
    output : str or Path
        ``.ply``; ``.las`` or ``.laz`` for a LAS/LAZ input (its records with the curvature as extra
        bytes, :mod:`curv.formats.laswrite`); ``.vtu`` or ``.vtp`` (:mod:`curv.tiles.vtkout`).
    method, range
        As in :func:`curv.estimate`; the default estimator the input kind's
        (:data:`curv.estimators.DEFAULT_ESTIMATORS`).
    tile_size : int, optional
        Points a tile holds at most; default what the memory budget allows each worker.
    memory : str or int, optional
        The budget of the whole run (every process): ``"4GB"``, ``"500MB"`` or bytes; default half
        the machine's total memory (:func:`curv.tiles.budget.default_budget`).
    workers : int, optional
        Processes estimating tiles at once on a local cluster; default the cores the budget can feed.
    scheduler : str, optional
        Run the tiles on the Dask cluster at this address instead (its workers see the scratch folder).
    client : distributed.Client, optional
        The same with a client of your own.
    scratch : str or Path, optional
        The run's scratch folder; default ``.OUTPUT.tiles`` beside the output.
    keep_scratch : bool
        Keep the scratch folder after a finished run.
    quantity, cmap, clim
        What a PLY, VTU or VTP output's colours (and its ``shown`` values) show (:func:`curv.save_ply`).
    las_extra : sequence of str
        LAS/LAZ output: the optional extra-byte groups (``directions``, ``errors``, ``normals``).
    **keywords
        As in :func:`curv.estimate` (not ``vertices=`` or ``smooth=``; ``features=`` an angle).

    Returns
    -------
    FileRun
    """
    return run_to_end(iter_estimate_file(input, output, method, range, **keywords))
