"""A large mesh PLY to PLY on tiles: wall time, CPU time and peak memory of every process together.

    PYTHONPATH=. python benchmarks/bench_mesh_tiles.py 5000000 --quads --memory 4GB
    PYTHONPATH=. python benchmarks/bench_mesh_tiles.py 1000000 --tile-size 250000 --repeat 3

Makes the terrain mesh of ``make_mesh_ply.py`` once in ``--data`` (triangles, or ``--quads``:
one quad a grid cell), then runs ``curv estimate in.ply -m M -r 2 -o out.ply --memory B
[--tile-size N]`` as a child process ``--repeat`` times, measured as ``bench_tiles.py`` measures
(every process the command starts added up, sampled every 0.1 s). Run it with ``nice`` on a
shared machine; compare two trees by alternating their runs in one period.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_tiles import measure  # noqa: E402
from make_mesh_ply import make  # noqa: E402


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("vertices", type=int)
    parser.add_argument("--quads", action="store_true")
    parser.add_argument("--method", default="mru")
    parser.add_argument("--memory", default="4GB")
    parser.add_argument("--tile-size", type=int)
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--data", type=Path, default=Path("bench_data"))
    args = parser.parse_args(argv)
    args.data.mkdir(parents=True, exist_ok=True)
    ply = args.data / f"{'quads' if args.quads else 'terrain'}{args.vertices}.ply"
    if not ply.is_file():
        make(args.vertices, ply, quads=args.quads)
    out = args.data / "out.ply"
    cmd = [sys.executable, "-m", "curv.cli", "estimate", str(ply), "-m", args.method, "-r", "2", "-o", str(out),
           "--quiet", "--memory", args.memory]
    if args.tile_size:
        cmd += ["--tile-size", str(args.tile_size)]
    for _ in range(args.repeat):
        r = measure(cmd)
        print(f"{ply.name} {args.method}: wall {r['wall']:.1f} s, CPU {r['cpu']:.1f} s, peak {r['peak'] / 2**30:.2f} GB"
              + ("" if r["rc"] == 0 else f" (failed: {r['out'][-300:]})"), flush=True)
    out.unlink(missing_ok=True)


if __name__ == "__main__":
    main()
