"""What one worker does for one tile of a file: read its region, run the engine, save its rows.

:func:`run_file_tile` is the task a cluster runs (it needs only the scratch folder, which every
worker sees, and its arguments). It writes the tile's rows (and, for an orientation across
tiles, its halo normals) under temporary names and renames them: a tile whose ``rows`` file
exists is finished, and a task killed half way leaves nothing the run would take for a result.
A task for a finished tile returns at once, so a resumed run and a retried task cost nothing twice.
"""

from __future__ import annotations

import numpy as np

from ..core.jit import run_to_end
from .engine import Job, iter_run_tile
from .prepare import FileInput
from .scratch import OVERLAP_DTYPE, Scratch, columns_to_rows, write_array

__all__ = ["run_file_tile", "iter_file_tile", "finished_summary", "first_halo"]


def run_file_tile(tile: int, source: FileInput, job: Job, frame, bounds, halo: float, overlap: bool,
                  georeferenced: bool = False, step: float | None = None) -> dict:
    """Estimate tile ``tile`` and save its rows (module notes); returns what the run reports about it:
    ``tile``, ``points`` (core), ``read`` (region points over every pass), ``redone``, ``passes``,
    ``seconds``, ``halo``, ``info`` (the estimate's own info entries), ``cached`` (already finished),
    ``reasons`` (its core points per reason code, a (256,) count)."""
    return run_to_end(iter_file_tile(tile, source, job, frame, bounds, halo, overlap, georeferenced, step))


def iter_file_tile(tile: int, source: FileInput, job: Job, frame, bounds, halo: float, overlap: bool,
                   georeferenced: bool = False, step: float | None = None):
    """:func:`run_file_tile` step by step: yields the tile's fraction done (where a run in this process
    may stop), returns the same summary."""
    scratch = Scratch(source.folder)
    if scratch.finished(tile):  # a task run twice (a worker lost after it saved its rows)
        return finished_summary(scratch, tile)
    core = scratch.read_points(tile, source.dtype)["id"]
    box = (source.tiles[tile].lo, source.tiles[tile].hi)
    rows = yield from iter_run_tile(np.ascontiguousarray(core), box, bounds, source.fetch, job, frame, halo=halo,
                                    points=not source.is_mesh, overlap=overlap, georeferenced=georeferenced,
                                    step=step)
    if overlap:
        ids, normals, parts = rows.info.pop("overlap", (np.empty(0, np.int64), np.empty((0, 3)), np.empty(0, np.int64)))
        seen = np.empty(ids.size, OVERLAP_DTYPE)
        seen["id"], seen["normal"], seen["part"] = ids, normals, parts
        write_array(scratch.overlap_path(tile), seen)
    info = rows.info
    reasons = np.bincount(rows.columns["reason"], minlength=256)
    scratch.write_info(tile, {"steps": info.get("steps", []), "reasons": reasons.tolist()})
    # the rows last: their file marks the tile finished
    write_array(scratch.rows_path(tile), columns_to_rows(rows.ids, rows.columns))
    return {"tile": tile, "cached": False, "points": int(rows.ids.size), "read": info["points"],
            "redone": info["redone"], "passes": info["passes"], "seconds": info["seconds"], "halo": info["halo"],
            "info": info.get("estimate_info", {}), "reasons": reasons, "steps": info.get("steps", [])}


def finished_summary(scratch: Scratch, tile: int) -> dict:
    """What :func:`run_file_tile` returns for a tile an earlier run (or try) finished."""
    saved = scratch.read_info(tile)
    return {"tile": tile, "cached": True, "points": int(sum(saved["reasons"])),
            "reasons": np.asarray(saved["reasons"], np.int64), "steps": [tuple(s) for s in saved["steps"]]}


def first_halo(source: FileInput, job: Job, frame, bounds, *, window: int = 200_000) -> float:
    """The first halo width of every tile: twice the 99th percentile of the reach of the points of a
    window of about ``window`` points at the centre of the tile that holds the most (read on its own,
    without a halo: their reach is then a little over the truth at its edges, which only widens the
    halo). A tile that needs more redoes those points (:mod:`curv.tiles.engine`): this only sets how
    often. The window keeps the driver's memory small whatever the tiles' size."""
    from .engine import shape_of
    from .plan import Region

    tile = max(source.tiles, key=lambda t: t.count)
    lo, hi = np.asarray(tile.lo), np.asarray(tile.hi)
    if tile.count > window:
        centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        shrink = np.sqrt(window / tile.count)  # a surface: the count goes with the area
        flat = half <= 0.05 * half.max()  # a terrain's thin side keeps its whole height
        half = np.where(flat, half, half * shrink)
        lo, hi = centre - half, centre + half
    piece = source.fetch(Region.around(lo, hi, 0.0, bounds))
    if piece.ids.size < 2 or (source.is_mesh and (piece.faces is None or piece.faces.size == 0)):
        return 0.0
    shape, _ = shape_of(piece, frame, points=not source.is_mesh)
    reach = job.reach(shape, None)
    finite = reach[np.isfinite(reach)]
    return 2.0 * float(np.percentile(finite, 99)) if finite.size else 0.0
