"""The fits' default call timed in one process, the mesh's set-up out of the timing.

``bench_estimators.py`` times one call per fresh process, connectivity included; at a few hundred
thousand vertices a fit's own work is a fraction of a second of that, below the noise of a shared
machine. This builds the sphere once, warms each variant on it (kernels, the mesh's cached
connectivity and lengths), then takes the best of ``--repeat`` calls' CPU seconds (every thread)
and wall seconds per variant, standard errors off. Compare two trees by running it alternately
with each on ``PYTHONPATH`` and taking the ratios run by run::

    PYTHONPATH=TREE_A python benchmarks/bench_fits_inprocess.py --out a1.json
    PYTHONPATH=TREE_B python benchmarks/bench_fits_inprocess.py --out b1.json   # and again, A B A B ...
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_estimators import MESHES  # noqa: E402

VARIANTS = ("nc:2", "qs:2", "an:2", "mru:2", "jet:2", "qs:4", "an:3", "mru:3")


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=400_000, help="vertices of the sphere (about)")
    parser.add_argument("--only", nargs="*", default=list(VARIANTS), help="variants as name:k")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", help="write the {variant: [cpu s, wall s]} table here (JSON)")
    args = parser.parse_args(argv)
    import curv

    mesh = curv.Mesh(*MESHES["sphere"](args.size))
    variants = [(m, float(k)) for m, k in (v.split(":") for v in args.only)]
    for m, k in variants:
        curv.estimate(mesh, m, k, standard_errors=False)
    out = {}
    for m, k in variants:
        best = (float("inf"), float("inf"))
        for _ in range(args.repeat):
            t0, c0 = time.perf_counter(), time.process_time()
            curv.estimate(mesh, m, k, standard_errors=False)
            best = min(best, (time.process_time() - c0, time.perf_counter() - t0))
        out[f"{m}:{k:g}"] = best
        print(f"{m} R{k:g}: cpu {best[0]:.3f} s, wall {best[1]:.3f} s", flush=True)
    if args.out:
        Path(args.out).write_text(json.dumps(out))
    return out


if __name__ == "__main__":
    main()
