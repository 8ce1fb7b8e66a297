"""Predict the peak memory of ``curv estimate`` before running it, and what the machine has free.

The model is ``BASE_BYTES + (PER_UNIT_BYTES + spec.extra_bytes_per_unit) * units
+ STAMP_BYTES_PER_THREAD * threads * n_vertices`` with ``units = n_vertices + n_faces / 2`` (twice
the vertex count on a closed triangle mesh). The kernels hold no per-range temporaries (each
thread's queue has a slot per vertex but touches only its largest support), so the range does not
enter. The coefficients come from peak RSS of the whole ``curv estimate`` process (reading the file,
connectivity, normals, the kernels' scratch, the result and the output file), measured with
``/usr/bin/time -v`` at 10M vertices and ``benchmarks/bench_estimators.py`` at 1M, rounded up.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["estimate_peak_bytes", "available_bytes", "total_bytes", "private_bytes", "format_bytes", "MemoryEstimate",
           "check_memory"]

BASE_BYTES = 170 * 2**20
"""Interpreter, numpy, scipy and plyfile loaded, before any mesh data."""

PER_UNIT_BYTES = 360.0
"""Mesh, connectivity, validity masks, normals, report and result arrays per size unit.

Measured with ``/usr/bin/time -v curv estimate torus.ply -m mru -r 2 -o out.ply`` on the torus of
``benchmarks/bench_large.py`` after the one corner pass, the int32 corner links, the report without
the edge table and the streaming PLY writer (docs/BENCHMARKS.md): 5.51 GB at 10M vertices (20M
units), 1.29 GB at 2M, about 260 B per unit above the base and the stamps; rounded up by about 35 %. The
peak is at the end of the command: the mesh report's face geometry on top of the mesh's cached
connectivity and the result."""

PER_POINT_BYTES = 1000.0
"""Point cloud, its neighbour search (the 10 nearest, the grid), spacing, normals and their
orientation, border flags, result arrays and the written file's records, per point.

Measured on ``curv estimate torus10M.ply -m qs -r 2 -o out.ply`` (10M points without normals):
the process's peak resident size reached 8.16 GB during the estimate (about 800 B a point above
the base; docs/BENCHMARKS.md, "Point-cloud files"), rounded up by 25 % as for meshes."""

STAMP_BYTES_PER_THREAD = 8.0
"""Bytes per vertex and kernel thread of the support search's visited stamps (int64)."""


def estimate_peak_bytes(n_vertices: int, n_faces: int, method: str, *, points: bool = False,
                        threads: int | None = None) -> int:
    """Predicted peak resident memory of estimating ``method`` on a mesh of this size, at any range.

    The kernels hold no per-range temporaries beyond each thread's small queue, so the peak does
    not depend on the range.

    Parameters
    ----------
    n_vertices, n_faces : int
        Mesh size (faces of any polygon kind); for a point cloud its points and 0.
    method : str
        Registry name.
    points : bool
        A point cloud: :data:`PER_POINT_BYTES` (and the estimator's ``extra_bytes_per_point``) per
        point in place of the mesh's per-unit bytes.
    threads : int, optional
        Kernel threads (their stamps); default the process's (:func:`curv.core.jit.threads`).

    Returns
    -------
    int
        Bytes.
    """
    units = float(n_vertices) + 0.5 * float(n_faces)
    from .core.jit import threads as kernel_threads

    from .estimators import get_spec

    spec = get_spec(method)
    per_unit = PER_POINT_BYTES + spec.extra_bytes_per_point if points else PER_UNIT_BYTES + spec.extra_bytes_per_unit
    linear = BASE_BYTES + per_unit * units
    threads = kernel_threads() if threads is None else int(threads)
    return int(linear + STAMP_BYTES_PER_THREAD * threads * float(n_vertices))


def _cgroup_free() -> int | None:
    """Free memory under a cgroup v2 limit, if the process runs under one."""
    limit_file, usage_file = Path("/sys/fs/cgroup/memory.max"), Path("/sys/fs/cgroup/memory.current")
    try:
        limit = limit_file.read_text().strip()
        if limit == "max":
            return None
        return max(0, int(limit) - int(usage_file.read_text().strip()))
    except (OSError, ValueError):
        return None


def _machine_memory(field: str, meminfo_key: str) -> int | None:
    """Bytes of psutil's ``virtual_memory().<field>``, else /proc/meminfo's ``meminfo_key``; None when unknown."""
    try:
        import psutil
    except ImportError:
        try:
            for line in Path("/proc/meminfo").read_text().splitlines():
                if line.startswith(meminfo_key + ":"):
                    return int(line.split()[1]) * 1024
        except (OSError, ValueError, IndexError):
            pass
        return None
    return int(getattr(psutil.virtual_memory(), field))


def available_bytes() -> int | None:
    """Memory this process can still use: MemAvailable (psutil or /proc/meminfo), capped by a cgroup limit.

    Returns ``None`` when it cannot be determined.
    """
    free = _machine_memory("available", "MemAvailable")
    cg = _cgroup_free()
    if cg is not None:
        free = cg if free is None else min(free, cg)
    return free


def total_bytes() -> int | None:
    """The memory this machine gives a process at most, whatever others use now: the physical
    memory (psutil or /proc/meminfo's MemTotal), capped by a cgroup limit. ``None`` when unknown."""
    total = _machine_memory("total", "MemTotal")
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if limit != "max":
            total = int(limit) if total is None else min(total, int(limit))
    except (OSError, ValueError):
        pass
    return total


def private_bytes(pid: int | None = None) -> int | None:
    """A process's own memory: its resident anonymous pages (``RssAnon`` of ``/proc/PID/status``),
    None where that cannot be read (not Linux, or the process is gone).

    This is what a memory budget counts, not the resident size: the resident size also holds the
    pages of every file the process maps (a memory-mapped input or scratch file, the libraries),
    which are the page cache's, shared by every process that maps them and dropped by the kernel
    under pressure. Measured on a tiled ``mru`` run of a 2M-vertex mesh: a worker's resident size
    peaked at 0.65 GiB, of which 0.26 GiB were file pages (docs/BENCHMARKS.md).
    """
    try:
        with open(f"/proc/{'self' if pid is None else int(pid)}/status") as fh:
            for line in fh:
                if line.startswith("RssAnon:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError):
        return None
    return None


def format_bytes(n: float) -> str:
    """``1536 -> '1.5 KiB'``."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} TiB"


class MemoryEstimate:
    """Predicted need versus available memory for one estimate.

    Attributes
    ----------
    needed : int
        Predicted peak bytes.
    available : int or None
        Free bytes now (None when unknown).
    """

    def __init__(self, needed: int, available: int | None):
        self.needed = needed
        self.available = available

    @property
    def fits(self) -> bool:
        """True when the prediction fits in the available memory (or the latter is unknown)."""
        return self.available is None or self.needed <= self.available

    def describe(self) -> str:
        have = "unknown" if self.available is None else format_bytes(self.available)
        return f"needs about {format_bytes(self.needed)}, {have} available"


def check_memory(n_vertices: int, n_faces: int, method: str, *, points: bool = False,
                 available: int | None = None) -> MemoryEstimate:
    """Compare :func:`estimate_peak_bytes` with :func:`available_bytes` (or ``available`` if given)."""
    have = available_bytes() if available is None else available
    return MemoryEstimate(estimate_peak_bytes(n_vertices, n_faces, method, points=points), have)


