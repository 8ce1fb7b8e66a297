"""Large-mesh benchmark: write a torus with N vertices as binary PLY, then time `curv estimate` on it.

Usage::

    python benchmarks/bench_large.py write --vertices 10000000 --out /tmp/torus10M.ply
    nice /usr/bin/time -v curv estimate /tmp/torus10M.ply -m mru -r 2 -q
    python benchmarks/bench_large.py calibrate     # peak RSS of `curv estimate` at a few sizes
    python benchmarks/bench_large.py viewer --ply /tmp/torus10M.ply --rounds 2 --baseline 1000
        # the viewer's time to first picture and peak RSS against `curv estimate`'s, runs alternating;
        # --baseline adds both tools on a 1000-vertex torus (their fixed start-up)

The torus is closed (no border), a regular (major x minor) grid split into triangles, so every
estimator has work at every vertex. Written with numpy in one go: no per-vertex Python.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def torus(n_vertices: int, R: float = 3.0, r: float = 1.0):
    """(vertices (n, 3) float64, faces (2n, 3) int32) of a closed torus with about ``n_vertices`` vertices."""
    n_minor = max(8, int(round(np.sqrt(n_vertices * r / R))))
    n_major = max(8, int(round(n_vertices / n_minor)))
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    theta = (2 * np.pi / n_major) * i.ravel()
    phi = (2 * np.pi / n_minor) * j.ravel()
    ring = R + r * np.cos(phi)
    v = np.stack([ring * np.cos(theta), ring * np.sin(theta), r * np.sin(phi)], axis=1)
    del theta, phi, ring
    a = (i * n_minor + j).ravel().astype(np.int32)
    b = (((i + 1) % n_major) * n_minor + j).ravel().astype(np.int32)
    c = (((i + 1) % n_major) * n_minor + (j + 1) % n_minor).ravel().astype(np.int32)
    d = (i * n_minor + (j + 1) % n_minor).ravel().astype(np.int32)
    faces = np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
    return v, faces


def write_ply(path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Binary little-endian PLY (float64 x, y, z; uchar-counted int32 triangles)."""
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
              "property double x\nproperty double y\nproperty double z\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    face = np.empty(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"] = 3
    face["i"] = faces
    with open(path, "wb") as fh:
        fh.write(header.encode("ascii"))
        fh.write(np.ascontiguousarray(vertices, dtype="<f8").tobytes())
        fh.write(face.tobytes())


def measure(path, method: str, k: int, curv_exe: str) -> dict:
    """Run ``curv estimate`` under ``/usr/bin/time -v``; return peak RSS (bytes), wall seconds, exit status."""
    cmd = ["/usr/bin/time", "-v", curv_exe, "estimate", str(path), "-m", method, "-r", str(k), "-q",
           "--no-memory-check"]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr)
    return {"method": method, "range": k, "peak_bytes": int(rss.group(1)) * 1024 if rss else None,
            "seconds": round(wall, 2), "status": proc.returncode, "stdout": proc.stdout.strip().splitlines()}


def _time_v(cmd: list[str], env=None) -> dict:
    """Run ``cmd`` (whose first words may wrap ``/usr/bin/time -v``); wall seconds, CPU seconds (user +
    system) and peak RSS of the timed process from time's report, and the exit status."""
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    out = proc.stderr
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)", out)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", out)
    cpu = [float(x) for x in re.findall(r"(?:User|System) time \(seconds\): ([\d.]+)", out)]
    secs = None
    if wall:
        secs = 0.0
        for part in wall.group(1).split(":"):
            secs = 60.0 * secs + float(part)
    return {"seconds": secs, "cpu_seconds": round(sum(cpu), 2) if cpu else None,
            "peak_bytes": int(rss.group(1)) * 1024 if rss else None, "status": proc.returncode}


def viewer_against_cli(path, method: str, k: int, rounds: int, python: str, screenshot: str,
                       baseline: str | None = None) -> list[dict]:
    """Alternate ``curv estimate PATH -m METHOD -r K -q`` and ``curvlab PATH --method METHOD --range K
    --screenshot PNG`` (under ``xvfb-run`` without a display), each under ``/usr/bin/time -v``.

    The CLI's run is its estimate with the mesh report and no output file: the same work the viewer
    does before its picture (the viewer writes a PNG, not the curvature file). With ``baseline`` (a
    small mesh file) both tools also run on it in every round, and the summary adds what the large
    mesh costs each tool beyond its fixed start-up (the large run's figure minus the small one's).
    """
    import os
    import shutil

    def commands(mesh):
        cli = ["/usr/bin/time", "-v", python, "-m", "curv.cli", "estimate", str(mesh), "-m", method, "-r", str(k), "-q"]
        gui = ["/usr/bin/time", "-v", python, "-m", "app.main", str(mesh), "--method", method, "--range", str(k),
               "--screenshot", screenshot]
        if not os.environ.get("DISPLAY") and shutil.which("xvfb-run"):
            gui = ["xvfb-run", "-a", "-s", "-screen 0 1600x1000x24", *gui]
        return (("cli", cli), ("viewer", gui))

    meshes = [("mesh", path)] + ([("baseline", baseline)] if baseline else [])
    rows = []
    for r in range(rounds):
        for which, mesh in meshes:
            for tool, cmd in commands(mesh):
                row = _time_v(cmd)
                row.update(tool=tool, mesh=which, round=r)
                print(json.dumps(row), flush=True)
                rows.append(row)
    medians = {}
    for which, _ in meshes:
        for tool in ("cli", "viewer"):
            runs = [x for x in rows if x["tool"] == tool and x["mesh"] == which and x["status"] == 0]
            if not runs:
                continue
            med = {key: float(np.median([x[key] for x in runs])) for key in ("seconds", "cpu_seconds", "peak_bytes")}
            medians[which, tool] = med
            print(f"{which:>8} {tool:>6}: median wall {med['seconds']:.1f} s, CPU {med['cpu_seconds']:.1f} s, "
                  f"peak RSS {med['peak_bytes'] / 1e9:.2f} GB over {len(runs)} runs")
    keys = [("mesh", "cli"), ("mesh", "viewer")]
    if all(key in medians for key in keys):
        cli, gui = (medians[key] for key in keys)
        print(f"viewer / CLI: wall {gui['seconds'] / cli['seconds']:.2f}x, CPU {gui['cpu_seconds'] / cli['cpu_seconds']:.2f}x, "
              f"peak {gui['peak_bytes'] / cli['peak_bytes']:.2f}x")
        if all(("baseline", tool) in medians for tool in ("cli", "viewer")):
            def beyond(tool, key):
                return medians["mesh", tool][key] - medians["baseline", tool][key]
            print("beyond each tool's start-up on the baseline mesh, viewer / CLI: "
                  f"wall {beyond('viewer', 'seconds') / beyond('cli', 'seconds'):.2f}x, "
                  f"CPU {beyond('viewer', 'cpu_seconds') / beyond('cli', 'cpu_seconds'):.2f}x, "
                  f"peak {beyond('viewer', 'peak_bytes') / beyond('cli', 'peak_bytes'):.2f}x")
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    w = sub.add_parser("write", help="write a torus PLY")
    w.add_argument("--vertices", type=int, default=10_000_000)
    w.add_argument("--out", required=True)
    c = sub.add_parser("calibrate", help="peak memory of curv estimate at a few sizes, as JSON lines")
    c.add_argument("--sizes", type=int, nargs="+", default=[100_000, 400_000])
    c.add_argument("--variants", nargs="+", default=["mru:2", "mru:4", "nc:1", "qs:4", "an:4", "meyer:1"])
    c.add_argument("--curv", default=str(Path(sys.executable).with_name("curv")))
    g = sub.add_parser("viewer", help="the viewer's time to first picture and peak RSS against the CLI's")
    g.add_argument("--ply", required=True)
    g.add_argument("--method", default="mru")
    g.add_argument("--range", type=int, default=2)
    g.add_argument("--rounds", type=int, default=2)
    g.add_argument("--screenshot", default=str(Path(tempfile.gettempdir()) / "curvlab-first-picture.png"))
    g.add_argument("--baseline", type=int, metavar="N", default=0,
                   help="also run both tools on an N-vertex torus each round (e.g. 1000): the fixed start-up")
    args = parser.parse_args(argv)
    if args.command == "viewer":
        with tempfile.TemporaryDirectory() as tmp:
            baseline = None
            if args.baseline:
                baseline = Path(tmp) / f"torus{args.baseline}.ply"
                write_ply(baseline, *torus(args.baseline))
            viewer_against_cli(args.ply, args.method, args.range, args.rounds, sys.executable, args.screenshot,
                               baseline)
        return 0
    if args.command == "write":
        t0 = time.perf_counter()
        v, f = torus(args.vertices)
        write_ply(args.out, v, f)
        print(f"wrote {args.out}: {len(v)} vertices, {len(f)} faces in {time.perf_counter() - t0:.1f} s")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            path = Path(tmp) / f"torus{n}.ply"
            v, f = torus(n)
            write_ply(path, v, f)
            for variant in args.variants:
                method, k = variant.split(":")
                row = measure(path, method, int(k), args.curv)
                row.update(vertices=len(v), faces=len(f))
                row.pop("stdout")
                print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
