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


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    p.add_argument("--method", default="nc")
    p.add_argument("--range", type=int, default=2)
    p.add_argument("--cancel", action="store_true", help="measure Cancel latency instead")
    p.add_argument("--cancel-after", type=float, default=3.0, help="seconds into the estimate of the last cancel")
    p.add_argument("--repeats", type=int, default=3)
    args = p.parse_args(argv)
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY") and shutil.which("xvfb-run") \
            and not os.environ.get("CURVLAB_BENCH_CHILD"):
        os.environ["CURVLAB_BENCH_CHILD"] = "1"
        cmd = ["xvfb-run", "-a", "-s", "-screen 0 1600x1000x24", sys.executable, *sys.argv]
        os.execvp(cmd[0], cmd)
    if args.cancel:
        run_cancel(args.sizes, args.method, args.range, after=args.cancel_after, repeats=args.repeats)
    else:
        run(args.sizes, args.method, args.range)


if __name__ == "__main__":
    main()
