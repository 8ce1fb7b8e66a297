"""Viewer speed: click-to-coloured-frame time and the longest GUI stall during an estimation.

Run with a display (or it re-runs itself under ``xvfb-run``)::

    .venv/bin/python benchmarks/bench_viewer.py [--sizes 100000 1000000] [--method mru --range 2]

For each size it meshes a torus in the real main window, then "clicks" an estimator (switches the
pane, as the Inspect panel does) and reports

- estimate: seconds the worker took (off the GUI thread);
- colour: seconds from the result's arrival to the coloured frame rendered (target: < 3 s at 1M);
- click-to-frame: the whole span;
- stall: the longest gap of a 10 ms QTimer heartbeat from the click until the result arrived
  (target: < 100 ms), and while the mesh was loaded and first shown (that includes the first render).
  The colouring itself runs on the GUI thread (it is the "colour" column).

``--cancel`` measures Cancel instead: it starts the estimate, clicks the real Cancel button a few
seconds in (``--cancel-after``), and reports how long until the window is idle again (controller
not busy, Cancel hidden), how long until the worker thread has really stopped (it stops at the
estimator's next yield), and whether the keyboard focus stayed where it was::

    .venv/bin/python benchmarks/bench_viewer.py --cancel --sizes 250000 --method csm --range 4

``--handlers`` times every GUI-thread handler a user sets off on a big point cloud (default 5M
points): the source arriving (load finished), the first result arriving, a pick (a real mouse
click on the pane), a quantity change, a colour-map change, Recompute (the real button) and Cancel
(the real button, a few seconds into the recompute), and whether the shown result stayed on screen
through Recompute and Cancel::

    .venv/bin/python benchmarks/bench_viewer.py --handlers --sizes 5000000 --method qs

The cloud is synthetic (a wavy terrain with its exact normals, so that the estimate fits no normals),
written once to a temporary vertex-only PLY and opened as a file. For each handler it reports
``call ms``, the time the GUI thread spent in the call that the user's action made (what runs
before the event loop gets control back), ``CPU ms``, the GUI thread's own CPU time in that call
(what the call costs on an idle machine: on a loaded one the wall time also counts the turns other
processes take), and ``stall ms``, the longest gap of a 10 ms heartbeat
from the action until its effect is on screen (frames included: under software GL a frame of 5M
points takes most of a second, which no handler can shorten).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


class Heartbeat:
    """A 10 ms QTimer recording the longest gap between its ticks."""

    def __init__(self):
        from PySide6.QtCore import QTimer

        self.timer = QTimer(interval=10)
        self.timer.timeout.connect(self._tick)
        self.reset()

    def reset(self):
        self.last = time.perf_counter()
        self.max_gap = 0.0

    def _tick(self):
        now = time.perf_counter()
        self.max_gap = max(self.max_gap, now - self.last)
        self.last = now


class StallSampler:
    """A thread that, while the heartbeat is late by more than ``late_s``, samples where the GUI thread
    is (its innermost frames of the project and of VTK/pyvista calls), so that a stall names its code."""

    def __init__(self, beat: Heartbeat, *, late_s: float = 0.3, every_s: float = 0.05):
        import collections
        import threading

        self.beat, self.late_s, self.every_s = beat, late_s, every_s
        self.samples = collections.Counter()
        self._main = threading.main_thread().ident
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def start(self):
        self._thread.start()

    def stop(self):
        self._stop.set()

    def _run(self):
        import traceback

        while not self._stop.wait(self.every_s):
            if time.perf_counter() - self.beat.last < self.late_s:
                continue
            frame = sys._current_frames().get(self._main)
            if frame is None:
                continue
            stack = [f for f in traceback.extract_stack(frame) if "/app/" in f.filename or "pyvista" in f.filename]
            if stack:
                self.samples[" < ".join(f"{Path(f.filename).name}:{f.lineno} {f.name}" for f in reversed(stack[-3:]))] += 1

    def report(self, top=8):
        total = sum(self.samples.values())
        if not total:
            return
        print(f"\nwhere the GUI thread was while the heartbeat was late ({total} samples of {self.every_s:g} s):")
        for where, count in self.samples.most_common(top):
            print(f"  {count:5d}  {where}")


def wait(app, cond, timeout=600.0):
    end = time.perf_counter() + timeout
    while not cond():
        app.processEvents()
        time.sleep(0.001)
        if time.perf_counter() > end:
            raise TimeoutError("benchmark step timed out")


def run(sizes, method, k):
    from PySide6.QtCore import QSettings
    from PySide6.QtWidgets import QApplication

    from app.model import SurfaceSource
    from app.views.main_window import MainWindow

    app = QApplication.instance() or QApplication([])
    tmp = Path(os.environ.get("TMPDIR", "/tmp")) / "curvlab-bench.ini"
    win = MainWindow(settings=QSettings(str(tmp), QSettings.Format.IniFormat))
    win.quiet = True
    win.resize(1400, 860)
    win.show()
    beat = Heartbeat()
    beat.timer.start()
    doc, ctl = win.doc, win.controller
    marks = {}
    original = doc.set_result

    def set_result(key, result):
        marks["result"] = time.perf_counter()
        marks["stall"] = beat.max_gap  # longest GUI gap from the click until the result arrived
        original(key, result)
        marks["drawn"] = time.perf_counter()  # set_result -> result_changed -> redraw + render, in order

    doc.set_result = set_result
    rows = []
    for n in sizes:
        beat.reset()
        t0 = time.perf_counter()
        win.open_surface(SurfaceSource(name="torus", n_vertices=n))
        wait(app, lambda: doc.mesh is not None and doc.mesh.n_vertices > 0.5 * n and not ctl.busy)
        load_s, load_stall = time.perf_counter() - t0, beat.max_gap
        marks.clear()
        app.processEvents()
        beat.reset()
        t_click = time.perf_counter()
        doc.set_pane(0, method=method, range=k)          # what picking an estimator in the panel does
        wait(app, lambda: "drawn" in marks and not ctl.busy)
        stall = marks["stall"]
        res = doc.result(0)
        rows.append(dict(n=doc.mesh.n_vertices, load=load_s, load_stall=load_stall,
                         estimate=res.info.get("seconds", float("nan")), colour=marks["drawn"] - marks["result"],
                         click=marks["drawn"] - t_click, stall=stall))
        doc.set_pane(0, method="mru" if method != "mru" else "nc", range=2)  # next size starts from another key
        ctl.cancel()
    win.close()
    print(f"{'vertices':>9} {'load+show s':>11} {'load stall ms':>13} {'estimate s':>10} "
          f"{'colour s':>8} {'click->frame s':>14} {'est. stall ms':>13}")
    for r in rows:
        print(f"{r['n']:>9} {r['load']:>11.2f} {1000 * r['load_stall']:>13.0f} {r['estimate']:>10.2f} "
              f"{r['colour']:>8.2f} {r['click']:>14.2f} {1000 * r['stall']:>13.0f}")
    return rows


def run_cancel(sizes, method, k, *, after: float, repeats: int):
    from PySide6.QtCore import QSettings, QThreadPool, Qt
    from PySide6.QtTest import QTest
    from PySide6.QtWidgets import QApplication

    from app.model import SurfaceSource
    from app.views.main_window import MainWindow

    app = QApplication.instance() or QApplication([])
    tmp = Path(os.environ.get("TMPDIR", "/tmp")) / "curvlab-bench-cancel.ini"
    win = MainWindow(settings=QSettings(str(tmp), QSettings.Format.IniFormat))
    win.quiet = True
    win.resize(1600, 1000)
    win.show()
    win.activateWindow()
    doc, ctl = win.doc, win.controller
    pool = QThreadPool.globalInstance()
    print(f"{'vertices':>9} {'estimate':>10} {'cancel at s':>11} {'idle ms':>8} {'worker stopped ms':>17} focus kept")
    for n in sizes:
        win.open_surface(SurfaceSource(name="torus", n_vertices=n))
        wait(app, lambda: doc.mesh is not None and doc.mesh.n_vertices > 0.5 * n and not ctl.busy)
        wait(app, lambda: pool.activeThreadCount() == 0)
        for r in range(repeats):
            win.inspect.quantity.setFocus()
            app.processEvents()
            focused = QApplication.focusWidget()
            ctl.recompute((method, f"R{k}")) if (method, f"R{k}") in doc.results else None
            doc.set_pane(0, method=method, range=k)
            if (method, f"R{k}") in doc.failures:
                ctl.recompute((method, f"R{k}"))
            t_start = time.perf_counter()
            wait(app, lambda: time.perf_counter() - t_start > after * (1 + r) / repeats)
            if not ctl.busy:
                print(f"{doc.mesh.n_vertices:>9} finished before the cancel point; use a larger mesh or range")
                break
            t0 = time.perf_counter()
            QTest.mouseClick(win.cancel_button, Qt.MouseButton.LeftButton)
            wait(app, lambda: not ctl.busy and not win.cancel_button.isVisible())
            idle = time.perf_counter() - t0
            wait(app, lambda: pool.activeThreadCount() == 0)
            stopped = time.perf_counter() - t0
            print(f"{doc.mesh.n_vertices:>9} {method + ' R' + str(k):>10} {t0 - t_start:>11.2f} {1000 * idle:>8.1f} "
                  f"{1000 * stopped:>17.0f} {QApplication.focusWidget() is focused}")
            doc.set_pane(0, method="mru", range=2)
            wait(app, lambda: not ctl.busy)
            wait(app, lambda: pool.activeThreadCount() == 0)
    win.close()


def terrain_ply(n: int, folder: Path) -> Path:
    """A vertex-only binary PLY of ``n`` points of a wavy terrain with its exact unit normals."""
    import numpy as np

    path = folder / f"curvlab-bench-terrain-{n}.ply"
    if path.exists():
        return path
    rng = np.random.default_rng(0)
    side = 1000.0
    x, y = rng.uniform(0, side, n), rng.uniform(0, side, n)
    a, w = 5.0, 2 * np.pi / 120.0
    z = a * np.sin(w * x) * np.cos(w * y)
    zx, zy = a * w * np.cos(w * x) * np.cos(w * y), -a * w * np.sin(w * x) * np.sin(w * y)
    normals = np.column_stack([-zx, -zy, np.ones(n)])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    rows = np.empty(n, dtype=[(c, "<f8") for c in ("x", "y", "z", "nx", "ny", "nz")])
    for c, v in zip(("x", "y", "z"), (x, y, z)):
        rows[c] = v
    for i, c in enumerate(("nx", "ny", "nz")):
        rows[c] = normals[:, i]
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {n}\n" + "".join(f"property double {c}\n" for c in rows.dtype.names)
              + "end_header\n")
    tmp = path.with_suffix(".part")
    with open(tmp, "wb") as fh:
        fh.write(header.encode("ascii"))
        rows.tofile(fh)
    tmp.rename(path)
    return path


def run_handlers(sizes, method, k, *, cancel_after: float, keep: bool, trace: bool = False, preview: bool = False):
    """Time every GUI-thread handler on a big cloud (module notes, ``--handlers``; ``preview``: open the
    file as the viewer does, a decimated preview above its limit, instead of drawing it whole)."""
    from PySide6.QtCore import QPoint, QSettings, QThreadPool, Qt
    from PySide6.QtTest import QTest
    from PySide6.QtWidgets import QApplication

    from app.model import Quantity
    from app.views.main_window import MainWindow

    app = QApplication.instance() or QApplication([])
    if not preview:
        try:  # the file drawn whole, as an in-memory cloud or a file below the preview limit is
            from app.model import large

            large.PREVIEW_LIMIT = max(large.PREVIEW_LIMIT, *sizes)
        except ImportError:  # a tree without previews draws every file whole
            pass
    folder = Path(os.environ.get("TMPDIR", "/tmp"))
    tmp = folder / "curvlab-bench-handlers.ini"
    tmp.unlink(missing_ok=True)
    win = MainWindow(settings=QSettings(str(tmp), QSettings.Format.IniFormat))
    win.quiet = True
    win.resize(1400, 860)
    win.show()
    beat = Heartbeat()
    beat.timer.start()
    sampler = StallSampler(beat) if trace else None
    if sampler is not None:
        sampler.start()
    doc, ctl = win.doc, win.controller
    pool = QThreadPool.globalInstance()

    def settle(cond=lambda: True, extra=0.5):
        """Run the loop until ``cond`` holds, no job runs and the window has drawn what it was asked to
        (then ``extra`` seconds more); the longest stall."""
        drawing = getattr(win, "drawing", None)  # the window's drawing state (none in older trees)
        wait(app, lambda: cond() and not ctl.busy and (drawing is None or not drawing.pending))
        end = time.perf_counter() + extra
        while time.perf_counter() < end:
            app.processEvents()
            time.sleep(0.002)
        return beat.max_gap

    timed = {}

    def timing(obj, name, label):
        """Wrap ``obj.name`` so that each call's duration is kept under ``label``."""
        original = getattr(obj, name)

        def wrapper(*args, **kwargs):
            t0, c0 = time.perf_counter(), time.thread_time()
            try:
                return original(*args, **kwargs)
            finally:
                timed.setdefault(label, []).append((time.perf_counter() - t0, time.thread_time() - c0))

        setattr(obj, name, wrapper)

    # the two handlers that workers' signals call: a source arriving, a result arriving
    timing(doc, "set_mesh", "load finished")
    timing(doc, "set_result", "result arrived")
    rows = []
    for n in sizes:
        path = terrain_ply(n, folder)
        doc.set_pane_count(1)
        doc.set_pane(0, method=method, range=k)
        timed.clear()
        beat.reset()
        t0 = time.perf_counter()
        win.open_path(path)
        stall_load = settle(lambda: doc.mesh is not None and Path(getattr(doc.source, "path", "")) == path
                            and doc.result(0) is not None)
        shown = doc.mesh.n_vertices
        total = time.perf_counter() - t0
        res = doc.result(0)
        def spent(label):
            calls = timed.get(label, [])
            return 1000 * sum(c[0] for c in calls), 1000 * sum(c[1] for c in calls)

        row = [("load finished", *spent("load finished"), None),
               ("result arrived", *spent("result arrived"), None),
               ("load + estimate + first frame", None, None, 1000 * stall_load)]
        vp = win.grid.viewports[0]
        plotter = vp.plotter

        def act(label, action, cond=lambda: True):
            app.processEvents()
            beat.reset()
            t, c = time.perf_counter(), time.thread_time()
            action()
            call, cpu = time.perf_counter() - t, time.thread_time() - c
            stall = settle(cond)
            row.append((label, 1000 * call, 1000 * cpu, 1000 * max(stall, call)))

        centre = QPoint(plotter.width() // 2, plotter.height() // 2)

        def click():
            QTest.mousePress(plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, centre)
            QTest.mouseRelease(plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, centre)

        act("pick", click, lambda: doc.picked is not None)
        act("quantity change", lambda: win.inspect.quantity.setCurrentEnum(Quantity.GAUSSIAN))
        other = next(name for name in (win.inspect.cmap_seq.itemText(i) for i in range(win.inspect.cmap_seq.count()))
                     if name != doc.display.state.sequential_cmap)
        act("colour change", lambda: win.inspect.cmap_seq.setCurrentText(other))
        # Recompute, then Cancel a few seconds in: the shown result must stay through both
        app.processEvents()
        beat.reset()
        t, c = time.perf_counter(), time.thread_time()
        QTest.mouseClick(win.inspect.recompute, Qt.MouseButton.LeftButton)
        call, cpu = time.perf_counter() - t, time.thread_time() - c
        kept_recompute = doc.result(0) is not None
        end = time.perf_counter() + cancel_after
        while time.perf_counter() < end and ctl.busy:
            app.processEvents()
            time.sleep(0.002)
        row.append(("recompute", 1000 * call, 1000 * cpu, 1000 * beat.max_gap))
        running = ctl.busy
        act("cancel", lambda: QTest.mouseClick(win.cancel_button, Qt.MouseButton.LeftButton))
        kept_cancel = doc.result(0) is not None and doc.result(0) is res if running else None
        wait(app, lambda: pool.activeThreadCount() == 0)
        # one frame of the scene as it is, for scale: no handler draws more than this, none draws it twice
        settle()
        vp.plotter.renderer.GetActiveCamera().Modified()
        t = time.perf_counter()
        win.grid.render_all()
        row.append(("one frame (VTK draw)", None, None, 1000 * (time.perf_counter() - t)))
        rows.append((n, shown, row, kept_recompute, kept_cancel, total))
    win.close()
    if sampler is not None:
        sampler.stop()
        sampler.report()
    if not keep:
        for n in sizes:
            (folder / f"curvlab-bench-terrain-{n}.ply").unlink(missing_ok=True)
    for n, shown, row, kept_recompute, kept_cancel, total in rows:
        whole = "drawn whole" if shown == n else f"a preview of {shown:,}"
        print(f"\n{n:,} points ({whole}), {method} R{k}: load to first coloured frame {total:.1f} s "
              f"(load average at the end {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
        print(f"{'handler':<32} {'call ms':>9} {'CPU ms':>9} {'stall ms':>9}")
        for label, *cells in row:
            print(f"{label:<32} " + " ".join("" .rjust(9) if v is None else f"{v:9.0f}" for v in cells))
        print(f"result shown through Recompute: {'yes' if kept_recompute else 'no'}; after Cancel: "
              + ("yes" if kept_cancel else "no" if kept_cancel is not None else "(the recompute ended first)"))
    return rows


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    p.add_argument("--method", default="nc")
    p.add_argument("--range", type=int, default=2)
    p.add_argument("--cancel", action="store_true", help="measure Cancel latency instead")
    p.add_argument("--cancel-after", type=float, default=3.0, help="seconds into the estimate of the last cancel")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--handlers", action="store_true", help="time every GUI-thread handler on a big cloud")
    p.add_argument("--keep", action="store_true", help="--handlers: keep the temporary PLY for the next run")
    p.add_argument("--preview", action="store_true",
                   help="--handlers: open the file as the viewer does (a preview above its limit), not whole")
    p.add_argument("--trace-stalls", action="store_true", help="--handlers: say where the GUI thread was while late")
    args = p.parse_args(argv)
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY") and shutil.which("xvfb-run") \
            and not os.environ.get("CURVLAB_BENCH_CHILD"):
        os.environ["CURVLAB_BENCH_CHILD"] = "1"
        cmd = ["xvfb-run", "-a", "-s", "-screen 0 1600x1000x24", sys.executable, *sys.argv]
        os.execvp(cmd[0], cmd)
    if args.handlers:
        run_handlers(args.sizes, args.method, args.range, cancel_after=args.cancel_after, keep=args.keep,
                     trace=args.trace_stalls, preview=args.preview)
    elif args.cancel:
        run_cancel(args.sizes, args.method, args.range, after=args.cancel_after, repeats=args.repeats)
    else:
        run(args.sizes, args.method, args.range)


if __name__ == "__main__":
    main()
