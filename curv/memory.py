"""Predict the peak memory of ``curv estimate`` before running it, and what the machine has free.

The model is ``BASE_BYTES + PER_UNIT_BYTES * units + BLOCK_BYTES[method, k]`` with
``units = n_vertices + n_faces / 2`` (twice the vertex count on a closed triangle mesh). The
coefficients were measured with ``benchmarks/bench_large.py calibrate`` (peak RSS of the whole
``curv estimate`` process: reading the file, connectivity, normals, the estimator's blocks and the
result) and rounded up.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["estimate_peak_bytes", "available_bytes", "format_bytes", "MemoryEstimate", "check_memory"]

BASE_BYTES = 170 * 2**20
"""Interpreter, numpy, scipy and plyfile loaded, before any mesh data."""

PER_UNIT_BYTES = 1950.0
"""Mesh, connectivity, normals, report and result arrays per size unit (largest slope measured:
``nc`` R1 between 100k and 400k vertices, 1.87 kB; ``mru`` R2: 1.30 kB)."""

BLOCK_BYTES: dict[tuple[str, int], int] = {
    ("mru", 3): 1150 * 2**20,
    ("mru", 4): 1150 * 2**20,
    ("qs", 3): 1000 * 2**20,
    ("qs", 4): 1000 * 2**20,
    ("nc", 3): 1000 * 2**20,
    ("nc", 4): 1000 * 2**20,
    ("an", 2): 2850 * 2**20,
    ("an", 3): 2850 * 2**20,
    ("an", 4): 2850 * 2**20,
    ("csm", 3): 1200 * 2**20,
    ("csm", 4): 1200 * 2**20,
}
"""Temporaries of the neighbourhood blocks at wide ranges, which do not grow with the mesh (the
blocks are bounded): measured peak at 100k vertices minus the linear part. Wide ranges not measured
take the value of their R4 (an upper bound); R1/R2 of the one-ring estimators have none to speak of."""


def estimate_peak_bytes(n_vertices: int, n_faces: int, method: str, range: int) -> int:
    """Predicted peak resident memory of estimating ``method`` at ``range`` on a mesh of this size.

    Parameters
    ----------
    n_vertices, n_faces : int
        Mesh size (faces of any polygon kind).
    method : str
        Registry name.
    range : int
        k of Rk.

    Returns
    -------
    int
        Bytes.
    """
    units = float(n_vertices) + 0.5 * float(n_faces)
    linear = BASE_BYTES + PER_UNIT_BYTES * units
    # small meshes have small blocks: the block term cannot exceed what the mesh can fill
    block = min(BLOCK_BYTES.get((method, int(range)), 0), 20_000.0 * units)
    return int(linear + block)


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


def available_bytes() -> int | None:
    """Memory this process can still use: MemAvailable (psutil or /proc/meminfo), capped by a cgroup limit.

    Returns ``None`` when it cannot be determined.
    """
    free = None
    try:
        import psutil
    except ImportError:
        try:
            for line in Path("/proc/meminfo").read_text().splitlines():
                if line.startswith("MemAvailable:"):
                    free = int(line.split()[1]) * 1024
                    break
        except (OSError, ValueError, IndexError):
            free = None
    else:
        free = int(psutil.virtual_memory().available)
    cg = _cgroup_free()
    if cg is not None:
        free = cg if free is None else min(free, cg)
    return free


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


def check_memory(n_vertices: int, n_faces: int, method: str, range: int, *,
                 available: int | None = None) -> MemoryEstimate:
    """Compare :func:`estimate_peak_bytes` with :func:`available_bytes` (or ``available`` if given)."""
    have = available_bytes() if available is None else available
    return MemoryEstimate(estimate_peak_bytes(n_vertices, n_faces, method, range), have)


