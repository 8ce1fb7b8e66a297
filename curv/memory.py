"""Predict the peak memory of ``curv estimate`` before running it, and what the machine has free.

The model is linear in the mesh size, ``BASE_BYTES + PER_UNIT[method][k] * units`` with
``units = n_vertices + n_faces / 2`` (twice the vertex count on a closed triangle mesh). The
coefficients were measured with ``benchmarks/bench_large.py calibrate`` (peak RSS of the whole
``curv estimate`` process: reading the file, connectivity, normals, the estimator's blocks and the
result) and rounded up.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["estimate_peak_bytes", "available_bytes", "format_bytes", "MemoryEstimate", "check_memory"]

BASE_BYTES = 160 * 2**20
"""Interpreter, numpy, scipy and plyfile loaded, before any mesh data."""

PER_UNIT: dict[str, dict[int, float]] = {
    "meyer": {1: 900.0},
    "csm": {1: 1100.0, 2: 1100.0, 3: 1100.0, 4: 1100.0},
    "nc": {1: 900.0, 2: 900.0, 3: 900.0, 4: 900.0},
    "qs": {1: 900.0, 2: 900.0, 3: 900.0, 4: 900.0},
    "an": {2: 1000.0, 3: 1000.0, 4: 1000.0},
    "ru": {2: 1000.0},
    "mru": {2: 1000.0, 3: 1000.0, 4: 1000.0},
}
"""Bytes per size unit for each (method, range), measured; see the module docstring."""

_FALLBACK_PER_UNIT = 1200.0
"""For an estimator or range not measured yet: the largest measured figure, rounded up."""


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
    per_unit = PER_UNIT.get(method, {}).get(int(range), _FALLBACK_PER_UNIT)
    units = float(n_vertices) + 0.5 * float(n_faces)
    return int(BASE_BYTES + per_unit * units)


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


