"""Whether two trees of curv give the same point-cloud estimates: k1, k2, directions, normals, valid
and reason of ``qs``, ``mru`` and ``jet`` at R2 (the default range and normals) on the clouds the
point-cost work is checked on (issue 33, item 5).

    PYTHONPATH=<tree before> python benchmarks/points_same.py save before.npz [--big 1000000]
    PYTHONPATH=<tree after>  python benchmarks/points_same.py save after.npz [--big 1000000]
    python benchmarks/points_same.py compare before.npz after.npz

The clouds: uniform random points of a unit sphere (seed 0, as ``points_cost.py``; ``--big`` points,
0 to leave it out), a blue-noise sphere, an open quadratic patch, scan rows 4:1 apart, and laspy's
sample scans (``tests/laspy_samples.py``) when they can be had. ``compare`` prints, per cloud and
method, the largest difference of k1, k2 (relative to the largest |k|) and of the directions over the
points valid in both, and the points whose validity or reason differs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

METHODS = ("qs", "mru", "jet")
FIELDS = ("k1", "k2", "d1", "d2", "normals", "valid", "reason")


def _clouds(big: int):
    import curv
    from curv.surfaces import QuadraticPatch, Sphere, sample_points

    if big:
        p = np.random.default_rng(0).normal(size=(big, 3))
        yield f"sphere{big}", curv.PointCloud(p / np.linalg.norm(p, axis=1, keepdims=True))
    yield "blue-sphere", sample_points(Sphere(1.0), 4000, sampling="blue", rng=6).cloud
    yield "open-patch", sample_points(QuadraticPatch(), 8000, rng=3).cloud
    yield "scan-rows", sample_points(QuadraticPatch(), 10000, sampling="rows", ratio=4, rng=12).cloud
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    try:
        from tests.laspy_samples import SAMPLES, laspy_sample

        for name in SAMPLES:
            yield name, curv.load(laspy_sample(name))
    except BaseException as exc:  # pytest's skip when the samples cannot be had
        print(f"laspy samples left out: {exc}", file=sys.stderr)


def save(path: str, big: int) -> None:
    import curv

    arrays = {}
    for name, cloud in _clouds(big):
        for method in METHODS:
            res = curv.estimate(cloud, method, 2)
            for field in FIELDS:
                arrays[f"{name}/{method}/{field}"] = np.asarray(getattr(res, field))
            print(name, method, int(res.valid.sum()), "valid of", res.valid.size, flush=True)
    np.savez(path, **arrays)


def compare(before: str, after: str) -> int:
    a, b = np.load(before), np.load(after)
    differing = 0
    for key in sorted({k.rsplit("/", 1)[0] for k in a.files}):
        if f"{key}/k1" not in b.files:
            continue
        get = {f: (a[f"{key}/{f}"], b[f"{key}/{f}"]) for f in FIELDS}
        same = all(np.array_equal(x, y, equal_nan=x.dtype.kind == "f") for x, y in get.values())
        both = get["valid"][0] & get["valid"][1]
        scale = max(np.abs(get["k1"][0][both]).max(initial=0.0), np.abs(get["k2"][0][both]).max(initial=0.0), 1e-300)
        dk = max(np.abs(get[f][0][both] - get[f][1][both]).max(initial=0.0) for f in ("k1", "k2"))
        dd = max(np.abs(get[f][0][both] - get[f][1][both]).max(initial=0.0) for f in ("d1", "d2"))
        reasons = int((get["reason"][0] != get["reason"][1]).sum())
        valid = int((get["valid"][0] != get["valid"][1]).sum())
        differing += not same
        print(f"{key:32s} {'bit-identical' if same else 'differs':14s} k {dk:.2e} ({dk / scale:.1e} rel)  "
              f"directions {dd:.1e}  valid differs at {valid}, reason at {reasons}")
    return 1 if differing else 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    s = sub.add_parser("save")
    s.add_argument("path")
    s.add_argument("--big", type=int, default=0)
    c = sub.add_parser("compare")
    c.add_argument("before")
    c.add_argument("after")
    args = parser.parse_args(argv)
    if args.command == "save":
        save(args.path, args.big)
        return 0
    return compare(args.before, args.after)


if __name__ == "__main__":
    sys.exit(main())
