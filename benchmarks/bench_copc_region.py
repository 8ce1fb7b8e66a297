"""A full-resolution region of a large scan: a COPC file read by bounds against the same points as a
plain LAZ (sorted into tiles in a scratch folder first), as the viewer's Region dock reads them.

Run by hand::

    .venv/bin/python benchmarks/bench_copc_region.py [--points 2000000] [--repeats 2]

It writes a wavy terrain (10 points a square metre, 1 mm coordinates) as a COPC file (the tests'
writer, ``tests/copc_files.py``) and as a plain LAZ (laspy), then alternates the two: the first
region (the COPC file's coordinates-only pass for its grid, or the plain file's three passes into
tiles) and a second region elsewhere (the octree query, or the tiles' files): the points within 1 %
of the extent of a point and the halo ``qs`` R2 reads around them (what the Region dock then
estimates). Wall seconds and their ratio; the two regions' points are checked equal.

Then the viewer's preview of each file at ``--preview`` points (:func:`curv.tiles.preview.read_preview`):
the COPC file's coarse octree levels against every k-th point of the plain file's full pass.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]


def main() -> None:
    import laspy

    from copc_files import write_copc
    from curv.core.jit import run_to_end
    from curv.tiles.preview import read_preview
    from curv.tiles.regions import FileRegions

    parser = argparse.ArgumentParser()
    parser.add_argument("--points", type=int, default=2_000_000)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--preview", type=int, default=200_000, help="points in the preview")
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="copc-bench-"))
    rng = np.random.default_rng(3)
    side = np.sqrt(args.points / 10.0)
    x, y = rng.uniform(0, side, args.points), rng.uniform(0, side, args.points)
    points = np.column_stack([x, y, 3.0 * np.sin(x / 25.0) + 2.0 * np.cos(y / 40.0)])
    levels = max(1, int(round(np.log(args.points / 50_000) / np.log(4))))  # about 50,000 points a deepest node
    write_copc(folder / "scan.copc.laz", points, levels=levels)
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales, header.offsets = np.full(3, 1e-3), np.floor(points.min(axis=0))
    las = laspy.LasData(header)
    las.x, las.y, las.z = points.T
    las.write(folder / "scan.laz")
    picks = [points.min(axis=0) + f * np.ptp(points, axis=0) for f in (0.3, 0.7)]
    radius = 0.01 * side
    try:
        for rep in range(args.repeats):
            results = {}
            for name in ("scan.copc.laz", "scan.laz"):
                regions = FileRegions(folder / name, scratch=folder / f"scratch-{rep}-{name}")
                times = []
                for centre in picks:
                    t = time.perf_counter()
                    around = run_to_end(regions.iter_around(centre, radius, [("qs", 2, {})]))
                    times.append(time.perf_counter() - t)
                results[name] = (times, around)
                regions.close()
            (copc, a), (plain, b) = results["scan.copc.laz"], results["scan.laz"]
            pa, pb = a.shape.points[a.ball], b.shape.points[b.ball]  # the files number the points differently
            assert np.array_equal(pa[np.lexsort(pa.T)], pb[np.lexsort(pb.T)])
            print(f"{args.points:,} points, region of {a.ball.size:,} points: first region COPC {copc[0]:.2f} s, "
                  f"plain LAZ {plain[0]:.2f} s ({plain[0] / copc[0]:.1f}x); second region COPC {copc[1]:.3f} s, "
                  f"plain LAZ {plain[1]:.3f} s", flush=True)
            shown = {}
            for name in ("scan.copc.laz", "scan.laz"):
                t = time.perf_counter()
                preview = read_preview(folder / name, args.preview)
                shown[name] = (time.perf_counter() - t, preview.words)
            (tc, wc), (tp, wp) = shown["scan.copc.laz"], shown["scan.laz"]
            print(f"preview: COPC {tc:.2f} s ({wc}), plain LAZ {tp:.2f} s ({wp}): {tp / tc:.1f}x", flush=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
