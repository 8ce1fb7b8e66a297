"""What an estimate over a region costs on a large mesh: it should follow the region, not the mesh.

    .venv/bin/python benchmarks/bench_region.py 1000000
    .venv/bin/python benchmarks/bench_region.py 10000000

On the torus of ``benchmarks/bench_large.py`` with n vertices: the mesh is *prepared* once (its
connectivity, cached normals and flags, the expansion adjacency, compiled kernels: what the first
``curv.estimate(mesh, ..., vertices=[0])`` of each estimator builds), then ``curv.estimate(mesh,
method, vertices=idx)`` for the 1,000 vertices nearest one point is timed (median of 5; a region
equals the whole-mesh run there, tests/test_regions.py). With ``--features`` the same with a 30
degree feature angle (its first call computes the mesh's dihedral angles). The viewer's recolouring
of the whole mesh with the rest grey is timed once.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's curv and app

import curv  # noqa: E402

from app.model.colors import colormap, map_colours  # noqa: E402
from app.model.region import REST_COLOUR  # noqa: E402
from bench_large import torus  # noqa: E402

METHODS = ("mru", "nc", "qs", "an", "jet", "ru", "meyer", "csm", "icc")
REGION = 1000
REPEATS = 5


def timed(fn) -> float:
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n_vertices", type=int, nargs="?", default=1_000_000)
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--features", action="store_true", help="also with features=30")
    args = parser.parse_args()
    t = time.perf_counter()
    mesh = curv.Mesh(*torus(args.n_vertices))
    print(f"torus of {mesh.n_vertices} vertices built in {time.perf_counter() - t:.1f} s")
    d2 = np.einsum("ij,ij->i", mesh.vertices - mesh.vertices[12345], mesh.vertices - mesh.vertices[12345])
    region = np.sort(np.argpartition(d2, REGION)[:REGION])
    for method in args.methods:
        prepared = timed(lambda: curv.estimate(mesh, method, vertices=[0]))
        for features in (None, 30.0) if args.features else (None,):
            first = timed(lambda: curv.estimate(mesh, method, vertices=region, features=features))
            times = [timed(lambda: curv.estimate(mesh, method, vertices=region, features=features))
                     for _ in range(REPEATS)]
            print(f"{method:6s} features={features}: {REGION} vertices in {1e3 * statistics.median(times):7.1f} ms "
                  f"(median of {REPEATS}; min {1e3 * min(times):.1f}, first {1e3 * first:.1f}); "
                  f"preparing {prepared:.1f} s", flush=True)
    part = curv.estimate(mesh, "mru", vertices=region)
    t = time.perf_counter()
    rgba = map_colours(part.mean, (-1.0, 1.0), colormap("coolwarm"))
    rgba[part.reason == curv.Reason.NOT_COMPUTED] = REST_COLOUR
    print(f"recolouring the whole mesh, the rest grey: {time.perf_counter() - t:.2f} s")


if __name__ == "__main__":
    main()
