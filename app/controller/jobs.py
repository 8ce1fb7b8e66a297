"""The job controller: one source job, one estimate job per (method, range), the mesh report and one
advisor job, all off the GUI thread. A new source supersedes everything running; a pane switching
estimator stops the estimate nobody shows any more. Stale results are recognised by a generation
number (the advisor's by its worker) and dropped."""

from __future__ import annotations

import time

from curv import iter_estimate
from PySide6.QtCore import QObject, QThreadPool, Signal
from superqt.utils import create_worker

from app.heap import release_free_memory
from app.model import AdviceRecord, Document, count_text
from app.model.inputs import item_word, items_word
from app.model.picture import scene_of

from .advice import advice_compile_note, advise_steps
from .large import WholeFileJob
from .outputs import overlay_edges, write_export
from .sources import mesh_report, prepare_source
from .worker_calls import counted, one_line

__all__ = ["Controller", "JOB_THREADS"]

JOB_THREADS = 8
"""Threads the controller's jobs may hold at once: a source, up to four panes' estimates, the report
and the advisor, with room to spare. Qt's default is one per core, two on a 2-core machine, and work
that cannot stop midway (a kernel's first compile, a report, the advisor) keeps its thread after a
cancel: the next source must not queue behind it. The kernels themselves run one launch at a time
(``curv.core.jit.launch``), so more threads here do not oversubscribe the cores."""


class Controller(QObject):
    """Start, supersede and cancel the document's background work.

    Parameters
    ----------
    document : Document
    prepare : callable, optional
        ``prepare(mesh)`` run in the source worker after loading (e.g. to build render geometry off
        the GUI thread); its value reaches the views as ``MeshChange.geometry``.

    Signals
    -------
    busy_changed(bool)
        Something is (no longer) running.
    progress(str, float)
        What runs and the fraction done (``-1``: unknown); the text includes the estimator's own
        status message when it yields one (``curv.core.jit.Progress.message``, e.g. first-run compiling).
    message(str)
        Informational status text.
    failed(str)
        A one-line error message (the document keeps its previous state).
    advising(bool)
        The advisor started or stopped (finished, failed, cancelled or superseded).
    advice_progress(float, str)
        The advisor's fraction done and what it runs (its self-check's steps).
    """

    advising = Signal(bool)
    advice_progress = Signal(float, str)
    busy_changed = Signal(bool)
    progress = Signal(str, float)
    message = Signal(str)
    failed = Signal(str)

    def __init__(self, document: Document, parent: QObject | None = None, *, prepare=None) -> None:
        super().__init__(parent)
        pool = QThreadPool.globalInstance()  # superqt's workers all run on it
        pool.setMaxThreadCount(max(pool.maxThreadCount(), JOB_THREADS))
        self.doc = document
        self.prepare = prepare
        self._generation = 0
        self._messages: dict = {}
        self.cancelled_at: float | None = None
        """``perf_counter`` time of the last cancel (for measuring how soon the workers stop)."""
        self._source_job = None
        self._early = None  # the preload's estimate of pane A (sources.EarlyEstimate), until used
        self._estimates: dict[tuple[str, int], object] = {}
        self._fractions: dict[tuple[str, int], float] = {}
        self._advice_job = None
        self._side_jobs: dict = {}  # exports and overlay edges: key -> (worker, what it does)
        self._report_job = None
        self._report_due = False  # a new mesh's report, started once its first estimates are done
        self._last_message = ""
        self.message.connect(lambda text: setattr(self, "_last_message", text))
        self._advice_note = ""
        self._advise_after_load = False
        self._closed = False
        self._busy = False
        self.whole_file = WholeFileJob(self)
        """A large file estimated tile by tile into an output file (the Large file panel's run)."""
        # subscribed before the views: a new mesh's estimates start before the views draw it (a
        # first render of a large mesh takes seconds; the estimate runs beside it, off this thread)
        document.mesh_changed.connect(lambda change: self.request_missing())

    # -- state ----------------------------------------------------------------------------------
    @property
    def busy(self) -> bool:
        """True while a source, estimate, report or advisor job runs (or a report is due)."""
        return (self._source_job is not None or bool(self._estimates) or self._advice_job is not None
                or self._report_job is not None or self._report_due or bool(self._side_jobs))

    @property
    def advising_now(self) -> bool:
        """True while the advisor runs."""
        return self._advice_job is not None

    def running_keys(self) -> list[tuple[str, int]]:
        return list(self._estimates)

    def _update_busy(self) -> None:
        if self.busy != self._busy:
            self._busy = self.busy
            self.busy_changed.emit(self._busy)
        if self._source_job is not None:
            self.progress.emit(f"Loading {self._source_job[1].label}", -1.0)
        elif self._estimates:
            names = ", ".join(f"{m} {r}" for m, r in self._estimates)
            frac = sum(self._fractions.values()) / len(self._fractions)
            notes = "; ".join(dict.fromkeys(m for m in (*self._messages.values(), self._advice_note) if m))
            advising = "; advising" if self._advice_job is not None else ""
            self.progress.emit(f"Estimating {names}{advising}" + (f": {notes}" if notes else ""), frac)
        elif self._report_job is not None or self._report_due:
            self.progress.emit("Checking the mesh", -1.0)
        elif self._side_jobs:
            self.progress.emit("; ".join(label for _, label in self._side_jobs.values()), -1.0)
        elif self._advice_job is not None:
            label = self.doc.source.label if self.doc.source is not None else "the mesh"
            note = f": {self._advice_note}" if self._advice_note else ""
            self.progress.emit(f"Advising on {label}{note}", getattr(self, "_advice_fraction", -1.0))

    # -- sources --------------------------------------------------------------------------------
    def open_source(self, source, *, loaded=None) -> None:
        """Load a file or mesh a surface; supersedes every running job.

        ``loaded``: the :func:`~app.controller.sources.preload` of this very source, already under way.
        """
        if self._closed:
            return
        self._stop_all()
        self._generation += 1
        gen = self._generation
        self._early = getattr(loaded, "early", None)
        # errored must be connected at creation, or superqt re-raises the error in the GUI thread
        worker = create_worker(prepare_source, source, self.prepare, loaded, _start_thread=False, _connect={
            "returned": lambda out, gen=gen: self._source_done(gen, out),
            "errored": lambda exc, gen=gen, src=source: self._source_failed(gen, src, exc)})
        self._source_job = (worker, source)
        worker.start()
        self._update_busy()

    def _source_done(self, gen: int, out) -> None:
        if gen != self._generation or self._closed:
            return
        self._source_job = None
        self._report_due = out.report is None
        self.doc.set_mesh(out.source, out.mesh, out.truth, report=out.report, repairs=out.repairs,
                          geometry=out.prepared)
        release_free_memory()  # the reader's buffers (a previous mesh's too, now unreferenced)
        size = "; ".join(out.report[:2]) if out.report else count_text(
            out.mesh.n_vertices, "vertex", "vertices") + ", " + count_text(out.mesh.n_faces, "face", "faces")
        self.message.emit(f"{out.source.label}: {size}")
        self.request_missing()
        self._drop_early()  # no pane wanted it (settings changed the panes): stop it
        if self._advise_after_load:
            self._advise_after_load = False
            self._start_advice()
        self._update_busy()

    def _source_failed(self, gen: int, source, exc: Exception) -> None:
        if gen != self._generation or self._closed:
            return
        self._source_job = None
        self._advise_after_load = False  # the advice was asked for the mesh that did not come
        self._update_busy()
        self.failed.emit(f"Could not open {source.label}: {one_line(exc)}")

    # -- estimates ------------------------------------------------------------------------------
    def request_missing(self) -> None:
        """Start an estimate for every key a pane shows that is neither known nor running."""
        if self._closed or self.doc.mesh is None or self._source_job is not None:
            return
        wanted = {p.key for p in self.doc.panes}
        for key in [k for k in self._estimates if k not in wanted]:
            self._stop(key)
        for key in self.doc.missing_keys():
            if key not in self._estimates:
                self._start_estimate(key)
        self._start_report_when_due()
        self._update_busy()

    # -- the mesh report ------------------------------------------------------------------------
    def _start_report_when_due(self) -> None:
        """Start the new mesh's report once no estimate runs (they built what it reads)."""
        if not self._report_due or self._estimates or self._closed or self.doc.mesh is None:
            return
        self._report_due = False
        gen = self._generation
        box = []
        worker = create_worker(mesh_report, self.doc.mesh, _start_thread=False, _connect={
            "returned": lambda lines: self._report_done(box[0], gen, lines),
            "errored": lambda exc: self._report_done(box[0], gen, [f"no report: {one_line(exc)}"])})
        box.append(worker)
        self._report_job = worker
        worker.start()

    def _report_done(self, worker, gen, lines) -> None:
        if self._closed or self._report_job is not worker:
            return
        self._report_job = None
        if gen == self._generation:
            self.doc.set_report(lines)
        release_free_memory()
        self._update_busy()
        if not self.busy and self._last_message:  # the status bar showed the check: back to the last news
            self.message.emit(self._last_message)

    def recompute(self, key) -> None:
        """Compute ``key`` again; a result of it stays shown until the new one replaces it (a cancel or
        a failure of the new one leaves it there)."""
        if self._closed or self.doc.mesh is None or self._source_job is not None:
            return
        self.doc.retry(key)
        self._stop(key)
        self._start_estimate(key)
        self._update_busy()

    def compute_in_pane(self, i: int, pane) -> None:
        """Show ``pane`` (a validated :class:`~app.model.Pane`) in pane ``i`` and compute it unless its
        result is known; an earlier failure or cancel of the same pair is retried, not shown again."""
        self.doc.retry(pane.key)
        self.doc.set_pane(i, method=pane.method, range=pane.range, radius=pane.radius, knn=pane.knn,
                          options=pane.options)
        self.request_missing()

    def _start_estimate(self, key) -> None:
        pane = self.doc.pane_for(key)
        gen = self._generation
        kwargs = pane.estimate_kwargs()
        call, args = iter_estimate, (self.doc.mesh, pane.method)
        if self._early is not None and self._early.follows(self.doc.mesh, pane.method, kwargs):
            call, args, kwargs = self._early.follow, (), {}  # started with the file's read: follow it
            self._early = None
        box = []  # the worker, for the callbacks (they must exist before it does)
        worker = create_worker(counted, call, *args,
                               **kwargs,
                               _start_thread=False, _connect={
            "yielded": lambda f: self._estimate_progress(box[0], key, f),
            "returned": lambda out: self._estimate_done(box[0], gen, key, *out),
            "errored": lambda exc: self._estimate_failed(box[0], gen, key, exc)})
        box.append(worker)
        self._estimates[key] = worker
        self._fractions[key] = 0.0
        worker.start()

    def _current(self, worker, gen, key) -> bool:
        return not self._closed and gen == self._generation and self._estimates.get(key) is worker

    def _estimate_progress(self, worker, key, fraction) -> None:
        if self._estimates.get(key) is worker:
            self._fractions[key] = float(fraction)
            self._messages[key] = getattr(fraction, "message", "") or ""
            self._update_busy()

    def _estimate_done(self, worker, gen, key, result, n_invalid: int) -> None:
        if not self._current(worker, gen, key):
            return
        self._forget(key)
        self.doc.set_result(key, result)
        release_free_memory()  # the estimate's and the frame's freed buffers, before the report's come
        # after the coloured frame, not beside it: VTK holds the GIL while it draws, so the report
        # gained no time there, and its temporaries piled onto the frame's buffers (0.9 GB at 10M)
        self._start_report_when_due()
        computed = result.info.get("region", result.n)  # a region's result: the rest is NOT_COMPUTED, not invalid
        n_bad = n_invalid - (result.n - computed)
        secs = result.info.get("seconds")
        took = f" in {secs:.2f} s" if secs is not None else ""
        of = "" if computed == result.n else f" of {computed} computed"
        bad = count_text(n_bad, f"invalid {item_word(self.doc.mesh)}", f"invalid {items_word(self.doc.mesh)}")
        self.message.emit(f"{key[0]} {key[1]}{took}; {bad}{of}" + "".join(f"; {w}" for w in result.info.get("warnings", ())))
        self._update_busy()

    def _estimate_failed(self, worker, gen, key, exc) -> None:
        if not self._current(worker, gen, key):
            return
        self._forget(key)
        msg = f"{key[0]} {key[1]} failed: {one_line(exc)}"
        if key in self.doc.results:  # a recompute: the earlier result stays shown
            msg += "; the earlier result stays"
        else:
            self.doc.set_failure(key, msg)
        self._start_report_when_due()
        self._update_busy()
        self.failed.emit(msg)

    # -- advice ---------------------------------------------------------------------------------
    def advise(self) -> None:
        """Run ``curv.advise`` on the document's mesh; the answer goes to :meth:`Document.set_advice`.

        While a source loads, the advisor runs once its mesh is there. A second request while the
        advisor runs on the same mesh is ignored (a new mesh stops it). Failures become an
        :class:`AdviceRecord` with its ``error`` and a ``failed`` message; nothing else changes.
        """
        if self._closed:
            return
        if self._source_job is not None:
            self._advise_after_load = True
            self.message.emit(f"Advice follows once {self._source_job[1].label} has loaded")
            return
        if self.doc.mesh is None:
            self.failed.emit("Nothing to advise on: open a mesh or generate a surface first")
            return
        if self._advice_job is None:
            self._start_advice()
            self._update_busy()

    def _start_advice(self) -> None:
        doc = self.doc
        serial, label = doc.mesh_serial, doc.source.label
        box = []  # the worker, for the callbacks (they must exist before it does)
        worker = create_worker(advise_steps, doc.mesh, mesh_serial=serial, source_label=label,
                               _start_thread=False, _connect={
            "yielded": lambda done: self._advice_step(box[0], done),
            "returned": lambda record: self._advice_done(box[0], record),
            "errored": lambda exc: self._advice_failed(box[0], serial, label, exc)})
        box.append(worker)
        self._advice_job = worker
        self._advice_fraction = -1.0
        self._advice_note = advice_compile_note()
        worker.start()
        self.advising.emit(True)

    def _advice_step(self, worker, done) -> None:
        """The advisor's progress (its check's steps): the fraction and what runs."""
        if self._closed or self._advice_job is not worker:
            return
        self._advice_fraction = float(done)
        message = getattr(done, "message", "")
        if message and message != "done":
            self._advice_note = message
        self.advice_progress.emit(self._advice_fraction, self._advice_note)
        self._update_busy()

    def cancel_advice(self) -> None:
        """Stop the advisor (at its next step); nothing else."""
        if self._advice_job is not None:
            self._advice_job.quit()
            self._forget_advice()
            self._update_busy()
            self.message.emit("Advice cancelled")

    def _advice_done(self, worker, record) -> None:
        if self._closed or self._advice_job is not worker:
            return
        self._forget_advice()
        self.doc.set_advice(record)
        adv = record.advice
        measured = adv.checked and adv.best.measured is not None and adv.best.measured.ok  # as the table shows it
        error = (f"measured median e_rel {adv.best.measured_erel:.2g}" if measured
                 else f"expected median e_rel {adv.expected_erel:.2g}")
        self.message.emit(f"Advice for {record.source_label} in {record.seconds:.2f} s: {adv.label}, {error}")
        self._update_busy()

    def _advice_failed(self, worker, serial, label, exc) -> None:
        if self._closed or self._advice_job is not worker:
            return
        self._forget_advice()
        reason = one_line(exc)
        # curv's messages already begin "cannot advise ..."; say only which mesh
        msg = f"{label}: {reason}" if reason.lower().startswith("cannot advise") else \
            f"Could not advise on {label}: {reason}"
        self.doc.set_advice(AdviceRecord(serial, label, None, error=msg))
        self._update_busy()
        self.failed.emit(msg)

    def _forget_advice(self) -> None:
        if self._advice_job is not None:
            self._advice_job = None
            self._advice_note = ""
            self.advising.emit(False)

    # -- exports and overlays -------------------------------------------------------------------
    def export(self, path, colours):
        """Write the active pane to ``path`` (``.ply`` or ``.vtu``) as shown, ``colours`` its colours on
        screen (:func:`~app.controller.outputs.write_export`); returns the path written."""
        pane = self.doc.panes[self.doc.active]
        return write_export(path, self.doc.mesh, scene_of(self.doc), pane, colours)

    def export_later(self, path, colours) -> None:
        """:meth:`export` in a worker (seconds for a large input); ``message`` says when the file is
        written, ``failed`` why it is not."""
        pane = self.doc.panes[self.doc.active]
        name = getattr(path, "name", None) or str(path).rsplit("/", 1)[-1]
        self._start_side(("export", str(path)), f"Writing {name}", write_export, path, self.doc.mesh,
                         scene_of(self.doc), pane, colours, done=lambda out: self.message.emit(f"Wrote {out}"),
                         failed=lambda exc: self.failed.emit(f"Export failed: {one_line(exc)}"))

    def request_edges(self, key) -> None:
        """Find the overlay edges ``key`` (``"borders"`` or a feature angle) of the shown mesh in a
        worker unless known or under way; they arrive in ``doc.edges`` (:meth:`Document.set_edges`)."""
        doc = self.doc
        if self._closed or doc.mesh is None or key in doc.edges or ("edges", key) in self._side_jobs:
            return
        serial = doc.mesh_serial
        what = "Finding the border edges" if key == "borders" else f"Finding the feature edges at {key:g}°"

        def done(edges):
            if doc.mesh_serial == serial:
                doc.set_edges(key, edges)

        self._start_side(("edges", key), what, overlay_edges, doc.mesh, key, done=done,
                         failed=lambda exc: self.failed.emit(f"{what} failed: {one_line(exc)}"))

    def _start_side(self, key, label, fn, *args, done, failed) -> None:
        box = []

        def finish(handler, value):
            if self._side_jobs.get(key, (None,))[0] is box[0]:
                del self._side_jobs[key]
                handler(value)
                self._update_busy()

        worker = create_worker(fn, *args, _start_thread=False, _connect={
            "returned": lambda out: finish(done, out), "errored": lambda exc: finish(failed, exc)})
        box.append(worker)
        self._side_jobs[key] = (worker, label)
        worker.start()
        self._update_busy()

    # -- stopping -------------------------------------------------------------------------------
    def cancel(self) -> None:
        """Stop everything running; panes fall back to their last result (a recompute's pane keeps the
        result it showed).

        Returns at once: each worker stops at its next yield (the estimators yield every chunk of
        vertices); nothing here waits for it.
        """
        self.cancelled_at = time.perf_counter()
        was_source = self._source_job is not None
        was_advice = self._advice_job is not None or self._advise_after_load
        keys = list(self._estimates)
        self._advise_after_load = False
        # the shown mesh's report still comes (it reads what the estimates built; it cannot stop midway)
        self._stop_all(keep_report=not was_source)
        self._generation += 1 if was_source else 0
        self._start_report_when_due()
        names = [f"{m} {r}" for m, r in keys]
        kept = [key for key in keys if key in self.doc.results]  # recomputes: their result stays
        self.doc.set_failures({key: f"{name} cancelled" for key, name in zip(keys, names) if key not in kept})
        self._update_busy()
        if was_source or keys or was_advice:
            again = "; choose it again to compute it" if len(kept) < len(keys) else ""
            stays = "; the earlier result stays" if kept else ""
            self.message.emit("Cancelled" + (f" {', '.join(names)}" if names else "") + again + stays)

    def _forget(self, key) -> None:
        self._estimates.pop(key, None)
        self._fractions.pop(key, None)
        self._messages.pop(key, None)

    def _stop(self, key) -> None:
        worker = self._estimates.get(key)
        if worker is not None:
            worker.quit()
            self._forget(key)

    def _drop_early(self) -> None:
        if self._early is not None:
            self._early.cancel()
            self._early = None

    def _stop_all(self, *, keep_report: bool = False) -> None:
        self._drop_early()
        if self._source_job is not None:
            self._source_job[0].quit()
            self._source_job = None
        if self._report_job is not None and not keep_report:  # it cannot stop midway: its answer is dropped
            self._report_job.quit()
            self._report_job = None
        self._report_due = self._report_due and keep_report
        for key in list(self._estimates):
            self._stop(key)
        for key in [k for k in self._side_jobs if k[0] == "edges"]:  # an export is not stopped midway
            self._side_jobs.pop(key)[0].quit()
        if self._advice_job is not None:
            # the advisor stops at its next step (its check yields between calls and inside them)
            self._advice_job.quit()
            self._forget_advice()

    def shutdown(self, *, timeout_ms: int = 5000) -> bool:
        """Stop every job and wait for the threads; returns False if some did not finish in time."""
        self._closed = True
        self._stop_all()
        self.whole_file.cancel()
        return QThreadPool.globalInstance().waitForDone(timeout_ms)

