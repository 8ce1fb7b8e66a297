"""A tiled run's memory budget: how many workers, how many points a tile, whether to tile at all.

The budget covers every process of the run: the driver (this process: the passes over the file
a chunk at a time, the read buffers of the output, the output's own buffers: :data:`DRIVER_BYTES`)
and each worker estimating one tile at a time, whose peak is :func:`curv.memory.estimate_peak_bytes`
of the tile's points and its halo (one kernel thread a worker). So a tile holds

    ``points = (budget - driver) / workers`` turned into points by that model,

less the halo's share (:data:`HALO_SHARE`). More workers share the budget; a worker needs at
least :data:`MIN_TILE` points' room, which caps their number.

The default budget (:func:`default_budget`) is a share of the machine's **total** memory, not of
the memory free at the moment: whether a command runs on tiles, and the tiles it cuts (which a
resumed run must find again), then depend on the input and the machine only, never on what other
processes hold when it starts. A machine too busy for the run's whole estimate is told so in one
line before any work (``curv estimate``'s memory check, against the memory free now), and
``--memory`` or ``--tile-size`` runs it on tiles.
"""

from __future__ import annotations

import os
import re

from ..core.errors import CurvError

__all__ = ["parse_memory", "Budget", "BudgetError", "plan_budget", "DRIVER_BYTES", "MIN_TILE", "HALO_SHARE",
           "MESH_TILE_FACTOR", "needs_tiles", "default_budget", "DEFAULT_SHARE", "UNKNOWN_TOTAL"]


class BudgetError(CurvError, ValueError):
    """A memory budget that is not a size, or too small for one worker (one line)."""

DRIVER_BYTES = 600 * 2**20
"""The driver process: interpreter and libraries, a chunk of points in each pass, the tiles' read
buffers and the output writer's (measured below 550 MB at 10M points: docs/LARGE_SCANS.md)."""

MIN_TILE = 100_000
"""Fewer points a tile than this and the halos cost more than the tiles (a halo of 5 spacings
around a square tile of 100k points is about 20 % of it)."""

HALO_SHARE = 0.25
"""A tile's region holds about this share more points than its core (the halo), at most, as planned."""

MESH_TILE_FACTOR = 2.0
"""A mesh tile's worker peaks at about this multiple of :func:`curv.memory.estimate_peak_bytes` of
its region (the region's vertices and faces read and renumbered, the connectivity its estimate
builds, the rows it keeps): measured 1.19 GiB for a 683k-vertex region (model 0.67 GiB, 1.8x;
``make_mesh_ply.py`` terrain, ``mru`` R2). Without it a 10M-vertex mesh under ``--memory 6GB`` got
tiles of 2.5M vertices whose workers were stopped past their 2.7 GB limit."""

_UNITS = {"": 1, "b": 1, "k": 1e3, "kb": 1e3, "m": 1e6, "mb": 1e6, "g": 1e9, "gb": 1e9, "t": 1e12, "tb": 1e12,
          "kib": 2**10, "mib": 2**20, "gib": 2**30, "tib": 2**40}


def parse_memory(text) -> int:
    """Bytes from ``4GB``, ``4 GiB``, ``500MB``, ``2.5g`` or a plain number of bytes; :class:`BudgetError`
    (a ValueError) in one line otherwise."""
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        value = float(text)
    else:
        match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*([a-zA-Z]*)\s*", str(text))
        if not match or match.group(2).lower() not in _UNITS:
            raise BudgetError(f"memory must be a size such as 4GB, 500MB or 2.5GiB; got {text!r}")
        value = float(match.group(1)) * _UNITS[match.group(2).lower()]
    if not value > 0:
        raise BudgetError(f"memory must be a positive size; got {text!r}")
    return int(value)


class Budget:
    """How a run spends its memory.

    Attributes
    ----------
    total : int
        Bytes for the whole run.
    workers : int
        Processes estimating tiles at once.
    tile_size : int
        Points a tile holds at most (its core).
    worker_bytes : int
        Each worker's share (its memory limit on a local cluster).
    """

    def __init__(self, total: int, workers: int, tile_size: int, worker_bytes: int):
        self.total, self.workers, self.tile_size, self.worker_bytes = int(total), int(workers), int(tile_size), int(worker_bytes)

    def __repr__(self) -> str:
        from ..memory import format_bytes

        return (f"Budget({format_bytes(self.total)}: {self.workers} workers of {format_bytes(self.worker_bytes)}, "
                f"tiles of {self.tile_size:,} points)")


def _tile_points(worker_bytes: float, method: str, *, points: bool, faces_per_vertex: float) -> int:
    """The most points (vertices) whose estimate, halo included, fits in ``worker_bytes`` on one thread."""
    from ..memory import estimate_peak_bytes

    def peak(n):
        bytes_ = estimate_peak_bytes(int(n), int(n * faces_per_vertex), method, points=points, threads=1)
        return bytes_ if points else MESH_TILE_FACTOR * bytes_

    base = peak(0)
    per = (peak(1_000_000) - base) / 1_000_000
    return max(0, int((worker_bytes - base) / per / (1.0 + HALO_SHARE)))


def plan_budget(total: int, method: str, *, points: bool, faces_per_vertex: float = 2.0, workers: int | None = None,
                tile_size: int | None = None) -> Budget:
    """Workers and tile size for a run of ``total`` bytes (module notes).

    ``workers`` defaults to the usable cores, fewer when the budget cannot give each
    :data:`MIN_TILE` points; ``tile_size``, when given, is kept (the caller forces it) and the workers
    are then as many as fit. Raises :class:`BudgetError` when not even one worker of :data:`MIN_TILE`
    points (or of ``tile_size``) fits.
    """
    from ..memory import format_bytes

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    room = total - DRIVER_BYTES
    want = workers or cores
    need = tile_size or MIN_TILE
    for w in range(want, 0, -1):
        share = room / w
        fits = _tile_points(share, method, points=points, faces_per_vertex=faces_per_vertex)
        if fits >= need:
            return Budget(total, w, tile_size or fits, int(share))
    raise BudgetError(f"a memory budget of {format_bytes(total)} leaves no room for one worker estimating "
                     f"{need:,} points with {method} (give more --memory, or a smaller --tile-size)")


DEFAULT_SHARE = 0.5
"""The default budget's share of the machine's total memory (:func:`curv.memory.total_bytes`): half,
leaving the other half to the system and the programs a user keeps open beside a long run."""

UNKNOWN_TOTAL = 8 * 2**30
"""The machine's memory where it cannot be read (neither psutil nor /proc/meminfo): 8 GiB."""


def default_budget() -> int:
    """Bytes for a run given no ``--memory``: :data:`DEFAULT_SHARE` of the machine's total memory (a
    cgroup limit when lower), the same whatever the machine holds free now (module notes)."""
    from ..memory import total_bytes

    total = total_bytes()
    return int(DEFAULT_SHARE * (total if total else UNKNOWN_TOTAL))


def needs_tiles(n_points: int, n_faces: int, method: str, total: int, *, points: bool) -> bool:
    """Whether the whole input's estimate in one process would exceed ``total`` bytes
    (:func:`curv.memory.estimate_peak_bytes`)."""
    from ..memory import estimate_peak_bytes

    return estimate_peak_bytes(n_points, n_faces, method, points=points) > total
