"""Turning a document source into a mesh (and its exact curvature for analytic surfaces)."""

from __future__ import annotations

import threading
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass, field, replace

import numpy as np
from curv.api import iter_estimate
from curv.io import is_point_file, load
from curv.geometry.normals import cached_max_normals
from curv.point_normals import grid_ordered
from curv.surfaces import SURFACES, make_surface, sample_points

from app.model.inputs import cloud_report, is_points

from .large import load_large
from app.model.sources import FileSource, SurfaceSource

__all__ = ["EarlyEstimate", "load_source", "preload", "prepare_source", "mesh_report", "Loaded"]


@dataclass
class Loaded:
    """What a source job hands to the GUI thread.

    Attributes
    ----------
    source : FileSource or SurfaceSource
    mesh : curv.Mesh
    truth : curv.Curvature or None
    report : list of str or None
        A point cloud's report, computed off the GUI thread; None for a mesh, whose report the
        controller computes after the mesh's first estimates (:func:`mesh_report`).
    repairs : list of str
        The repairs applied while loading (``mesh.info["repairs"]``).
    prepared : object
        Whatever the controller's ``prepare`` hook built from the mesh (e.g. render geometry).
    """

    source: object
    mesh: object
    truth: object
    report: list | None = None
    prepared: object = None
    repairs: list = field(default_factory=list)


class EarlyEstimate:
    """Pane A's estimate of a mesh file named on the command line, run in the preload thread as soon
    as the mesh and its normals are there, while the window is still being built.

    The controller's first estimate of the same pane on the same mesh follows this one
    (:meth:`follows`, :meth:`follow`) instead of starting its own; any other use cancels it
    (:meth:`cancel`). The estimate is ``curv.iter_estimate(mesh, method, **kwargs)``, the call the
    controller would make, so the result is the same.

    Parameters
    ----------
    method : str
        Registry name of the estimator.
    kwargs : dict
        The pane's ``estimate_kwargs()``.
    """

    def __init__(self, method: str, kwargs: dict) -> None:
        self.method = method
        self.kwargs = dict(kwargs)
        self.mesh = None
        self.progress = 0.0
        self._stop = threading.Event()
        self._result: Future = Future()

    def follows(self, mesh, method: str, kwargs: dict) -> bool:
        """True if this estimate is ``method`` with ``kwargs`` on this very ``mesh``."""
        return mesh is not None and mesh is self.mesh and method == self.method and kwargs == self.kwargs

    def run(self) -> None:
        """Estimate on :attr:`mesh` (set beforehand); called in the preload thread."""
        try:
            steps = iter_estimate(self.mesh, self.method, **self.kwargs)
            while True:
                if self._stop.is_set():
                    steps.close()
                    raise InterruptedError(f"{self.method} cancelled")
                try:
                    self.progress = next(steps)
                except StopIteration as end:
                    self._result.set_result(end.value)
                    return
        except BaseException as exc:  # noqa: BLE001 (handed to whoever follows the estimate)
            self._result.set_exception(exc)

    @property
    def stopped(self) -> bool:
        """True once the estimate was told to stop (cancelled, or its follower quit or ended)."""
        return self._stop.is_set()

    def result(self, timeout: float | None = None):
        """The :class:`curv.Curvature` once the estimate has ended (its exception if it failed;
        ``concurrent.futures.TimeoutError`` after ``timeout`` seconds)."""
        return self._result.result(timeout=timeout)

    def follow(self):
        """A generator for the controller's worker: yields the progress (a fraction, with the
        estimator's message) until the estimate ends and returns its :class:`curv.Curvature`; a
        worker that quits closes it, which stops the estimate."""
        try:
            while True:
                try:
                    return self.result(timeout=0.05)
                except FutureTimeout:
                    yield self.progress
        finally:
            self._stop.set()  # no effect once the estimate has ended

    def cancel(self) -> None:
        """Stop the estimate at its next step (nobody will follow it)."""
        self._stop.set()


def preload(source, early: EarlyEstimate | None = None) -> Future:
    """Start :func:`load_source` of ``source`` and a mesh's default normals in a thread now; hand the
    future to :func:`prepare_source` (``loaded=``).

    ``curvlab FILE`` reads the file and computes its normals while the window is being built (the
    imports of Qt, VTK and pyvista alone take seconds). With ``early`` the same thread then runs
    that estimate on the mesh (not on a point cloud), still beside the window's construction; the
    future's ``early`` attribute holds it for the controller. Import this module before calling: the
    thread uses only modules already imported.
    """
    future = Future()
    future.early = early

    def work():
        try:
            out = load_source(source)
            if not is_points(out[1]):
                cached_max_normals(out[1])  # what the drawing and the default estimates shade and fit with
        except BaseException as exc:  # noqa: BLE001 (handed to whoever waits for the result)
            if early is not None:
                early.cancel()
            future.set_exception(exc)
            return
        runs_early = early is not None and not is_points(out[1])
        if runs_early:
            early.mesh = out[1]  # before the result: the controller compares meshes once it has it
        future.set_result(out)
        if runs_early:
            early.run()

    # a daemon: a window that never opens (a bad argument) does not wait for the file to load
    threading.Thread(target=work, name="curvlab-preload", daemon=True).start()
    return future


def prepare_source(source, prepare=None, loaded: Future | None = None) -> Loaded:
    """:func:`load_source` (or the result of ``loaded``, a :func:`preload`), a point cloud's report and
    ``prepare(mesh)`` if given; runs in a worker thread.

    A mesh's report waits for its first estimates (:func:`mesh_report`): they build the
    connectivity it reads (vertex corners, components), as ``curv estimate`` reports after its
    estimate, so the estimate starts seconds earlier on a large mesh and the report costs little.
    """
    source, mesh, truth = load_source(source) if loaded is None else loaded.result()
    report = None
    if is_points(mesh):
        # the cloud's facts need its neighbour search: made once, on the grid-ordered twin that its
        # whole-cloud estimates run on, so that they find it done
        grid_ordered(mesh)
        report = cloud_report(mesh)
    repairs = list(mesh.info.get("repairs", [])) if isinstance(getattr(mesh, "info", None), dict) else []
    return Loaded(source, mesh, truth, report, None if prepare is None else prepare(mesh), repairs)


def mesh_report(mesh) -> list[str]:
    """``mesh.report().lines()``; runs in a worker thread."""
    return mesh.report().lines()


def load_source(source):
    """Load or mesh ``source``; runs in a worker thread.

    Parameters
    ----------
    source : FileSource or SurfaceSource

    Returns
    -------
    (source, mesh, truth)
        ``truth`` is the exact :class:`curv.Curvature` of an analytic surface, else None.

    Raises
    ------
    curv.CurvError or ValueError
        With a one-line message (unreadable file, bad parameters, ...).
    """
    big = load_large(source)  # a file too large to draw whole: its preview (app.model.large)
    if big is not None:
        return big
    if isinstance(source, FileSource) and is_point_file(source.path):
        # the opt-in repairs are a mesh's (the Mesh report's checkboxes): a point file is read as it is
        return source, load(source.path), None
    if isinstance(source, FileSource):
        # STL stores every triangle with its own corners: merge them, or nothing is connected
        flags = {name: True for name in source.repairs}
        flags.setdefault("merge_vertices", source.path.lower().endswith(".stl"))
        return source, load(source.path, **flags), None
    if isinstance(source, SurfaceSource) and source.sampling is not None:
        cls = SURFACES[source.name]
        rng = np.random.default_rng(source.seed)  # one stream, as make_surface: parameters, then points
        params = {**cls.random(rng).parameters, **source.params} if source.random_params else source.params
        sampled = sample_points(cls(**params), source.n_vertices, sampling=source.sampling, noise=source.noise,
                                rng=rng)
        # blue noise and rows give about the count asked for: the source names the count the cloud has
        return replace(source, n_vertices=sampled.cloud.n_points), sampled.cloud, sampled.truth
    if isinstance(source, SurfaceSource):
        sampled = make_surface(
            source.name, n_vertices=source.n_vertices, irregularity=source.irregularity,
            noise=source.noise, seed=source.seed, random_params=source.random_params, **source.params)
        # a closed surface's tessellation has its own nearest count (a torus grid: 10240 for 10242):
        # the source then names the count the mesh really has
        return replace(source, n_vertices=sampled.mesh.n_vertices), sampled.mesh, sampled.truth
    raise TypeError(f"unknown source {source!r}")
