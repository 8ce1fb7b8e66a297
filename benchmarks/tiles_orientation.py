"""A tiled run against the whole call on the benchmark terrain, oriented from the top (issue 33, item 2).

Run by hand from the repository root::

    PYTHONPATH=. python benchmarks/tiles_orientation.py 4000000 --tile-size 250000 [--method qs]

The terrain of ``make_terrain_laz.py`` written as a binary PLY (``bench_tiles.ensure_inputs``): a
PLY is not georeferenced, so its normals are propagated along spanning trees from each part's top
(``orient="top"``), the orientation the tiles must make agree (:mod:`curv.tiles.orient`). The
whole call (``curv estimate IN -o whole.ply``) and the tiled one (``--tile-size N --workers 1``)
run in child processes of this interpreter; the two PLY files are compared row by row: the points
whose validity or reason code differ, and among the points valid in both, those whose normal
points the other way (their k1, k2 are then -k2, -k1) and the largest difference of k1.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))


def _run(args: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "curv.cli", "estimate", *args, "--quiet"], check=True,
                   env={**os.environ, "PYTHONPATH": os.environ.get("PYTHONPATH", str(ROOT))})
    return time.perf_counter() - t0


def compare(whole: Path, tiled: Path) -> dict:
    """Row by row differences of two PLY results of the same input."""
    from plyfile import PlyData

    a, b = PlyData.read(str(whole))["vertex"].data, PlyData.read(str(tiled))["vertex"].data
    both = (a["valid"] == 1) & (b["valid"] == 1)
    turned = both & (a["nx"] * b["nx"] + a["ny"] * b["ny"] + a["nz"] * b["nz"] < 0)
    return {"points": a.size, "valid differ": int((a["valid"] != b["valid"]).sum()),
            "reason differ": int((a["reason"] != b["reason"]).sum()),
            "valid turned the other way": int(turned.sum()),
            "largest k1 difference elsewhere": float(np.max(np.abs(a["k1"] - b["k1"])[both & ~turned], initial=0.0))}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", type=int)
    parser.add_argument("--tile-size", type=int, default=250_000)
    parser.add_argument("--method", default="qs")
    parser.add_argument("--data", type=Path, default=Path("/tmp/curvlab-bench-tiles"))
    args = parser.parse_args(argv)
    from bench_tiles import ensure_inputs

    _, ply = ensure_inputs(args.n, args.data)
    whole, tiled = args.data / f"whole-{args.n}.ply", args.data / f"tiled-{args.n}.ply"
    t_whole = _run([str(ply), "-m", args.method, "-r", "2", "-o", str(whole)])
    t_tiled = _run([str(ply), "-m", args.method, "-r", "2", "-o", str(tiled), "--tile-size", str(args.tile_size),
                    "--workers", "1"])
    print(f"{args.n:,} points, {args.method} R2, tiles of {args.tile_size:,}: whole {t_whole:.1f} s, "
          f"tiled {t_tiled:.1f} s wall")
    for key, value in compare(whole, tiled).items():
        print(f"  {key}: {value}")


if __name__ == "__main__":
    main()
