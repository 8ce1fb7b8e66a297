"""Large inputs on tiles: wall time, CPU time and peak memory of every process together, against CloudCompare.

    PYTHONPATH=. python benchmarks/bench_tiles.py --sizes 1000000 10000000 --methods qs jet
    PYTHONPATH=. python benchmarks/bench_tiles.py --sizes 1000000 --cases tiled-laz cloudcompare

Each case is one whole command (read, estimate, write) run as a child process; a sampler adds up
the resident memory of the command and every process it starts (a local Dask cluster's workers)
every 0.1 s, so "peak" is the peak of the whole run, not of one process. It counts the pages of
a memory-mapped file once in every process that touches them; "own" adds up each process's own
(anonymous) memory instead (:func:`curv.memory.private_bytes`), what the ``--memory`` budget
means and what docs/BENCHMARKS.md quotes beside it: file pages are the page cache's, which the
kernel drops under pressure. Inputs are made once in
``--data`` (``make_terrain_laz.py``, and a PLY of the same points for CloudCompare, which reads
PLY). Cases:

- ``whole-ply``: ``curv estimate in.ply -m M -r 2 -o out.ply`` (the whole cloud in memory);
- ``tiled-ply``: the same with ``--memory 4GB``: tiled on a local cluster when the whole estimate
  would not fit in 4 GB, the tiles as large as the budget allows (``--tile-size N`` forces tiles
  of N points at any size);
- ``tiled-laz``: ``curv estimate in.laz -m M -r 2 -o out.laz --memory 4GB`` (LAZ in and out,
  every record kept), tiled the same way;
- ``cloudcompare``: ``CloudCompare -SILENT -O in.ply -CURV MEAN R -SAVE_CLOUDS`` under
  ``xvfb-run``, with R the radius holding about 20 neighbours (its unsigned mean curvature).

Run it with ``nice`` on a shared machine and compare ratios within one run: absolute times drift
with the load.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def measure(cmd: list[str], *, env=None) -> dict:
    """Run ``cmd``; its wall seconds, CPU seconds, and peak bytes of every process it starts together:
    ``peak`` of their resident sizes, ``own`` of their own (anonymous) memory (module notes)."""
    import resource

    import psutil

    from curv.memory import private_bytes

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, text=True)
    peak = {"rss": 0, "own": 0}
    done = threading.Event()

    def sample():
        try:
            root = psutil.Process(proc.pid)
        except psutil.NoSuchProcess:
            return
        while not done.is_set():
            rss = own = 0
            try:
                family = [root, *root.children(recursive=True)]
            except psutil.NoSuchProcess:
                break
            for p in family:
                try:
                    resident = p.memory_info().rss
                except psutil.NoSuchProcess:
                    continue
                rss += resident
                mine = private_bytes(p.pid)
                own += resident if mine is None else mine
            peak["rss"], peak["own"] = max(peak["rss"], rss), max(peak["own"], own)
            time.sleep(0.1)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    out, _ = proc.communicate()
    done.set()
    sampler.join()
    wall = time.perf_counter() - start
    # every process of the command, waited for by its parent in turn, adds up in our children's times
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall": wall, "cpu": cpu, "peak": peak["rss"], "own": peak["own"], "rc": proc.returncode, "out": out}


def ensure_inputs(n: int, data: Path) -> tuple[Path, Path]:
    """The benchmark terrain as LAZ and as a binary PLY of the same points (float64 coordinates)."""
    data.mkdir(parents=True, exist_ok=True)
    laz = data / f"terrain{n}.laz"
    ply = data / f"terrain{n}.ply"
    if not laz.exists():
        subprocess.run([sys.executable, str(ROOT / "benchmarks" / "make_terrain_laz.py"), str(n), str(laz)], check=True,
                       env={"PYTHONPATH": str(ROOT)})
    if not ply.exists():
        import laspy

        header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty double x\nproperty double y\n"
                  f"property double z\nend_header\n").encode()
        with laspy.open(laz) as reader, open(ply, "wb") as fh:
            fh.write(header)
            for pts in reader.chunk_iterator(1_000_000):
                fh.write(np.column_stack([pts.x, pts.y, pts.z]).astype("<f8").tobytes())
    return laz, ply


def cc_radius(ply: Path, neighbours: int = 20) -> float:
    """The radius holding about ``neighbours`` points on average (CloudCompare's ball)."""
    from plyfile import PlyData

    v = PlyData.read(str(ply))["vertex"].data
    n = v.shape[0]
    area = float((v["x"].max() - v["x"].min()) * (v["y"].max() - v["y"].min()))
    return float(np.sqrt(neighbours * area / (np.pi * n)))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1_000_000])
    parser.add_argument("--methods", nargs="+", default=["qs", "jet"])
    parser.add_argument("--cases", nargs="+", default=["whole-ply", "tiled-ply", "tiled-laz", "cloudcompare"])
    parser.add_argument("--memory", default="4GB")
    parser.add_argument("--data", type=Path, default=Path("/tmp/curvlab-bench-tiles"))
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--tile-size", type=int, help="force tiles of this many points in the tiled cases")
    args = parser.parse_args(argv)
    curv = [sys.executable, "-m", "curv.cli", "estimate"]
    env = {**__import__("os").environ, "PYTHONPATH": str(ROOT)}
    rows = []
    tiles = ["--tile-size", str(args.tile_size)] if args.tile_size else []
    for n in args.sizes:
        laz, ply = ensure_inputs(n, args.data)
        out = args.data / "out"
        out.mkdir(exist_ok=True)
        for _ in range(args.repeat):
            for case in args.cases:
                for method in (args.methods if case != "cloudcompare" else ["CURV MEAN"]):
                    if case == "whole-ply":
                        cmd = [*curv, str(ply), "-m", method, "-r", "2", "-o", str(out / "w.ply"), "--quiet"]
                    elif case == "tiled-ply":
                        cmd = [*curv, str(ply), "-m", method, "-r", "2", "-o", str(out / "t.ply"), "--quiet",
                               "--memory", args.memory, *tiles]
                    elif case == "tiled-laz":
                        cmd = [*curv, str(laz), "-m", method, "-r", "2", "-o", str(out / "t.laz"), "--quiet",
                               "--memory", args.memory, *tiles]
                    else:
                        if shutil.which("CloudCompare") is None:
                            print("CloudCompare is not installed (apt-get install cloudcompare)")
                            continue
                        r = cc_radius(ply)
                        cmd = ["xvfb-run", "-a", "CloudCompare", "-SILENT", "-AUTO_SAVE", "OFF", "-O", str(ply),
                               "-CURV", "MEAN", f"{r:.6g}", "-C_EXPORT_FMT", "PLY", "-SAVE_CLOUDS",
                               "FILE", str(out / "cc.ply")]
                    m = measure(cmd, env=env)
                    status = "" if m["rc"] == 0 else f" (exit {m['rc']}: {m['out'].strip().splitlines()[-1:]})"
                    rows.append((n, case, method, m["wall"], m["cpu"], m["peak"] / 2**30, m["own"] / 2**30, status))
                    print(f"{n:>11,} {case:<13} {method:<10} wall {m['wall']:7.1f} s  cpu {m['cpu']:7.1f} s  "
                          f"peak {m['peak'] / 2**30:5.2f} GiB (own {m['own'] / 2**30:5.2f}){status}", flush=True)
    print("\n| points | case | method | wall s | CPU s (all processes) | peak GiB (all processes: resident / own) |")
    print("|---:|---|---|---:|---:|---:|")
    for n, case, method, wall, cpu, peak, own, status in rows:
        print(f"| {n:,} | {case} | {method} | {wall:.1f} | {cpu:.1f} | {peak:.2f} / {own:.2f}{status} |")


if __name__ == "__main__":
    main()
