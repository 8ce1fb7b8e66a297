"""``curv study``: run the paper's evaluation grid and write its table, figures and report.

Wired into ``curv/cli.py`` through :func:`add_study_parser` and :func:`run_study`. Heavy imports
(matplotlib, dask) happen only when the command runs.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from .protocol import DENSITIES, FUNCTIONS, Preset, StudySettings, preset_settings

__all__ = ["add_study_parser", "run_study", "settings_from_args", "StudyProgressBar"]

EXIT_INTERRUPTED = 130

_FUNCTION_ALIASES = {"ellipsoid": "ellipsoid_patch", "trig": "trigonometric", "quad": "quadratic"}


def _function(text: str) -> str:
    name = _FUNCTION_ALIASES.get(text, text)
    if name not in FUNCTIONS:
        raise argparse.ArgumentTypeError(f"unknown function {text!r}; choose from {', '.join(FUNCTIONS)}")
    return name


def _density(text: str) -> int:
    """A hexagon subdivision's vertex count (the rule is :func:`curv.surfaces.hexagon.hexagon_subdivisions`'s)."""
    from ..surfaces.hexagon import hexagon_subdivisions

    try:
        d = int(text)
        hexagon_subdivisions(d)
    except ValueError as exc:
        detail = str(exc) if text.strip().lstrip("-").isdigit() else f"not a whole number: {text!r}"
        raise argparse.ArgumentTypeError(detail) from None
    return d


def _nonneg(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if x < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return x


def add_study_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``study`` sub-command to an ``argparse`` sub-parser collection."""
    p = subparsers.add_parser(
        "study", help="run the paper's §5 evaluation study",
        description="Evaluate every estimator on random Monge patches over densities, noise levels and "
                    "irregularities (paper §5); write results.csv, table1.md, fig8-10.png and report.md. "
                    "Rerunning with the same --out resumes: finished tasks are skipped.",
    )
    p.add_argument("--out", required=True, type=Path, help="output directory (results are appended here)")
    p.add_argument("--preset", choices=[x.value for x in Preset], default="quick",
                   help="grid to start from: quick (CI, < 1 min), medium (docs, < 30 min on 2 cores), "
                        "paper (full grid, N=1000, for a cluster); default quick; the options below override it")
    p.add_argument("--samples", "-n", type=int, help="random surfaces per setting")
    p.add_argument("--densities", nargs="+", type=_density, metavar="V",
                   help=f"vertex counts of the subdivided hexagon, 3s(s+1)+1: the paper's {' '.join(map(str, DENSITIES))} "
                        "or any other, e.g. 1801")
    p.add_argument("--noise", nargs="+", type=_nonneg, metavar="PCT",
                   help="noise levels in percent of the full level (σ = 10%% of the mean edge), e.g. 0 33 66 100")
    p.add_argument("--irregularity", nargs="+", type=_nonneg, metavar="DEG",
                   help="target RMS angle deviations from 60°, e.g. 0 14 25")
    p.add_argument("--functions", nargs="+", type=_function, metavar="F", help=f"from {', '.join(FUNCTIONS)}")
    p.add_argument("--estimators", nargs="+", metavar="SEL",
                   help="estimators: name (all its ranges), name:R2, name:R2,R3 or name:R2SM; default all registered")
    p.add_argument("--seed", type=int, help="root of all random streams; default 0")
    p.add_argument("--scheduler", metavar="ADDR", help="Dask scheduler address, e.g. tcp://host:8786; default local processes")
    p.add_argument("--workers", type=int, help="local worker processes (default: CPU count; 0 = in this process)")
    p.add_argument("--measure", choices=["rms_erel", "median_erel"], default="rms_erel",
                   help="measure of the report and figures; default the paper's RMS of e_rel < 1")
    p.add_argument("--report-only", action="store_true", help="only rebuild the report from the results in --out")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress output")
    p.set_defaults(func=run_study)
    return p


def settings_from_args(args) -> StudySettings:
    """The preset with the command-line overrides applied."""
    base = preset_settings(args.preset)
    return base.with_(
        samples=args.samples, densities=args.densities, irregularity=args.irregularity, functions=args.functions,
        noise=[x / 100.0 for x in args.noise] if args.noise else None,
        estimators=args.estimators, seed=args.seed,
    )


def _clock(seconds: float | None) -> str:
    if seconds is None:
        return "--:--:--"
    s = int(round(seconds))
    return f"{s // 3600:02d}:{s % 3600 // 60:02d}:{s % 60:02d}"


class StudyProgressBar:
    """Task progress with ETA on stderr: a redrawn bar on a terminal, a line every ~10 s otherwise."""

    def __init__(self, *, stream=None, enabled: bool = True, interval: float = 10.0):
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.tty = self.stream.isatty()
        self.interval = interval
        self._last = -1e9

    def update(self, p) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        final = p.done == p.total
        if not final and now - self._last < (0.2 if self.tty else self.interval):
            return
        self._last = now
        frac = p.fraction
        bar = "#" * int(30 * frac)
        err = f", {p.errors} estimator errors" if p.errors else ""
        text = (f"study [{bar:<30}] {p.done}/{p.total} meshes ({100 * frac:5.1f}%) "
                f"elapsed {_clock(p.elapsed)} ETA {_clock(p.eta if p.done else None)}{err}")
        if self.tty:
            self.stream.write("\r" + text + ("\n" if final else ""))
        else:
            self.stream.write(text + "\n")
        self.stream.flush()


def run_study(args) -> int:
    """Run ``curv study`` with parsed arguments; returns the exit status."""
    from .report import write_report
    from .runner import RESULTS_NAME, iter_study, select
    from .store import ResultsFile

    settings = settings_from_args(args)
    out: Path = args.out
    say = (lambda *a: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    t0 = time.perf_counter()
    if args.report_only:
        table = select(ResultsFile(out / RESULTS_NAME).load(repair=False), settings)
        if not len(table):
            say(f"curv study: no results for these settings in {out / RESULTS_NAME}")
            return 2
    else:
        variants = settings.variants()
        say(f"curv study: {settings.n_tasks} meshes x up to {len(variants)} estimator variants, "
            f"N={settings.samples}, seed {settings.seed}, "
            + (f"Dask scheduler {args.scheduler}" if args.scheduler else
               "in this process" if args.workers == 0 else f"{args.workers or 'all'} local processes")
            + f"; results in {out / RESULTS_NAME}")
        bar = StudyProgressBar(enabled=not args.quiet)
        gen = iter_study(settings, out, scheduler=args.scheduler, workers=args.workers)
        done = 0
        try:
            while True:
                try:
                    p = next(gen)
                except StopIteration as stop:
                    table = stop.value
                    break
                if p.task is None and p.skipped:
                    say(f"curv study: resuming, {p.skipped} meshes already done")
                done = p.done
                bar.update(p)
        except KeyboardInterrupt:
            gen.close()
            print(f"\ncurv study: interrupted; {done} finished meshes are saved in {out / RESULTS_NAME}. "
                  "Run the same command again to resume.", file=sys.stderr)
            return EXIT_INTERRUPTED
    files = write_report(table, settings, out, measure=args.measure, elapsed=time.perf_counter() - t0)
    say(f"curv study: {len(table)} result rows; wrote " + ", ".join(f.name for f in files)
        + f" in {out} ({time.perf_counter() - t0:.0f} s)")
    return 0
