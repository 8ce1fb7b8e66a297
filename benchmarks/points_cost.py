"""The per-point cost of a whole point-cloud estimate, two source trees side by side (issue 33, item 5).

Usage::

    python benchmarks/points_cost.py BEFORE_TREE AFTER_TREE [--n 1000000] [--methods qs mru jet]
                                     [--range 2] [--rounds 1]

Each call runs in a fresh process with ``PYTHONPATH`` set to one tree (warmed up on 500 points
first, so numba's cache is loaded, not timed): ``curv.estimate(curv.PointCloud(points), method,
range)`` on uniform random points of a unit sphere (seed 0), wall and CPU seconds of the call.
The trees alternate call by call (before, after, before, ...) so that both see the same load;
scipy's cKDTree k = 20 query plus pgeof's covariance features on that kNN run in the same
rounds. At the end the results of the two trees are compared: the largest difference of k1, k2
over the points valid in both, and the points whose validity or reason differs.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

_CHILD = r"""
import json, sys, time
import numpy as np

def sphere(n):
    p = np.random.default_rng(0).normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True)

kind, method, rng, n, out = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
pts = sphere(n)
if kind == "curv":
    import curv
    curv.estimate(curv.PointCloud(sphere(500)), method, rng)
    t0, c0 = time.perf_counter(), time.process_time()
    res = curv.estimate(curv.PointCloud(pts), method, rng)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    np.savez(out, k1=res.k1, k2=res.k2, valid=res.valid, reason=res.reason)
else:
    import pgeof
    from scipy.spatial import cKDTree
    t0, c0 = time.perf_counter(), time.process_time()
    _, nn = cKDTree(pts).query(pts, 21, workers=-1)
    flat = nn[:, 1:].astype(np.uint32).ravel()
    pgeof.compute_features(pts.astype(np.float32), flat, (np.arange(n + 1) * 20).astype(np.uint32))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
print(json.dumps({"wall": wall, "cpu": cpu}))
"""


def _run(tree: str | None, kind: str, method: str, rng: float, n: int, out: str) -> dict:
    env = dict(os.environ)
    if tree is not None:
        env["PYTHONPATH"] = str(Path(tree).resolve())
    # run in the tree itself: ``python -c`` puts the working directory first on sys.path, ahead of
    # PYTHONPATH, so from another tree's root both "trees" would import that one
    proc = subprocess.run([sys.executable, "-c", _CHILD, kind, method, str(rng), str(n), out],
                          capture_output=True, text=True, env=env, cwd=None if tree is None else Path(tree).resolve())
    if proc.returncode:
        raise SystemExit(f"{kind} {method} in {tree}: {proc.stderr.strip().splitlines()[-1:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _compare(a: str, b: str) -> str:
    x, y = np.load(a), np.load(b)
    both = x["valid"] & y["valid"]
    worst = max(float(np.abs(x[q][both] - y[q][both]).max(initial=0.0)) for q in ("k1", "k2"))
    same = all(np.array_equal(x[q][both], y[q][both]) for q in ("k1", "k2"))
    return (f"{'bit-identical' if same else f'largest |dk| {worst:.3g}'}; validity differs at "
            f"{int((x['valid'] != y['valid']).sum())}, reason at {int((x['reason'] != y['reason']).sum())} points")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--methods", nargs="+", default=["qs", "mru", "jet"])
    parser.add_argument("--range", type=float, default=2.0)
    parser.add_argument("--rounds", type=int, default=1)
    args = parser.parse_args()
    trees = {"before": args.before, "after": args.after}
    times: dict[tuple[str, str], list[dict]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.rounds):
            times.setdefault(("peer", "cKDTree+pgeof"), []).append(_run(None, "peer", "-", 0, args.n, ""))
            for m in args.methods:
                for label, tree in trees.items():
                    times.setdefault((label, m), []).append(
                        _run(tree, "curv", m, args.range, args.n, os.path.join(tmp, f"{label}-{m}.npz")))
                    print(label, m, times[label, m][-1], flush=True)
        peer = times["peer", "cKDTree+pgeof"]
        pw, pc = (float(np.median([t[q] for t in peer])) for q in ("wall", "cpu"))
        print(f"\n{args.n} points, R{args.range:g}, median of {args.rounds} round(s), load {os.getloadavg()[0]:.1f}")
        print(f"{'variant':<16} {'wall s':>8} {'CPU s':>8}  {'peer/this wall':>14} {'peer/this CPU':>13}")
        print(f"{'cKDTree+pgeof':<16} {pw:8.2f} {pc:8.2f}")
        for m in args.methods:
            for label in trees:
                w, c = (float(np.median([t[q] for t in times[label, m]])) for q in ("wall", "cpu"))
                print(f"{m + ' ' + label:<16} {w:8.2f} {c:8.2f}  {pw / w:13.2f}x {pc / c:12.2f}x")
            print(f"{'':<16} {_compare(os.path.join(tmp, f'before-{m}.npz'), os.path.join(tmp, f'after-{m}.npz'))}")
        print(time.strftime("%Y-%m-%d %H:%M"))


if __name__ == "__main__":
    main()
