"""A seeded fuzzer of curv's readers: the cases of :mod:`tests.fuzz_seeds`, read in a watched worker.

:func:`run_cases` reads every case in a worker process (``python -m tests.fuzzing --worker``) with
a watchdog that only *detects* a hang (the bound is generous: 30 s plus a second per 100 kB; the
readers are bounded by construction, not by this timeout); the worker runs under a 4 GiB address
space limit, so that an allocation a header made run away surfaces as a failure instead of
swapping the machine. A case must end in a result (finite coordinates, faces in range; with
``estimate``, curvature finite where valid and NaN where not) or a :class:`curv.core.errors.CurvError`
whose message is one line naming the file; with ``cli``, ``curv estimate FILE -o out.ply`` on a
file that does not load must exit 2 with one line, and leave no file in the folder.

The estimate is optional: on a fuzzed cloud with one point moved 2^31 away, ``qs`` took about 100 s
for 200 points (the neighbour search scales with the bounding box), which is the estimators'
matter, not the readers'.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import select
import subprocess
import sys
import time
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tests.fuzz_seeds import Case, Seed, make_case, real_las_seeds, seed_files

WATCHDOG_S = 30.0
WATCHDOG_S_PER_BYTE = 1e-5
MEMORY_LIMIT = 4 << 30
ROOT = Path(__file__).resolve().parents[1]

__all__ = ["check_file", "Worker", "Report", "run_cases", "seed_files", "real_las_seeds"]


# --- the worker: one process reads case after case ---------------------------------------------

def _one_line_error(message: str, path: Path) -> str | None:
    """Why ``message`` is not a proper one-line error naming ``path``; None when it is."""
    if "\n" in message or "\r" in message:
        return "the message has more than one line"
    if str(path) not in message:
        return "the message does not name the file"
    if "not enough memory" in message:
        return "ran out of memory: an allocation was not bounded by the file"
    return None


def _check_result(obj, estimate: bool) -> str | None:
    import curv

    vertices = np.asarray(obj.vertices)
    if not np.isfinite(vertices).all():
        return "a coordinate is not finite"
    if isinstance(obj, curv.Mesh):
        if obj.face_indices.size and (obj.face_indices.min() < 0 or obj.face_indices.max() >= obj.n_vertices):
            return "a face index is out of range"
    elif obj.normals is not None and obj.normals.shape != vertices.shape:
        return "normals of the wrong shape"
    if estimate:
        try:
            res = curv.estimate(obj, "qs", 2)
        except curv.CurvError as exc:
            return "the estimate's error has more than one line" if "\n" in str(exc) else None
        values = np.column_stack([res.k1, res.k2])
        if not np.isfinite(values[res.valid]).all():
            return "a valid point's curvature is not finite"
        if not np.isnan(values[~res.valid]).all():
            return "an invalid point's curvature is not NaN"
    return None


def _run_cli(path: Path) -> str | None:
    """``curv estimate PATH -m qs -o out.ply`` on a file that does not load: exit 2, one line, no file."""
    from curv.cli import main

    out = path.parent / f"{path.stem}-out.ply"
    before = set(path.parent.iterdir())
    err, stdout = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(stdout):
        try:
            code = main(["estimate", str(path), "-m", "qs", "-r", "2", "-o", str(out), "-q"])
        except SystemExit as exc:  # argparse
            code = exc.code
    lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
    left = set(path.parent.iterdir()) - before - {out}
    try:
        if left:
            return f"the CLI left {sorted(p.name for p in left)}"
        if code != 2:
            return f"the CLI exited {code}: {' | '.join(lines)[:300]}"
        if out.exists():
            return "the CLI failed but left an output file"
        if len(lines) != 1 or "Traceback" in err.getvalue():
            return f"the CLI's error is {len(lines)} lines: {' | '.join(lines)[:300]}"
        return None
    finally:
        out.unlink(missing_ok=True)


def check_file(path: Path, *, estimate: bool = False, cli: bool = False) -> dict:
    """Read ``path`` with ``curv.load`` (and optionally estimate, run the CLI); the outcome as a dict."""
    import curv

    t0 = time.perf_counter()
    outcome, detail = "result", ""
    try:
        obj = curv.load(path)
    except curv.CurvError as exc:
        outcome, detail = "error", str(exc)
        problem = _one_line_error(detail, path)
        if problem:
            outcome, detail = "failure", f"{problem}: {detail[:300]!r}"
    except BaseException as exc:  # noqa: BLE001 - the fuzzer's job is to catch these
        if isinstance(exc, KeyboardInterrupt):
            raise
        outcome, detail = "failure", f"traceback: {type(exc).__name__}: {' '.join(str(exc).split())[:300]}"
    else:
        problem = _check_result(obj, estimate)
        if problem:
            outcome, detail = "failure", problem
        else:
            detail = f"{type(obj).__name__} of {obj.n_vertices} points"
    if cli and outcome == "error":  # the CLI on a file that does not load: exit 2, one line, no file left
        problem = _run_cli(path)
        if problem:
            outcome, detail = "failure", problem
    return {"outcome": outcome, "detail": detail, "seconds": time.perf_counter() - t0}


def _worker() -> None:
    """Read JSON requests from stdin, answer each with a JSON line on stdout."""
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # a crash is reported at once, without a core dump
    import tempfile

    import curv  # noqa: F401 - imported once, before the first case

    if "--warm" in sys.argv:  # compile the kernels the estimates run, before the watchdog starts
        with tempfile.TemporaryDirectory(prefix="curv-fuzz-warm-") as folder:
            for seed in seed_files():
                if seed.name in ("PLY binary mesh", "PLY binary cloud"):
                    path = Path(folder) / f"warm{seed.suffix}"
                    path.write_bytes(seed.data)
                    check_file(path, estimate=True)
    out = sys.stdout
    sys.stdout = sys.stderr  # whatever a library prints stays off the answer channel
    out.write(json.dumps({"ready": True}) + "\n")
    out.flush()
    for line in sys.stdin:
        request = json.loads(line)
        answer = check_file(Path(request["path"]), estimate=request["estimate"], cli=request["cli"])
        out.write(json.dumps(answer) + "\n")
        out.flush()


class Worker:
    """A worker process and its answer channel; restarted after a hang or a crash."""

    def __init__(self, warm: bool = False):
        self.proc = None
        self.warm = warm

    def start(self, timeout: float = 1800.0) -> None:
        """Start the worker; a warm one first compiles what the estimates need (minutes after an edit)."""
        env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        flags = ["--worker"] + (["--warm"] if self.warm else [])
        self.proc = subprocess.Popen([sys.executable, "-m", "tests.fuzzing", *flags], cwd=ROOT, env=env,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     text=True, bufsize=1)
        ready = self._answer(timeout)
        if not ready or not ready.get("ready"):
            raise RuntimeError("the fuzz worker did not start")

    def _answer(self, timeout: float) -> dict | None:
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
        if not ready:
            return None
        line = self.proc.stdout.readline()
        return json.loads(line) if line else None

    def ask(self, path: Path, timeout: float, *, estimate: bool, cli: bool) -> dict:
        if self.proc is None or self.proc.poll() is not None:
            self.start()
        self.proc.stdin.write(json.dumps({"path": str(path), "estimate": estimate, "cli": cli}) + "\n")
        self.proc.stdin.flush()
        answer = self._answer(timeout)
        if answer is None:
            try:
                self.proc.wait(timeout=5)  # the end of the answer channel: the worker is dying
            except subprocess.TimeoutExpired:
                pass
            hung = self.proc.poll() is None
            self.stop()
            return {"outcome": "hang" if hung else "crash",
                    "detail": f"no answer within {timeout:.0f} s" if hung else "the worker died",
                    "seconds": timeout}
        return answer

    def stop(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.kill()
            self.proc.wait()
            self.proc = None


@dataclass
class Report:
    """Counts per format and the failures."""

    counts: dict = field(default_factory=lambda: defaultdict(Counter))
    slowest: dict = field(default_factory=lambda: defaultdict(float))
    failures: list = field(default_factory=list)
    bytes_read: int = 0

    def add(self, case: Case, answer: dict) -> None:
        fmt = case.seed.format
        self.counts[fmt]["cases"] += 1
        self.counts[fmt][answer["outcome"]] += 1
        self.slowest[fmt] = max(self.slowest[fmt], answer["seconds"])
        self.bytes_read += len(case.data)
        if answer["outcome"] not in ("result", "error"):
            self.failures.append((case.index, case.seed.name, case.mutation, answer["outcome"], answer["detail"]))

    def table(self) -> str:
        rows = ["| format | cases | results | errors | hangs | failures | slowest case (s) |", "|---|---|---|---|---|---|---|"]
        total = Counter()
        for fmt in sorted(self.counts):
            c = self.counts[fmt]
            total.update(c)
            rows.append(f"| {fmt} | {c['cases']} | {c['result']} | {c['error']} | {c['hang']} | "
                        f"{c['failure'] + c['crash']} | {self.slowest[fmt]:.2f} |")
        rows.append(f"| all | {total['cases']} | {total['result']} | {total['error']} | {total['hang']} | "
                    f"{total['failure'] + total['crash']} | {max(self.slowest.values(), default=0):.2f} |")
        return "\n".join(rows)


def run_cases(n_cases: int, folder: Path, *, master_seed: int = 0, estimate: bool = False, cli_every: int = 0,
              seeds: list[Seed] | None = None, progress=None) -> Report:
    """Read ``n_cases`` mutated files (every ``cli_every``-th through the CLI too) in a watched worker."""
    seeds = seeds or seed_files()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    report, worker = Report(), Worker(warm=estimate)
    try:
        for index in range(n_cases):
            case = make_case(index, seeds, master_seed)
            case_dir = folder / f"case{index % 8}"
            case_dir.mkdir(exist_ok=True)
            path = case_dir / f"case{index}{case.seed.suffix}"
            path.write_bytes(case.data)
            answer = worker.ask(path, WATCHDOG_S + WATCHDOG_S_PER_BYTE * len(case.data), estimate=estimate,
                                cli=bool(cli_every) and index % cli_every == 0)
            report.add(case, answer)
            path.unlink(missing_ok=True)
            if progress is not None:
                progress(index, case, answer)
    finally:
        worker.stop()
    return report


def main(argv=None) -> int:
    import argparse
    import tempfile

    parser = argparse.ArgumentParser(description="Fuzz curv's readers with mutated small files of every format.")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--warm", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=0, help="master seed of the mutations")
    parser.add_argument("--estimate", action="store_true", help="estimate qs R2 on every file that loads")
    parser.add_argument("--cli-every", type=int, default=10, help="run the CLI on every N-th case (0: never)")
    parser.add_argument("--laspy-samples", help="a folder of laspy's sample files, added as seeds")
    args = parser.parse_args(argv)
    if args.worker:
        _worker()
        return 0
    seeds = seed_files() + (real_las_seeds(args.laspy_samples) if args.laspy_samples else [])
    t0 = time.perf_counter()

    def progress(index, case, answer):
        if answer["outcome"] not in ("result", "error"):
            print(f"case {index} ({case.seed.name}; {case.mutation}): {answer['outcome']}: {answer['detail']}",
                  flush=True)
        if (index + 1) % 500 == 0:
            print(f"{index + 1} cases, {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)

    with tempfile.TemporaryDirectory(prefix="curv-fuzz-") as folder:
        report = run_cases(args.cases, Path(folder), master_seed=args.seed, estimate=args.estimate,
                           cli_every=args.cli_every, seeds=seeds, progress=progress)
    print(report.table())
    print(f"{args.cases} cases in {time.perf_counter() - t0:.0f} s; {len(seeds)} seed files")
    return 1 if report.failures else 0


if __name__ == "__main__":
    sys.exit(main())
