"""Speed and memory of every estimator variant, with libigl and VTK as peers.

Run by hand (not part of the test suite)::

    .venv/bin/python benchmarks/bench_estimators.py --sizes 100000 1000000
    .venv/bin/python benchmarks/bench_estimators.py --sizes 1000000 --only mru:2 nc:4

Each measurement runs in a fresh subprocess; the mesh and its connectivity are built first, then
resident memory is sampled during the call, so "peak MB" is what the estimate itself adds above
the mesh (including the normals it computes and the result it returns). Times are wall-clock on
all cores (estimators run their blocks on a thread pool; ``CURV_THREADS`` limits it).

Meshes (``--mesh``):
- ``hexagon`` (default): the paper's test mesh (§5.1), the regular hexagon grid subdivided to about
  N vertices and lifted by the trigonometric patch: near-equilateral, valence 6, one border.
- ``torus``: a closed torus whose grid parameters are jittered: right-angled, uneven triangles whose
  longest 1-ring edge is ~1.4 mean edges, so every Rk support holds about twice as many vertices
  (R2: ~32, R4: ~130) as on the hexagon (R2: ~18, R4: ~60). A stress case.
"""

from __future__ import annotations

import argparse
import json
import os
import gc
import subprocess
import sys
import threading
import time

import numpy as np


def jittered_torus(n_target: int, *, R: float = 2.0, r: float = 0.8, seed: int = 0):
    """Closed irregular triangle torus with about ``n_target`` vertices: (vertices (n,3), faces (m,3))."""
    n_minor = int(round(np.sqrt(n_target * r / R)))
    n_major = int(round(n_target / n_minor))
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    theta = 2 * np.pi * (i.ravel() + 0.25 * rng.uniform(-1, 1, i.size)) / n_major
    phi = 2 * np.pi * (j.ravel() + 0.25 * rng.uniform(-1, 1, j.size)) / n_minor
    ring = R + r * np.cos(phi)
    v = np.stack([ring * np.cos(theta), ring * np.sin(theta), r * np.sin(phi)], axis=1)
    a = (i * n_minor + j).ravel()
    b = (((i + 1) % n_major) * n_minor + j).ravel()
    c = (((i + 1) % n_major) * n_minor + (j + 1) % n_minor).ravel()
    d = (i * n_minor + (j + 1) % n_minor).ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return v, faces


def hexagon_patch(n_target: int):
    """The paper's regular hexagon grid with about ``n_target`` vertices, lifted by sin(x^A) + cos(By)."""
    from curv.surfaces import TrigonometricPatch, hexagon_grid

    s = max(1, int(round((-3 + np.sqrt(9 + 12 * (n_target - 1))) / 6)))
    sampled = TrigonometricPatch(A=1.5, B=1.2).sample(hexagon_grid(3 * s * (s + 1) + 1).mesh)
    return np.asarray(sampled.mesh.vertices), sampled.mesh.triangles


MESHES = {"hexagon": hexagon_patch, "torus": jittered_torus}


class PeakRSS:
    """Samples this process's resident memory every 5 ms on a thread; ``peak`` is the largest seen.

    ``ru_maxrss`` is a high-water mark for the whole process, so it cannot isolate one call when
    building the mesh already went higher; sampling can.
    """

    def __init__(self):
        import psutil

        self._proc = psutil.Process()
        self.base = self._proc.memory_info().rss
        self.peak = self.base
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while not self._stop.wait(0.005):
            self.peak = max(self.peak, self._proc.memory_info().rss)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, self._proc.memory_info().rss)

    @property
    def above_base_mb(self) -> float:
        return (self.peak - self.base) / 2**20


def _child(kind: str, name: str, k: int, n: int, mesh_kind: str) -> dict:
    """Runs in the subprocess: build the mesh, take the baseline, time one estimate."""
    v, f = MESHES[mesh_kind](n)
    if kind == "curv":
        import curv

        mesh = curv.Mesh(v, f)
        t0 = time.perf_counter()
        for attr in ("edges", "adjacency", "longest_edge", "edge_faces", "vertex_faces", "degenerate_faces",
                     "border_vertices", "nonmanifold_vertices", "face_normals",
                     "vertex_corners", "corner_next", "corner_prev", "inconsistent_edges", "isolated_vertices"):
            getattr(mesh, attr)
        prep = time.perf_counter() - t0
        gc.collect()
        with PeakRSS() as mem:
            t0 = time.perf_counter()
            res = curv.estimate(mesh, name, k)
            seconds = time.perf_counter() - t0
        extra = {"valid": float(res.valid.mean()), "prep_seconds": prep}
    elif kind == "igl":
        import igl

        gc.collect()
        with PeakRSS() as mem:
            t0 = time.perf_counter()
            igl.principal_curvature(v, f.astype(np.int64), radius=k)
            seconds = time.perf_counter() - t0
        extra = {}
    elif kind == "vtk":
        import pyvista as pv
        import vtk

        poly = pv.PolyData.from_regular_faces(v, f)
        gc.collect()
        with PeakRSS() as mem:
            t0 = time.perf_counter()
            for mode in ("SetCurvatureTypeToMean", "SetCurvatureTypeToGaussian"):
                flt = vtk.vtkCurvatures()
                flt.SetInputData(poly)
                getattr(flt, mode)()
                flt.Update()
            seconds = time.perf_counter() - t0
        extra = {}
    else:
        raise ValueError(kind)
    return {"seconds": seconds, "peak_above_mesh_mb": mem.above_base_mb, **extra}


def run_one(kind: str, name: str, k: int, n: int, mesh_kind: str, repeat: int = 1) -> dict:
    """Best of ``repeat`` fresh subprocesses: the fastest time, and the largest peak memory seen."""
    cmd = [sys.executable, __file__, "--child", kind, name, str(k), str(n), mesh_kind]
    runs = []
    for _ in range(repeat):
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            return {"error": (out.stderr.strip().splitlines() or ["failed"])[-1]}
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    best = min(runs, key=lambda r: r["seconds"])
    return {**best, "peak_above_mesh_mb": max(r["peak_above_mesh_mb"] for r in runs)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    parser.add_argument("--only", nargs="*", help="variants as name:k (default all)")
    parser.add_argument("--no-peers", action="store_true", help="skip libigl and VTK")
    parser.add_argument("--mesh", choices=sorted(MESHES), default="hexagon", help="benchmark mesh (see above)")
    parser.add_argument("--repeat", type=int, default=1,
                        help="runs per variant, each a fresh process; the fastest is reported (shared "
                             "machines vary by tens of percent from run to run)")
    parser.add_argument("--child", nargs=5, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        kind, name, k, n, mesh_kind = args.child
        print(json.dumps(_child(kind, name, int(k), int(n), mesh_kind)))
        return 0

    import curv
    from curv.estimators import all_variants

    variants = [tuple(v.split(":")) for v in args.only] if args.only else all_variants()
    variants = [(m, int(k)) for m, k in variants]
    print(f"# cores: {os.cpu_count()}, numpy {np.__version__}, curv {curv.__version__}, best of {args.repeat}")
    for n in args.sizes:
        v, _ = MESHES[args.mesh](n)
        print(f"\n## {args.mesh}, {len(v)} vertices")
        print(f"{'variant':<12} {'seconds':>8} {'peak MB':>8} {'valid':>6}   vs igl R2  vs VTK")
        peers = {}
        if not args.no_peers:
            peers["igl"] = run_one("igl", "principal_curvature", 2, n, args.mesh, args.repeat)
            peers["vtk"] = run_one("vtk", "curvatures", 0, n, args.mesh, args.repeat)
        for m, k in variants:
            r = run_one("curv", m, k, n, args.mesh, args.repeat)
            if "error" in r:
                print(f"{m + ' R' + str(k):<12} error: {r['error']}")
                continue
            ratios = "  ".join(
                f"{peers[p]['seconds'] / r['seconds']:8.2f}x" if "seconds" in peers.get(p, {}) else "       -"
                for p in ("igl", "vtk"))
            print(f"{m + ' R' + str(k):<12} {r['seconds']:8.2f} {r['peak_above_mesh_mb']:8.0f} "
                  f"{r['valid']:6.3f}   {ratios}", flush=True)
        for p, r in peers.items():
            text = f"{r['seconds']:8.2f} {r['peak_above_mesh_mb']:8.0f}" if "seconds" in r else f"error: {r['error']}"
            label = "libigl R2" if p == "igl" else "VTK H+K"
            print(f"{label:<12} {text}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
