"""Reading and writing point-cloud files at scale: the load and write parts of ``curv estimate``.

    PYTHONPATH=. .venv/bin/python benchmarks/bench_points_io.py --points 10000000 --folder /tmp/pio

Writes a torus sampled at N random points as a binary PLY (float x y z), a LAS (point format 0,
1e-6 m grid) and a LAZ, then for each: ``curv.load`` (wall and CPU seconds) and ``curv.save_result``
of a result of the same size to a vertex-only PLY (every exported field), and the peak resident
size of the process. The estimate itself is ``benchmarks/bench_estimators.py --points``'s.
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def make_files(n: int, folder: Path) -> list[Path]:
    import laspy
    from plyfile import PlyData, PlyElement

    rng = np.random.default_rng(1)
    u, v = rng.random(n) * 2 * np.pi, rng.random(n) * 2 * np.pi
    p = np.column_stack([(1 + 0.4 * np.cos(v)) * np.cos(u), (1 + 0.4 * np.cos(v)) * np.sin(u), 0.4 * np.sin(v)])
    vert = np.empty(n, [("x", "f4"), ("y", "f4"), ("z", "f4")])
    for i, c in enumerate("xyz"):
        vert[c] = p[:, i]
    stem = folder / f"torus{n}"
    PlyData([PlyElement.describe(vert, "vertex")]).write(f"{stem}.ply")
    header = laspy.LasHeader(point_format=0, version="1.2")
    header.scales, header.offsets = [1e-6] * 3, [0.0] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = p.T
    las.write(f"{stem}.las")
    las.write(f"{stem}.laz")
    return [Path(f"{stem}.{s}") for s in ("ply", "las", "laz")]


def one(path: str, out: str) -> None:
    """Load ``path`` and write a result for it; one line of figures (run in a fresh process)."""
    import curv
    from curv.core.result import Curvature

    t = time.perf_counter()
    cpu = time.process_time()
    cloud = curv.load(path)
    t_load, cpu_load = time.perf_counter() - t, time.process_time() - cpu
    n = cloud.n_points
    rng = np.random.default_rng(0)
    axes = np.zeros((3, n, 3))
    for i in range(3):
        axes[i, :, i] = 1.0
    res = Curvature(k1=rng.random(n) + 1, k2=rng.random(n), d1=axes[0], d2=axes[1], normals=axes[2],
                    valid=np.ones(n, bool), reason=np.zeros(n, np.uint8), method="qs", range=2)
    t, cpu = time.perf_counter(), time.process_time()
    curv.save_result(out, cloud, res)
    t_write, cpu_write = time.perf_counter() - t, time.process_time() - cpu
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    print(f"{Path(path).suffix[1:]:<4} {n:>10,}  load {t_load:6.2f} s (cpu {cpu_load:5.2f})  "
          f"write {t_write:6.2f} s (cpu {cpu_write:5.2f})  peak {peak:5.2f} GB  out {Path(out).stat().st_size / 1e6:,.0f} MB",
          flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--folder", type=Path, default=Path("/tmp"))
    parser.add_argument("--one", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        one(*args.one)
        return
    args.folder.mkdir(parents=True, exist_ok=True)
    files = make_files(args.points, args.folder)
    for path in files:
        subprocess.run([sys.executable, __file__, "--one", str(path), str(args.folder / "bench_out.ply")], check=True)


if __name__ == "__main__":
    main()
