"""Where the time of one point-cloud estimate goes, phase by phase (wall and CPU seconds).

Run by hand from the repository root::

    PYTHONPATH=. .venv/bin/python benchmarks/points_profile.py 1000000 qs [up|top|outward] [--lines]

N uniform random points of the unit sphere (seed 0), no normals, as ``bench_estimators.py
--points``. The phases are those of ``curv.estimate(curv.PointCloud(points), method, 2)``, run one
by one on one cloud: its twin in grid order (the estimate's first step, which every later phase
runs on), the grid and the 10 nearest (the spacing), the one pass per point (PCA and
gap at the border test's radius, the jet normals and their gap at R2, the line checks at R2 and
R1), the neighbour graph (only the propagating rules read it), the orientation (the rule named last:
``top``, the default for such a cloud, or ``up``, the default of a georeferenced scan, which reads
the 10 nearest and no graph), the coincident points and the coordinates' grid step; then the whole
call on a fresh cloud with that rule, whose remainder over the phases is the estimator's own kernel. CPU seconds are the
process's over all threads: on a shared machine they move much less with the load than the wall.

``--lines``: the whole call is also sampled (every millisecond, the stacks of the threads that are
not waiting) and the lines of curv it spends its wall time on are listed, the kernels' calls and the
numpy between them: run at ``CURV_THREADS=1`` and ``=2``, a line whose time does not halve is serial.
"""

from __future__ import annotations

import collections
import inspect
import os
import sys
import threading
import time

import numpy as np


def sphere_points(n: int) -> np.ndarray:
    p = np.random.default_rng(0).normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True)


class LineSampler:
    """Where the wall time of the threads that are not waiting goes: every ``every`` seconds, the
    innermost frame of curv's own code in each such thread's stack (file, line and function), and
    its function's inclusive count. A numba kernel runs without the interpreter, so its time is the
    line that called it; the numpy between kernels is its own lines."""

    def __init__(self, every: float = 0.001):
        self.every, self.lines, self.functions, self.samples = every, collections.Counter(), collections.Counter(), 0
        self._stop = threading.Event()
        self._root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

    def _own(self, frame) -> bool:
        return frame.f_code.co_filename.startswith(self._root) and "/benchmarks/" not in frame.f_code.co_filename

    def _sample(self, me: int) -> None:
        for ident, frame in sys._current_frames().items():
            if ident == me or frame.f_code.co_name in ("wait", "_wait_for_tstate_lock", "select"):
                continue
            self.samples += 1
            seen, inner = set(), None
            while frame is not None:
                if self._own(frame):
                    where = f"{os.path.relpath(frame.f_code.co_filename, self._root)}:{frame.f_code.co_name}"
                    inner = inner or f"{where}:{frame.f_lineno}"
                    seen.add(where)
                frame = frame.f_back
            self.lines[inner or "(outside curv)"] += 1
            self.functions.update(seen)

    def _run(self) -> None:
        me = threading.get_ident()
        while not self._stop.wait(self.every):
            self._sample(me)

    def __enter__(self):
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()

    def report(self, wall: float, top: int = 30) -> None:
        scale = wall / max(self.samples, 1)
        print(f"\nlines of the whole call (wall s, {self.samples} samples):")
        for where, count in self.lines.most_common(top):
            print(f"  {count * scale:7.2f}  {where}")
        print("functions, inclusive (wall s):")
        for where, count in self.functions.most_common(top):
            print(f"  {count * scale:7.2f}  {where}")


def main() -> None:
    import curv
    from curv import point_normals as pn
    from curv.point_normals.normals import EXACT_GAP, ONE_SIDED_GAP, _default_spreads, _radii
    from curv.point_normals.one_pass import _one_pass
    from curv.core.jit import run_to_end

    lines = "--lines" in sys.argv
    args = [a for a in sys.argv[1:] if a != "--lines"]
    n = int(args[0]) if len(args) > 0 else 1_000_000
    method = args[1] if len(args) > 1 else "qs"
    orient = args[2] if len(args) > 2 else "top"
    curv.estimate(curv.PointCloud(sphere_points(2000)), method, 2)  # kernels from the cache
    points = sphere_points(n)
    total_wall = total_cpu = 0.0

    def phase(label, work):
        nonlocal total_wall, total_cpu
        t, c = time.perf_counter(), time.process_time()
        out = work()
        wall, cpu = time.perf_counter() - t, time.process_time() - c
        total_wall, total_cpu = total_wall + wall, total_cpu + cpu
        print(f"{label:<34} wall {wall:7.2f}  cpu {cpu:7.2f}", flush=True)
        return out

    cloud = phase("point cloud", lambda: curv.PointCloud(points))
    cloud = phase("grid order", lambda: pn.grid_ordered(cloud)[0])
    phase("grid + 10 nearest", lambda: cloud.nearest)
    border = phase("border radii", lambda: pn.border_radii(cloud))
    r2, spreads = _radii(cloud, 2), _default_spreads(cloud)
    # an estimate that reads the pass's fits at R2 (the jet, qs) has the pass keep them (a tree
    # without the keyword: nothing kept; with the older one, the jet's only)
    params = inspect.signature(_one_pass).parameters
    reads = curv.estimators.get_spec(method).reads_normal_fits
    fits = reads({}, False) if "kept" in params and reads is not None else None
    keep = ({"kept": fits.new(r2)} if fits else
            {"keep_fits": True} if method == "jet" and "keep_fits" in params else {})
    found = phase("one pass (frames, jet, line checks)",
                  lambda: run_to_end(_one_pass(cloud, border, r2, jet=True, spreads=spreads,
                                               screens=(EXACT_GAP, ONE_SIDED_GAP), **keep)))
    if orient != "up":
        phase("neighbour graph", lambda: cloud.adjacency)
    phase(f"orientation ({orient})", lambda: pn.orient_normals(cloud, found.normal_a, orient=orient))
    phase("coincident points", lambda: cloud.coincident_points)
    phase("coordinate step", lambda: cloud.coordinate_step)
    print(f"{'phases':<34} wall {total_wall:7.2f}  cpu {total_cpu:7.2f}")
    sampler = LineSampler() if lines else None
    t, c = time.perf_counter(), time.process_time()
    if sampler:
        sampler.__enter__()
    res = curv.estimate(curv.PointCloud(points), method, 2, orient=orient)
    wall = time.perf_counter() - t
    if sampler:
        sampler.__exit__()
    print(f"{'whole ' + method + ' R2 call':<34} wall {wall:7.2f}  "
          f"cpu {time.process_time() - c:7.2f}  (valid {res.valid.mean():.4f})")
    if sampler:
        sampler.report(wall)


if __name__ == "__main__":
    main()
