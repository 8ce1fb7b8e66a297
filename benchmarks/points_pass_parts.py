"""Where the time of the point normals' one pass goes, part by part (issue 33, item 5).

Run by hand from the repository root (one thread, so the CPU seconds are the pass's own)::

    CURV_THREADS=1 PYTHONPATH=. python benchmarks/points_pass_parts.py 300000 [--repeat 3]

N uniform random points of the unit sphere (seed 0, as ``points_profile.py``), in their grid's
order, with the radii the default estimate's pass reads (the border test's R3, the jet fit's R2,
the line checks at R2 and R1). A serial copy of :func:`curv.point_normals.one_pass._pass_kernel`'s
walk runs up to a stage and stops there; the cost of a part is the step from the stage before
(median CPU seconds of ``--repeat`` runs, in one process):

0. the walk and each cell's block of columns (:func:`curv.core.knn.cell_block`) and their bounds;
1. the ball search at the outer radius (:func:`curv.core.knn.block_gather`);
2. frame A's second moments and eigen-solve;
3. frame A's angular gap (exact from 60 degrees on: the border test's);
4. the R2 support picked from the ball;
5. the jet fit over it, in four steps: its PCA frame (centroid, covariance, eigen-solve), the normal
   equations, the scaled Cholesky factor and solve, then the whole fit (the step adds the
   ``SINGULAR`` verdict, :func:`curv.estimators._jet_fit._solve`);
6. the fit's gap (exact from 150 degrees on: the one-sided test's);
7. the line check at R2 (on the jet fit's support);
8. the line check at R1 (its support picked from the ball, then the spread).

The pass also keeps the jet fits for the jet estimator (not here) and writes its outputs; the whole
pass (:func:`curv.point_normals.one_pass._one_pass` as the estimate runs it, one thread) is timed too.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from curv.core.jit import jit
from curv.core.grid_blocks import cell_runs
from curv.core.knn import block_gather
from curv.core.small_linalg import sym3_eigen_closed
from curv.core.small_linalg import cholesky_scaled, cholesky_solve_scaled, scaled_norm_bound
from curv.core.validity import OK
from curv.estimators._jet_fit import MAX_UNKNOWNS, _normal_equations, _pca_frame, fit_jet, jet_scratch
from curv.point_normals.frames import _spread, _widest_gap, _within, gap_scratch, offset_moments

STAGES = ("walk and cell blocks", "ball search (outer radius)", "frame A: moments and eigen-solve",
          "frame A: gap (border test)", "R2 support from the ball", "jet fit: PCA frame", "jet fit: normal equations",
          "jet fit: Cholesky and solve", "jet fit: the verdict (whole fit)", "jet fit's gap (one-sided)",
          "line check R2", "line check R1")


@jit
def _parts(stage, grid, radii, screens):
    """The pass's walk up to ``stage`` (module notes), serial; returns a checksum."""
    cells, coords = grid
    outer2, radii2 = radii
    order = cells[3]
    x, y, z = coords[1], coords[2], coords[3]
    n = order.size
    queue = np.empty(n + 1, np.int64)
    dist2 = np.empty(n + 1)
    sub = np.empty(n + 1, np.int64)
    cov = np.empty((3, 3))
    vecs = np.empty((4, 3))
    gaps = gap_scratch()
    block = (np.empty((64, 2), np.int64), 0, np.empty((64, 6)))
    m, vec, cov_jet, frame, evec = jet_scratch()
    normal_a = np.empty((n, 3))
    total = 0.0
    c = 0
    cell_end = 0
    for i in range(n):
        if i >= cell_end:
            c, cell_end, block = cell_runs(i, c, outer2, cells, coords[0], block)
            total += block[1]
        if stage < 1:
            continue
        p = order[i]
        count = block_gather(i, outer2[p], block, coords, queue, dist2)
        total += count
        if stage < 2:
            continue
        whole = radii2[0, p] == outer2[p]
        c_a = count if whole else _within(queue, dist2, count, radii2[0, p], sub)
        support = queue if whole else sub
        offset_moments(i, support, c_a, x, y, z, True, cov)
        sym3_eigen_closed(cov, vecs)
        normal_a[i, 0], normal_a[i, 1], normal_a[i, 2] = vecs[0, 0], vecs[1, 0], vecs[2, 0]
        total += vecs[3, 0]
        if stage < 3:
            continue
        total += _widest_gap(i, support, c_a, x, y, z, vecs, gaps, screens[0])
        if stage < 4:
            continue
        c_b = _within(queue, dist2, count, radii2[1, p], sub)
        total += c_b
        if stage < 5:
            continue
        evec[3, 0] = math.nan
        if stage < 8:
            # the fit's first steps apart (stage 8: the whole fit)
            code, h2 = _pca_frame((i, c_b, sub), (x, y, z, normal_a), 0.0, (m, vec, cov_jet, frame, evec))
            if stage > 5 and code == OK:
                total += _normal_equations((i, c_b, sub), (x, y, z), frame, (0.0, 1.0 / math.sqrt(h2)), 2, (m, vec))
            if stage > 6 and code == OK:
                total += scaled_norm_bound(m, 6, MAX_UNKNOWNS)
                if cholesky_scaled(m, 6, MAX_UNKNOWNS):
                    cholesky_solve_scaled(m, MAX_UNKNOWNS, 6, vec)
            total += code
            continue
        code, h, _ = fit_jet(i, c_b, sub, (x, y, z, normal_a), 2, (m, vec, cov_jet, frame, evec))
        total += code
        if stage < 9:
            continue
        if c_b >= 3 and math.isfinite(evec[3, 0]):
            total += _widest_gap(i, sub, c_b, x, y, z, evec, gaps, screens[1])
        if stage < 10:
            continue
        total += _spread(i, sub, c_b, x, y, z, cov, vecs)
        if stage < 11:
            continue
        c_s = _within(queue, dist2, count, radii2[3, p], sub)
        total += _spread(i, sub, c_s, x, y, z, cov, vecs)
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", type=int, nargs="?", default=300_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    import curv
    from curv import point_normals as pn
    from curv.core.jit import run_to_end
    from curv.point_normals.normals import EXACT_GAP, ONE_SIDED_GAP, _default_spreads, _radii
    from curv.point_normals.one_pass import _one_pass

    p = np.random.default_rng(0).normal(size=(args.n, 3))
    cloud = pn.grid_ordered(curv.PointCloud(p / np.linalg.norm(p, axis=1, keepdims=True)))[0]
    border, r2, spreads = pn.border_radii(cloud), _radii(cloud, 2), _default_spreads(cloud)
    radii2 = np.square(np.stack([border, r2, *spreads]))
    outer2 = radii2.max(axis=0)
    grid = cloud.ball_grid(np.sqrt(outer2))
    screens = np.array([EXACT_GAP, ONE_SIDED_GAP])
    _parts(len(STAGES) - 1, grid, (outer2, radii2), screens)  # compile or load
    cpu = []
    for stage in range(len(STAGES)):
        runs = []
        for _ in range(args.repeat):
            c = time.process_time()
            _parts(stage, grid, (outer2, radii2), screens)
            runs.append(time.process_time() - c)
        cpu.append(float(np.median(runs)))
    print(f"{args.n} points, one thread, median CPU s of {args.repeat}")
    print(f"{'part':<36} {'cumulative':>10} {'part':>7} {'share':>6}")
    for stage, label in enumerate(STAGES):
        step = cpu[stage] - (cpu[stage - 1] if stage else 0.0)
        print(f"{label:<36} {cpu[stage]:10.3f} {step:7.3f} {step / cpu[-1]:6.1%}")
    whole = []
    for _ in range(args.repeat):
        c = time.process_time()
        run_to_end(_one_pass(cloud, border, r2, jet=True, spreads=spreads, screens=(EXACT_GAP, ONE_SIDED_GAP)))
        whole.append(time.process_time() - c)
    print(f"{'the pass itself (_one_pass)':<36} {float(np.median(whole)):10.3f}")


if __name__ == "__main__":
    main()
