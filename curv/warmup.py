"""Compile curv's numba kernels ahead of their first use: ``python -m curv.warmup``.

numba compiles a kernel on its first call and keeps it in an on-disk cache, one folder per state
of curv's sources (:mod:`curv.core.jit`). On a fresh install every estimator's first call therefore
spends seconds to half a minute compiling (docs/BENCHMARKS.md, "Compile and cold start"): the
viewer's first picture, and every estimator a user tries for the first time, wait for it. This
module runs each estimator once on a small mesh and on a small point cloud, so that the install
pays the compile instead of the user's first click (``make venv`` runs it).

The steps run in worker processes (``--jobs``); the mesh and point-cloud steps, whose kernels the
estimators' steps share, run first, so the others load those from the cache instead of each
compiling them again.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path

import numpy as np

__all__ = ["STEPS", "pending_estimators", "run_step", "warm"]

MESH_VERTICES = 631
"""Small enough to estimate in a fraction of a second, large enough for every range's support (a hexagon patch size)."""

CLOUD_POINTS = 2000


def _mesh():
    from curv.surfaces import make_surface

    return make_surface("torus", n_vertices=MESH_VERTICES, noise=0.05, seed=0).mesh


def _open_mesh():
    from curv.surfaces import make_surface

    return make_surface("quadratic", n_vertices=MESH_VERTICES, seed=0).mesh


def _creased_mesh():
    from curv.surfaces import make_surface

    return make_surface("box", seed=0).mesh


def _quad_mesh():
    """A grid of quads (a polygon mesh, for the estimators that take polygons)."""
    import curv

    side = 20
    u, v = np.meshgrid(np.linspace(-1, 1, side), np.linspace(-1, 1, side))
    vertices = np.column_stack([u.ravel(), v.ravel(), 0.3 * (u.ravel() ** 2 - v.ravel() ** 2)])
    corner = (np.arange(side - 1)[:, None] * side + np.arange(side - 1)[None, :]).ravel()
    return curv.Mesh(vertices, np.column_stack([corner, corner + 1, corner + side + 1, corner + side]))


def _cloud():
    from curv.surfaces import sample_points

    return sample_points("torus", CLOUD_POINTS, rng=np.random.default_rng(0)).cloud


def _mesh_step() -> None:
    """Connectivity, incidence, normals, the mesh report and feature edges: what every estimate and
    the viewer's load need, on triangles and on polygons (their face geometry's own kernel)."""
    import curv

    for mesh in (_mesh(), _open_mesh(), _quad_mesh()):
        mesh.report()
        curv.vertex_normals(mesh)
        curv.feature_edges(mesh, 30.0)
        mesh.vertex_edges, mesh.vertex_faces  # the incidence kernels


def _estimator_step(name: str) -> None:
    """One estimator on a closed, an open, a creased (with features) and, where it takes polygons, a quad mesh;
    its ranges in one call, with the estimators it shares a pass with; and on a cloud where it takes one."""
    import curv
    from curv.estimators import ESTIMATORS, get_spec, polygon_estimators

    spec = get_spec(name)
    k = spec.ranges[min(1, len(spec.ranges) - 1)] if spec.has_support else None
    for mesh in (_mesh(), _open_mesh()):
        curv.estimate(mesh, name, k)
        if spec.uses_normals:
            curv.estimate(mesh, name, k, normals="fit")
    if spec.skips_errors:  # the fits' kernels with their standard errors (the viewer asks for them)
        curv.estimate(_mesh(), name, k, standard_errors=True)
    curv.estimate(_creased_mesh(), name, k, features=30.0)
    if name in polygon_estimators():
        curv.estimate(_quad_mesh(), name, k)
    if spec.takes_levels:
        curv.estimate_ranges(_mesh(), name, spec.ranges, standard_errors=False)
    if spec.shared_pass:  # the study's path: the estimators sharing the pass in one call
        partners = [other for other in ESTIMATORS if get_spec(other).shared_pass == spec.shared_pass]
        curv.estimate_table(_mesh(), partners, spec.ranges, standard_errors=False)
    if spec.takes_points:
        curv.estimate(_cloud(), name, k)
        if spec.skips_errors:
            curv.estimate(_cloud(), name, k, standard_errors=True)


def _cloud_step() -> None:
    """A point cloud's spacing, normals, orientation (propagated, and up as for a scan) and border
    test, with the default estimator."""
    import curv

    curv.estimate(_cloud(), range=2)
    curv.estimate(_cloud(), range=2, orient="up")


def _advice_step() -> None:
    """The advisor's measuring fits and residual kernel (the viewer's Advise and ``--method auto``)."""
    import curv

    curv.advise(_mesh())


def _export_step() -> None:
    """A coloured PLY written and read back (the export and the file loader)."""
    import curv

    mesh = _mesh()
    res = curv.estimate(mesh, "meyer")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "warm.ply"
        curv.save_result(path, mesh, res)
        curv.load(path)


def _tiles_step() -> None:
    """A tiled estimate of a mesh and of a cloud: the reach kernel (curv.tiles.reach), redone points included."""
    from curv.tiles import estimate_tiled

    estimate_tiled(_mesh(), "mru", tile_size=300, halo=0.0)
    estimate_tiled(_cloud(), "qs", tile_size=800, orient=(0.0, 0.0, 10.0))


def _steps() -> dict:
    from curv.estimators import ESTIMATORS

    steps = {"mesh": _mesh_step, "cloud": _cloud_step, "advice": _advice_step, "export": _export_step,
             "tiles": _tiles_step}
    steps.update({name: (lambda n=name: _estimator_step(n)) for name in ESTIMATORS})
    return steps


STEPS = ("mesh", "cloud", "advice", "export", "tiles")
"""The steps besides one per registered estimator (:func:`warm` runs them all)."""


def run_step(label: str) -> tuple[str, float]:
    """Run one warm-up step by its label (a name of :data:`STEPS` or an estimator's); returns (label, seconds)."""
    start = time.perf_counter()
    _steps()[label]()
    return label, time.perf_counter() - start


def pending_estimators(names=None) -> list[str]:
    """Those of ``names`` (default every estimator) whose kernels are not in numba's cache for this
    state of the sources."""
    from curv.core.jit import compile_pending
    from curv.estimators import ESTIMATORS, get_spec

    return [name for name in (ESTIMATORS if names is None else names) if compile_pending(get_spec(name).kernels)]


FIRST = ("mesh", "cloud")
"""Steps whose kernels (connectivity, normals; a cloud's spacing, orientation and border test) the
others share: they run before the rest, so no two processes compile the same kernel."""


def warm(labels=None, *, jobs: int = 1, report=print) -> list[tuple[str, float]]:
    """Compile the kernels the given steps use (all by default), ``jobs`` processes at a time.

    Parameters
    ----------
    labels : iterable of str, optional
        Steps to run: a name of :data:`STEPS` or an estimator's. Default all. The mesh step runs
        whenever any other does (every estimator's kernels include the connectivity's).
    jobs : int
        Worker processes. 1 runs the steps in this process.
    report : callable
        Called with one line per finished step.

    Returns
    -------
    list of (str, float)
        Each step's label and wall seconds, in the order they finished.
    """
    steps = _steps()
    labels = list(steps) if labels is None else list(labels)
    unknown = sorted(set(labels) - set(steps))
    if unknown:
        raise ValueError(f"unknown warm-up steps {unknown}; choose from {sorted(steps)}")
    if labels and "mesh" not in labels:
        labels.insert(0, "mesh")
    phases = [[label for label in labels if label in FIRST], [label for label in labels if label not in FIRST]]
    done = []

    def finished(label, seconds):
        done.append((label, seconds))
        report(f"  {label:<8} {seconds:6.1f} s")

    if jobs <= 1:
        for label in phases[0] + phases[1]:
            finished(*run_step(label))
        return done
    with ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn")) as pool:
        for phase in phases:
            for future in as_completed([pool.submit(run_step, label) for label in phase]):
                finished(*future.result())
    return done


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m curv.warmup", description=__doc__.split("\n\n")[0])
    parser.add_argument("steps", nargs="*", help="steps to run (default all): mesh, cloud, advice, export, tiles, "
                        "or estimator names")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="worker processes (default: the cores)")
    parser.add_argument("--if-needed", action="store_true",
                        help="do nothing when the estimators' kernels (those named, or all) are already cached")
    args = parser.parse_args(argv)
    unknown = sorted(set(args.steps) - set(_steps()))
    if unknown:
        parser.error(f"unknown steps {unknown}; choose from {sorted(_steps())}")
    if args.if_needed:
        from curv.estimators import ESTIMATORS

        named = [step for step in args.steps if step in ESTIMATORS]
        if not pending_estimators(named or None):
            return 0
    start = time.perf_counter()
    print(f"curvlab: compiling the curvature kernels ahead of first use ({args.jobs} processes)...", flush=True)
    warm(args.steps or None, jobs=args.jobs, report=lambda line: print(line, flush=True))
    print(f"curvlab: kernels compiled in {time.perf_counter() - start:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
