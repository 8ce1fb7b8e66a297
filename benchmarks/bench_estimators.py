"""Speed and memory of every estimator variant, with trueform, libigl and VTK as peers.

Run by hand (not part of the test suite)::

    .venv/bin/python benchmarks/bench_estimators.py --sizes 100000 1000000
    .venv/bin/python benchmarks/bench_estimators.py --sizes 1000000 --only mru:2 nc:4

Each measurement runs in a fresh subprocess. The vertex and face arrays are built first; then, as a
new user would call it, a fresh ``curv.Mesh`` is made and estimated inside the timed region, so
the connectivity every first estimate pays is included ("seconds"); the connectivity alone is
reported as well ("conn s", on another fresh Mesh), and the CPU seconds of the timed call ("cpu s":
on a machine shared with other jobs their ratios vary less than those of wall time; in brackets, the
peers' CPU seconds over the variant's). Before timing, each child calls the same estimator once on
a tiny mesh, so numba's kernels are loaded from the on-disk cache (the first-run compile and the
cold start are reported by ``--compile``). Resident memory is sampled during the
call, so "peak MB" is what the estimate adds above the vertex and face arrays. Times are
wall-clock on all cores (``CURV_THREADS`` limits the kernels' threads).

Meshes (``--mesh``):
- ``sphere`` (default): a geodesic unit sphere (icosahedron, faces split f^2 times, 10 f^2 + 2
  vertices): near-equilateral, valence 6 (5 at 12 vertices), closed.
- ``hexagon`` (default): the paper's test mesh (§5.1), the regular hexagon grid subdivided to about
  N vertices and lifted by the trigonometric patch: near-equilateral, valence 6, one border.
- ``torus``: a closed torus whose grid parameters are jittered: right-angled, uneven triangles whose
  longest 1-ring edge is ~1.4 mean edges, so every Rk support holds about twice as many vertices
  (R2: ~32, R4: ~130) as on the hexagon (R2: ~18, R4: ~60). A stress case.
- ``--shuffle``: any of them with its vertices numbered at random (the same numbering for every
  peer): a mesh whose neighbours are far apart in memory, as a careless export leaves it.

Point clouds (``--points``)::

    .venv/bin/python benchmarks/bench_estimators.py --points --sizes 1000000

N uniform random points of the unit sphere (seed 0), no normals. Timed: the whole
``curv.estimate(curv.PointCloud(points), method, 2)`` (grid, nearest neighbours, spacing, PCA,
orientation and jet normals, borders, the estimate) for ``qs``, ``mru``, ``jet`` (``--only`` to
change), and in the same run the peers: scipy's cKDTree (build and k=20 query), cKDTree + pgeof's
covariance features on that kNN (no principal curvatures), and curv's own grid kNN (k=20) alone.
``cpu s`` is the process's CPU time over all its threads: on a shared machine the wall clock
follows the other jobs' load, the CPU seconds much less, so both ratios are printed.
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


def sphere(n_target: int):
    """Geodesic unit sphere with about ``n_target`` vertices: (vertices (n,3), faces (m,3))."""
    from curv.surfaces.tessellate import geodesic_sphere, sphere_frequency

    return geodesic_sphere(sphere_frequency(n_target))


MESHES = {"sphere": sphere, "hexagon": hexagon_patch, "torus": jittered_torus}


def shuffled(v: np.ndarray, f: np.ndarray, seed: int = 0):
    """The same mesh with its vertices numbered at random (``--shuffle``): (vertices (n,3), faces (m,3))."""
    perm = np.random.default_rng(seed).permutation(len(v))
    rank = np.empty_like(perm)
    rank[perm] = np.arange(perm.size)
    return v[perm], rank[f]


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


def sphere_points(n: int) -> np.ndarray:
    """(n, 3) uniform random points of the unit sphere (seed 0)."""
    p = np.random.default_rng(0).normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True)


def _points_child(kind: str, name: str, k: float, n: int, standard_errors: bool = False) -> dict:
    """A point-cloud measurement in the subprocess: see the module notes (``--points``)."""
    pts = sphere_points(n)
    extra = {}
    if kind == "curv":
        import curv

        curv.estimate(curv.PointCloud(sphere_points(500)), name, k, standard_errors=standard_errors)  # from the cache
        gc.collect()
        with PeakRSS() as mem:
            t0, c0 = time.perf_counter(), time.process_time()
            res = curv.estimate(curv.PointCloud(pts), name, k, standard_errors=standard_errors)
            seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
        extra["valid"] = float(res.valid.mean())
        extra["mean_H"] = float(np.median(res.mean[res.valid]))
    elif kind == "gridknn":
        from curv.core.knn import nearest_neighbours

        nearest_neighbours(sphere_points(500), 20)
        gc.collect()
        with PeakRSS() as mem:
            t0, c0 = time.perf_counter(), time.process_time()
            nearest_neighbours(pts, 20)
            seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    elif kind in ("ckdtree", "pgeof"):
        from scipy.spatial import cKDTree

        if kind == "pgeof":
            import pgeof
        gc.collect()
        with PeakRSS() as mem:
            t0, c0 = time.perf_counter(), time.process_time()
            _, nn = cKDTree(pts).query(pts, 21, workers=-1)
            if kind == "pgeof":
                xyz = pts.astype(np.float32)
                flat = nn[:, 1:].astype(np.uint32).ravel()
                ptr = (np.arange(n + 1) * 20).astype(np.uint32)
                pgeof.compute_features(xyz, flat, ptr)
            seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    else:
        raise ValueError(kind)
    return {"seconds": seconds, "cpu_seconds": cpu, "peak_above_mesh_mb": mem.above_base_mb, **extra}


def run_points(args) -> None:
    """``--points``: curv's point estimators against cKDTree (+ pgeof) in the same run."""
    import curv

    variants = [tuple(v.split(":")) for v in args.only] if args.only else [("qs", 2), ("mru", 2), ("jet", 2)]
    print(f"# cores: {os.cpu_count()}, numpy {np.__version__}, curv {curv.__version__}, best of {args.repeat}")
    for n in args.sizes:
        print(f"\n## unit sphere, {n} uniform random points, no normals")
        peers = {label: run_one(kind, kind, 20, n, "points", args.repeat)
                 for label, kind in (("cKDTree k=20", "ckdtree"), ("cKDTree+pgeof", "pgeof"),
                                     ("curv grid k=20", "gridknn"))}
        print(f"{'variant':<16} {'seconds':>8} {'cpu s':>7} {'peak MB':>8} {'valid':>6} {'median H':>9}"
              f"  vs cKDTree+pgeof (wall, cpu)")
        for m, k in variants:
            r = run_one("curv", m, float(k), n, "points", args.repeat, args.standard_errors)
            label = f"{m} R{float(k):g}"
            if "error" in r:
                print(f"{label:<16} error: {r['error']}")
                continue
            ratio = peers["cKDTree+pgeof"].get("seconds", float("nan")) / r["seconds"]
            cpu_ratio = peers["cKDTree+pgeof"].get("cpu_seconds", float("nan")) / r["cpu_seconds"]
            print(f"{label:<16} {r['seconds']:8.2f} {r['cpu_seconds']:7.2f} {r['peak_above_mesh_mb']:8.0f} "
                  f"{r['valid']:6.4f} {r['mean_H']:9.5f}  {ratio:6.2f}x {cpu_ratio:6.2f}x", flush=True)
        for p, r in peers.items():
            text = (f"{r['seconds']:8.2f} {r['cpu_seconds']:7.2f} {r['peak_above_mesh_mb']:8.0f}" if "seconds" in r
                    else f"error: {r['error']}")
            print(f"{p:<16} {text}")


def _tiny(kind_mesh: str):
    return MESHES["sphere"](200)


def _child(kind: str, name: str, k: float, n: int, mesh_kind: str, standard_errors: bool = False) -> dict:
    """Runs in the subprocess: build the arrays, warm up on a tiny mesh, take the baseline, time one call."""
    if mesh_kind == "points":
        return _points_child(kind, name, k, n, standard_errors)
    mesh_kind, _, order = mesh_kind.partition(":")
    v, f = MESHES[mesh_kind](n)
    if order == "shuffled":
        v, f = shuffled(v, f)
    extra = {}
    if kind == "curv":
        import curv

        tv, tf_ = _tiny(mesh_kind)
        t0 = time.perf_counter()
        # kernels from the cache (or compiled)
        curv.estimate(curv.Mesh(tv, tf_), name, k, standard_errors=standard_errors)
        extra["warmup_seconds"] = time.perf_counter() - t0
        conn_mesh = curv.Mesh(v, f)
        t0 = time.perf_counter()
        for attr in ("adjacency", "longest_edge", "border_vertices", "nonmanifold_vertices",
                     "isolated_vertices", "inconsistent_edges", "degenerate_faces"):
            getattr(conn_mesh, attr)
        extra["conn_seconds"] = time.perf_counter() - t0
        del conn_mesh
        gc.collect()
        with PeakRSS() as mem:
            t0, c0 = time.perf_counter(), time.process_time()
            res = curv.estimate(curv.Mesh(v, f), name, k, standard_errors=standard_errors)
            seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
        extra["valid"] = float(res.valid.mean())
    elif kind == "trueform":
        import trueform as tf

        faces = np.ascontiguousarray(f, dtype=np.int32)
        tv, tf_ = _tiny(mesh_kind)
        tf.principal_curvatures((tf_.astype(np.int32), tv), k=int(k), directions=True)
        gc.collect()
        with PeakRSS() as mem:
            t0, c0 = time.perf_counter(), time.process_time()
            tf.principal_curvatures((faces, v), k=int(k), directions=True)
            seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    elif kind == "igl":
        import igl

        gc.collect()
        with PeakRSS() as mem:
            t0, c0 = time.perf_counter(), time.process_time()
            igl.principal_curvature(v, f.astype(np.int64), radius=int(k))
            seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    elif kind == "vtk":
        import pyvista as pv
        import vtk

        gc.collect()
        with PeakRSS() as mem:
            t0, c0 = time.perf_counter(), time.process_time()
            poly = pv.PolyData.from_regular_faces(v, f)
            for mode in ("SetCurvatureTypeToMean", "SetCurvatureTypeToGaussian"):
                flt = vtk.vtkCurvatures()
                flt.SetInputData(poly)
                getattr(flt, mode)()
                flt.Update()
            seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    else:
        raise ValueError(kind)
    return {"seconds": seconds, "cpu_seconds": cpu, "peak_above_mesh_mb": mem.above_base_mb, **extra}


def compile_times(variants) -> None:
    """First-run compile time and cached cold start per estimator, each in a fresh process.

    The compile run points numba at an empty cache folder (``NUMBA_CACHE_DIR``), so it measures
    what a first install pays; the cold start then loads that cache in a new process.
    """
    import tempfile

    code = ("import time, sys; t=time.perf_counter(); import curv; from curv.surfaces.tessellate import "
            "geodesic_sphere; v,f=geodesic_sphere(5); m=curv.Mesh(v,f); t1=time.perf_counter(); "
            "curv.estimate(m, sys.argv[1], float(sys.argv[2])); print(t1-t, time.perf_counter()-t1)")
    print(f"{'estimator':<10} {'import s':>8} {'compile s':>10} {'cold start s':>13}")
    seen = set()
    for name, k in variants:
        if name in seen:
            continue
        seen.add(name)
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            first = subprocess.run([sys.executable, "-c", code, name, str(k)], capture_output=True, text=True, env=env)
            second = subprocess.run([sys.executable, "-c", code, name, str(k)], capture_output=True, text=True, env=env)
        try:
            imp, comp = map(float, first.stdout.split())
            _, cold = map(float, second.stdout.split())
        except ValueError:
            print(f"{name:<10} error: {(first.stderr or second.stderr).strip().splitlines()[-1:]}")
            continue
        print(f"{name:<10} {imp:8.2f} {comp:10.2f} {cold:13.2f}", flush=True)


def run_one(kind: str, name: str, k: float, n: int, mesh_kind: str, repeat: int = 1,
            standard_errors: bool = False) -> dict:
    """Best of ``repeat`` fresh subprocesses: the fastest time, and the largest peak memory seen."""
    cmd = [sys.executable, __file__, "--child", kind, name, str(k), str(n), mesh_kind, str(int(standard_errors))]
    runs = []
    for _ in range(repeat):
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            return {"error": (out.stderr.strip().splitlines() or ["failed"])[-1]}
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    best = min(runs, key=lambda r: r["seconds"])
    return {**best, "peak_above_mesh_mb": max(r["peak_above_mesh_mb"] for r in runs),
            "cpu_seconds": min(r.get("cpu_seconds", float("nan")) for r in runs)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    parser.add_argument("--only", nargs="*", help="variants as name:k (default all)")
    parser.add_argument("--no-peers", action="store_true", help="skip trueform, libigl and VTK")
    parser.add_argument("--mesh", choices=sorted(MESHES), default="sphere", help="benchmark mesh (see above)")
    parser.add_argument("--shuffle", action="store_true",
                        help="number the mesh's vertices at random (seed 0), for every peer alike")
    parser.add_argument("--compile", action="store_true",
                        help="measure first-run compile and cached cold-start times instead")
    parser.add_argument("--repeat", type=int, default=1,
                        help="runs per variant, each a fresh process; the fastest is reported (shared "
                             "machines vary by tens of percent from run to run)")
    parser.add_argument("--points", action="store_true",
                        help="point clouds: uniform random points of the unit sphere (see above)")
    parser.add_argument("--standard-errors", action="store_true",
                        help="time curv's calls with standard_errors=True (default: the default call, without)")
    parser.add_argument("--child", nargs=6, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        kind, name, k, n, mesh_kind, se = args.child
        print(json.dumps(_child(kind, name, float(k), int(n), mesh_kind, se == "1")))
        return 0

    if args.points:
        run_points(args)
        return 0
    import curv
    from curv.estimators import all_variants

    variants = [tuple(v.split(":")) for v in args.only] if args.only else all_variants()
    variants = [(m, float(k)) for m, k in variants]
    if args.compile:
        compile_times(variants)
        return 0
    print(f"# cores: {os.cpu_count()}, numpy {np.__version__}, curv {curv.__version__}, best of {args.repeat}")
    for n in args.sizes:
        v, _ = MESHES[args.mesh](n)
        print(f"\n## {args.mesh}, {len(v)} vertices{', shuffled numbering' if args.shuffle else ''}")
        mesh_kind = f"{args.mesh}:shuffled" if args.shuffle else args.mesh
        peers = {}
        if not args.no_peers:
            for k in (2, 4):
                peers[f"trueform k={k}"] = run_one("trueform", "principal_curvatures", k, n, mesh_kind, args.repeat)
            peers["libigl r=2"] = run_one("igl", "principal_curvature", 2, n, mesh_kind, args.repeat)
            peers["VTK H+K"] = run_one("vtk", "curvatures", 0, n, mesh_kind, args.repeat)
        print(f"{'variant':<14} {'seconds':>8} {'cpu s':>7} {'conn s':>7} {'peak MB':>8} {'valid':>6}  vs tf k=2"
              f"  vs tf k=4  vs VTK  (cpu: tf k=2, tf k=4)")
        for m, k in variants:
            r = run_one("curv", m, k, n, mesh_kind, args.repeat, args.standard_errors)
            label = f"{m} R{k:g}"
            if "error" in r:
                print(f"{label:<14} error: {r['error']}")
                continue
            ratios = "  ".join(
                f"{peers[p]['seconds'] / r['seconds']:8.2f}x" if "seconds" in peers.get(p, {}) else "       -"
                for p in ("trueform k=2", "trueform k=4", "VTK H+K"))
            cpu_ratios = ", ".join(
                f"{peers[p]['cpu_seconds'] / r['cpu_seconds']:.2f}x" if "seconds" in peers.get(p, {}) else "-"
                for p in ("trueform k=2", "trueform k=4"))
            print(f"{label:<14} {r['seconds']:8.2f} {r['cpu_seconds']:7.2f} {r['conn_seconds']:7.2f} "
                  f"{r['peak_above_mesh_mb']:8.0f} {r['valid']:6.3f}  {ratios}  ({cpu_ratios})", flush=True)
        for p, r in peers.items():
            text = (f"{r['seconds']:8.2f} {r['cpu_seconds']:7.2f} {'':>7} {r['peak_above_mesh_mb']:8.0f}"
                    if "seconds" in r else f"error: {r['error']}")
            print(f"{p:<14} {text}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
