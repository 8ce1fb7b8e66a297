"""Check a tiled run of a huge LAS/LAZ against the in-memory call on a window of it.

    PYTHONPATH=. python benchmarks/check_window.py terrain100M.laz out.laz -m qs -r 2 --points 1000000

Reads the points of a square window (about ``--points`` of them, around the input's centre or
``--centre X Y``) a chunk at a time, estimates them in memory with ``curv.estimate``, and compares
the window's **interior** (the points whose reach, :func:`curv.tiles.support_reach`, stays inside
the window: their in-memory result is the whole file's) with the tiled output's extra bytes: the
reason codes must be identical and the float32 values equal to within one unit in their last place
(the tiled run sums a support in another order where its ball grid differs, curv/tiles/frame.py).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np


def main(argv=None) -> int:
    import laspy

    import curv
    from curv.tiles import support_reach
    from curv.tiles.plan import Region

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("input")
    parser.add_argument("output")
    parser.add_argument("-m", "--method", default="qs")
    parser.add_argument("-r", "--range", type=float, default=2)
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--centre", type=float, nargs=2)
    parser.add_argument("--orient-normals", nargs="+", help="as the tiled run's (default: the library's)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    with laspy.open(args.input) as reader:
        h = reader.header
        n = h.point_count
        lo, hi = np.array(h.mins), np.array(h.maxs)
        side = math.sqrt(args.points * (hi[0] - lo[0]) * (hi[1] - lo[1]) / n)
        centre = np.array(args.centre) if args.centre else 0.5 * (lo[:2] + hi[:2])
        box_lo = np.array([*(centre - side / 2), lo[2] - 1])
        box_hi = np.array([*(centre + side / 2), hi[2] + 1])
        ids, pts = [], []
        start = 0
        for chunk in reader.chunk_iterator(2_000_000):
            xyz = np.column_stack([chunk.x, chunk.y, chunk.z])
            inside = np.all((xyz >= box_lo) & (xyz <= box_hi), axis=1)
            ids.append(np.flatnonzero(inside) + start)
            pts.append(xyz[inside])
            start += len(chunk)
    ids, pts = np.concatenate(ids), np.concatenate(pts)
    cloud = curv.PointCloud(pts)
    orient = {}
    if args.orient_normals:
        words = args.orient_normals
        orient = {"orient": words[0] if len(words) == 1 else tuple(float(w) for w in words)}
    res = curv.estimate(cloud, args.method, args.range, **orient)
    region = Region(box_lo, box_hi, np.zeros(3, bool), np.zeros(3, bool))
    interior = support_reach(cloud, args.method, args.range, **orient) <= region.room(pts)
    # the tiled output's rows of the window's interior
    want = ids[interior]
    got = {name: [] for name in ("k1", "k2", "mean", "gaussian", "valid", "reason")}
    with laspy.open(args.output) as reader:
        start = 0
        for chunk in reader.chunk_iterator(2_000_000):
            lo_i, hi_i = np.searchsorted(want, [start, start + len(chunk)])
            rows = want[lo_i:hi_i] - start
            for name in got:
                got[name].append(np.asarray(chunk[name])[rows])
            start += len(chunk)
    got = {k: np.concatenate(v) for k, v in got.items()}
    same_reason = np.array_equal(got["reason"], res.reason[interior])
    worst = 0
    for name in ("k1", "k2", "mean", "gaussian"):
        expected = np.asarray(res.quantity(name)[interior], np.float32)
        ulps = np.abs(got[name].view(np.int32).astype(np.int64) - expected.view(np.int32).astype(np.int64))
        ulps = ulps[np.isfinite(expected) | np.isfinite(got[name])]
        worst = max(worst, int(ulps.max()) if ulps.size else 0)
    print(f"window of {pts.shape[0]:,} points ({side:.0f} m square), interior {int(interior.sum()):,}; reason codes "
          f"{'identical' if same_reason else 'DIFFER'}; values within {worst} float32 units in the last place "
          f"({time.perf_counter() - t0:.0f} s)")
    return 0 if same_reason and worst <= 1 else 1


if __name__ == "__main__":
    raise SystemExit(main())
