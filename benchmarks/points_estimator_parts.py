"""Where a point cloud's estimator time goes after its normals: search, fit, assembly, checks (CPU seconds).

Run by hand from the repository root::

    CURV_THREADS=1 PYTHONPATH=. .venv/bin/python benchmarks/points_estimator_parts.py 1000000 qs

N uniform random points of the unit sphere (seed 0, as ``points_profile.py``), no normals, default
orientation. One ``curv.estimate(cloud, method, 2)`` on a fresh cloud, with the steps after the
normals timed inside the call (the library's functions wrapped, a generator's time counted while it
runs): the normals and flags (``point_setup``, the one pass and the orientation:
``points_profile.py`` splits them), the radii, the visiting order (it builds the estimate's search
grid), the estimator (its search grid and scratch, its kernel, the hand-over of the normals' fits
where it reads them), and the finish (the two support checks, the rows' settling, NaN-filling and
putting the rows back in the caller's order). Then, on the same cloud with every cache warm, the
estimator's kernel once more and a copy of its ball search alone (the same grid and radii, the
supports only counted): the search, and so the fit (the kernel less the search); and the normals'
pass without and with the fits the estimator reads kept (:mod:`curv.estimators._handover`).
CPU seconds are the process's over all threads.
"""

from __future__ import annotations

import functools
import inspect
import sys
import time
from collections import defaultdict

import numpy as np

TOTALS: dict = defaultdict(float)


def _timed(label, function):
    """``function`` timing its own CPU seconds into ``TOTALS[label]`` (a generator's while it runs)."""
    def run(*args, **kwargs):
        c = time.process_time()
        out = function(*args, **kwargs)
        TOTALS[label] += time.process_time() - c
        if not inspect.isgenerator(out):
            return out
        return (yield from _timed_generator(label, out))

    def plain(*args, **kwargs):
        c = time.process_time()
        try:
            return function(*args, **kwargs)
        finally:
            TOTALS[label] += time.process_time() - c

    return functools.wraps(function)(run if inspect.isgeneratorfunction(function) else plain)


def _timed_generator(label, gen):
    value = None
    while True:
        c = time.process_time()
        try:
            item = gen.send(value)
        except StopIteration as stop:
            TOTALS[label] += time.process_time() - c
            return stop.value
        TOTALS[label] += time.process_time() - c
        value = yield item


def _patch(module, name, label):
    setattr(module, name, _timed(label, getattr(module, name)))


def sphere_points(n: int) -> np.ndarray:
    p = np.random.default_rng(0).normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True)


def _search_only_kernel():
    from curv.core.jit import jit_parallel, prange, slice_bounds
    from curv.geometry.neighbourhood import ball_support

    @jit_parallel
    def search_only(centres, radius, indptr, indices, coords, stamps, queues, counts):
        x, y, z = coords
        slices = stamps.shape[0]
        for t in prange(slices):
            stamp, queue = stamps[t], queues[t]
            start, stop = slice_bounds(0, centres.size, t, slices)
            for i in range(start, stop):
                p = centres[i]
                count, queue = ball_support(p, radius[p] ** 2, indptr, indices, x, y, z, stamp, queue)
                # what a fit reads of each support point: its coordinates
                s = 0.0
                for j in range(count):
                    q = queue[j]
                    s += x[q] - x[p] + y[q] - y[p] + z[q] - z[p]
                counts[p] = count + (s > 1e300)

    return search_only


def main() -> None:
    import curv
    import curv.api as api
    import curv.estimate_finish as finish_mod
    import curv.estimators._fit_driver as driver
    from curv.core.jit import run_to_end, threads
    from curv.core.ranges import ball_radii, resolve
    from curv.core.support import CloudSupport
    from curv.estimators import get_spec
    from curv.geometry.neighbourhood import coordinate_columns, expansion_adjacency, new_queues, new_scratch

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    method = sys.argv[2] if len(sys.argv) > 2 else "qs"
    curv.estimate(curv.PointCloud(sphere_points(2000)), method, 2)  # kernels from the cache
    points = sphere_points(n)
    spec = get_spec(method)

    import curv.point_normals as pn
    import curv.estimators.jet as jet_mod
    import curv.estimators.qs as qs_mod

    for owner, name, label in (
            (api, "point_setup", "normals and flags (point_setup)"), (api, "ball_radii", "radii"),
            (CloudSupport, "visit_order", "visiting order (the estimate's search grid)"),
            (driver, "expansion_adjacency", "estimator: search grid"), (driver, "new_scratch", "estimator: scratch"),
            (driver, "new_queues", "estimator: scratch"), (driver, "launch", "estimator: fit kernel (search + fit)"),
            (api, "finish", "finish (all)"), (finish_mod, "launch", "finish: mark and settle rows"),
            (finish_mod, "rows_back", "finish: rows back in the caller's order"),
            (pn, "support_spread", "finish: line check"), (pn, "quantised_supports", "finish: quantised supports"),
            (jet_mod, "iter_handed", "estimator: hand-over"), (qs_mod, "iter_handed", "estimator: hand-over")):
        if hasattr(owner, name):  # a tree before the hand-over has none
            _patch(owner, name, label)
    function = spec.function
    object.__setattr__(spec, "function", _timed("estimator (all)", function))

    cloud = curv.PointCloud(points)
    t, c = time.perf_counter(), time.process_time()
    res = curv.estimate(cloud, method, 2)
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    object.__setattr__(spec, "function", function)
    for label in sorted(TOTALS, key=lambda k: (k.split(":")[0], k)):
        print(f"{label:<48} cpu {TOTALS[label]:7.2f}")
    rest = cpu - TOTALS["normals and flags (point_setup)"] - TOTALS["radii"] - TOTALS[
        "visiting order (the estimate's search grid)"] - TOTALS["estimator (all)"] - TOTALS["finish (all)"]
    print(f"{'the rest of the call':<48} cpu {rest:7.2f}")
    print(f"{'whole ' + method + ' R2 call':<48} cpu {cpu:7.2f}  wall {wall:7.2f}  (valid {res.valid.mean():.4f})")

    # again on the grid-ordered twin the call ran on, every cache warm: the kernel, then the search alone
    twin, rows = api.cloud_twin(cloud)
    normals = np.asarray(res.normals)[rows]
    radii = ball_radii(twin, resolve(spec, 2, None, None), uses_normals=spec.uses_normals)
    order = CloudSupport(twin).visit_order(radii)
    c = time.process_time()
    run_to_end(function(twin, normals, radii, centres=order))
    kernel = time.process_time() - c
    indptr, indices = expansion_adjacency(twin, radii=radii)
    parts = max(1, min(threads(), n))
    counts = np.empty(n, np.int64)
    search_only = _search_only_kernel()
    args = (order, np.ascontiguousarray(radii), indptr, indices, coordinate_columns(twin),
            new_scratch(n, parts), new_queues(n, parts), counts)
    search_only(order[:100], *args[1:])  # compiled
    c = time.process_time()
    search_only(*args)
    search = time.process_time() - c
    print(f"{'again: the estimator, warm':<48} cpu {kernel:7.2f}")
    print(f"{'again: its ball search alone':<48} cpu {search:7.2f}  (mean support {counts.mean():.1f})")
    _pass_with_fits(twin, spec)


def _pass_with_fits(cloud, spec) -> None:
    """The normals' pass without and with the fits the estimator reads kept (alternating, the
    least of two each): what keeping them costs the pass."""
    import inspect

    from curv.core.jit import run_to_end
    from curv.point_normals import border_radii
    from curv.point_normals.normals import EXACT_GAP, ONE_SIDED_GAP, _default_spreads, _radii
    from curv.point_normals.one_pass import _one_pass

    reads = spec.reads_normal_fits
    fits = reads({}, False) if reads is not None and "kept" in inspect.signature(_one_pass).parameters else None
    if not fits:
        return
    border, r2, spreads = border_radii(cloud), _radii(cloud, 2), _default_spreads(cloud)[:1]
    times = {False: [], True: []}
    for keep in (False, True, False, True):
        kept = fits.new(r2) if keep else None
        c = time.process_time()
        run_to_end(_one_pass(cloud, border, r2, jet=True, spreads=spreads, screens=(EXACT_GAP, ONE_SIDED_GAP),
                             kept=kept))
        times[keep].append(time.process_time() - c)
    print(f"{'the normals pass, without / with kept fits':<48} cpu {min(times[False]):7.2f} / {min(times[True]):.2f}"
          f"  (runs {times[False]} / {times[True]})")


if __name__ == "__main__":
    main()
