"""What the advisor's self-check costs against one default estimate, on a 100k-vertex mesh and cloud.

Run by hand (not part of the test suite)::

    python benchmarks/bench_advise_cost.py                    # 100k, 3 alternating rounds
    python benchmarks/bench_advise_cost.py --vertices 30000 --rounds 2

The mesh is a noisy Monge patch of the study (trigonometric, the hexagon with s = 182: 99,919
vertices, 10 degrees irregular, half the paper's noise); the cloud is 100,000 random points of the
same surface with the same noise. Each round, in turn and each on a fresh input object (nothing
cached from the round before: connectivity, grids and normals are built again, as for a file just
loaded):

- one default estimate (``curv.estimate(input)``: mru R2, the default normals);
- ``curv.advise(input, check=False)``: the table's ranking alone (on a cloud: the prior order);
- ``curv.advise(input)``: the same and the self-check; its check part is timed by the check itself
  (``Advice.check.seconds``).

Reported: the medians over the rounds, wall seconds, and the ratios to the default estimate; and the
processor seconds of the default estimate and of the check (every thread of the process together),
which move less with the machine's load than the wall times, with their ratio from the two medians
and the median of the per-round ratios (``ratio_cpu`` in each round's line). The issue's bound: the self-check at
most 10x one default estimate at 100k. ``--profile FILE`` writes a ``cProfile`` of one checked advice
on the mesh (after the rounds) to FILE and prints its 25 largest cumulative entries. The kernels are compiled
before the first round (a warm-up call on a small input of each kind) so that no round pays a compile.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def inputs(n_vertices: int):
    """(vertices, faces) of the mesh and the cloud's points: a noisy study patch and points of its surface."""
    from curv.study.protocol import Task
    from curv.study.testmesh import build_test_mesh
    from curv.surfaces import sample_points

    s = int(round((-3 + np.sqrt(9 + 12 * (n_vertices - 1))) / 6))
    tm = build_test_mesh(Task(7, "trigonometric", 3 * s * (s + 1) + 1, 10.0, 0.5, 0))
    rng = np.random.default_rng(1)
    sampled = sample_points(tm.sampled.surface, n_vertices, rng=rng)
    points = sampled.cloud.points + rng.normal(scale=tm.noise_sigma, size=sampled.cloud.points.shape)
    return (tm.mesh.vertices.copy(), tm.mesh.faces.copy()), points


def time_round(kind: str, data) -> dict:
    """One round on a fresh input: the default estimate, the table-only advice, the checked advice."""
    import curv

    def fresh():
        return curv.Mesh(*data) if kind == "mesh" else curv.PointCloud(data)

    out = {}
    t0, cpu0 = time.perf_counter(), time.process_time()
    curv.estimate(fresh())
    out["estimate"] = time.perf_counter() - t0
    out["estimate_cpu"] = time.process_time() - cpu0
    t0, cpu0 = time.perf_counter(), time.process_time()
    curv.advise(fresh(), check=False)
    out["table"] = time.perf_counter() - t0
    out["table_cpu"] = time.process_time() - cpu0
    t0, cpu0 = time.perf_counter(), time.process_time()
    adv = curv.advise(fresh())
    out["checked"] = time.perf_counter() - t0
    out["checked_cpu"] = time.process_time() - cpu0
    out["check"] = adv.check.seconds
    out["check_cpu"] = adv.check.cpu_seconds
    out["calls"] = len(adv.check.measured)
    out["ratio_cpu"] = out["check_cpu"] / out["estimate_cpu"]
    return out


def main(argv=None) -> int:
    import curv

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vertices", type=int, default=100_000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--kinds", nargs="+", default=["mesh", "cloud"], choices=["mesh", "cloud"])
    parser.add_argument("--profile", help="write a cProfile of one checked advice on the mesh here")
    args = parser.parse_args(argv)
    mesh_data, points = inputs(args.vertices)
    data = {"mesh": mesh_data, "cloud": points}
    # compile every kernel the rounds use on small inputs first
    warm_mesh, warm_points = inputs(3000)
    for kind, d in (("mesh", warm_mesh), ("cloud", warm_points)):
        if kind in args.kinds:
            time_round(kind, d)
    rows = {kind: [] for kind in args.kinds}
    for r in range(args.rounds):
        for kind in args.kinds:
            rows[kind].append(time_round(kind, data[kind]))
            print(f"round {r + 1} {kind}: " + ", ".join(f"{k} {v:.2f}" for k, v in rows[kind][-1].items()), flush=True)
    print()
    print(f"| input ({args.vertices:,}) | default estimate | advise, table only | advise, checked | the check | "
          f"check / estimate | checked advise / estimate | CPU: estimate, check, check / estimate "
          f"(from the medians; per round, median) |")
    print("|---|---|---|---|---|---|---|---|")
    for kind, rs in rows.items():
        med = {k: float(np.median([x[k] for x in rs])) for k in rs[0]}
        print(f"| {kind} | {med['estimate']:.2f} s | {med['table']:.2f} s | {med['checked']:.2f} s | "
              f"{med['check']:.2f} s ({int(med['calls'])} calls) | {med['check'] / med['estimate']:.1f}x | "
              f"{med['checked'] / med['estimate']:.1f}x | {med['estimate_cpu']:.2f} s, {med['check_cpu']:.2f} s, "
              f"{med['check_cpu'] / med['estimate_cpu']:.1f}x; {med['ratio_cpu']:.1f}x |")
    cmd = "benchmarks/bench_advise_cost.py " + " ".join(sys.argv[1:] if argv is None else argv)
    print(f"\nCommand: `{cmd}`; medians of {args.rounds} alternating rounds, wall seconds, "
          f"{curv.core.jit.threads()} threads.")
    if args.profile:
        profile(mesh_data, args.profile)
    return 0


def profile(mesh_data, path: str) -> None:
    """A cProfile of one checked advice on a fresh mesh, written to ``path``; its largest entries printed."""
    import cProfile
    import pstats

    import curv

    mesh = curv.Mesh(*mesh_data)
    cProfile.runctx("curv.advise(mesh)", {"curv": curv}, {"mesh": mesh}, path)
    pstats.Stats(path).sort_stats("cumulative").print_stats(25)


if __name__ == "__main__":
    sys.exit(main())
