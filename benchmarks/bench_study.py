"""What one random surface of the study costs, and where it goes.

    CURV_THREADS=1 .venv/bin/python benchmarks/bench_study.py              # function 0 (48 tasks)
    CURV_THREADS=1 .venv/bin/python benchmarks/bench_study.py --function 2 --rounds 2

Runs the tasks of one random surface and one Monge function of the default grid (every density,
irregularity and noise level: 48 of the surface's 144 meshes) through ``curv.study.tasks.run_task``,
as the study's workers do, after one warm-up task (so numba's cache is loaded, not timed). It prints
the process CPU seconds of the 48 tasks, that times 3 as the cost of one random surface, and the
CPU seconds of each estimator and density (each variant's ``seconds`` is timed by ``run_task``; here
the task clock is the process clock, so the split does not move with the machine's other load; the
ranges of one estimator run in one call, whose time its rows share equally).
"""

from __future__ import annotations

import argparse
import collections
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's curv

from curv.study import tasks as study_tasks  # noqa: E402
from curv.study.protocol import FUNCTIONS, StudySettings  # noqa: E402


class _ProcessClock:
    """Stands in for the ``time`` module inside ``run_task``: its variant timings become CPU seconds."""

    perf_counter = staticmethod(time.process_time)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--function", type=int, default=0, help=f"index into {FUNCTIONS}")
    parser.add_argument("--rounds", type=int, default=1, help="repeat the 48 tasks")
    args = parser.parse_args(argv)

    settings = StudySettings(functions=(FUNCTIONS[args.function],))
    tasks = list(settings.tasks())
    study_tasks.time = _ProcessClock
    study_tasks.run_task(tasks[-1], settings.variants_for(tasks[-1]))  # warm-up: every kernel loaded
    for r in range(args.rounds):
        by_method, by_density = collections.Counter(), collections.Counter()
        start = time.process_time()
        for task in tasks:
            for row in study_tasks.run_task(task, settings.variants_for(task)):
                by_method[row["method"]] += row["seconds"]
                by_density[row["density"]] += row["seconds"]
        cpu = time.process_time() - start
        print(f"round {r + 1}: {len(tasks)} tasks of {FUNCTIONS[args.function]}: {cpu:.1f} CPU s; "
              f"one random surface (x 3 functions): {3 * cpu:.0f} CPU s")
        print("  by estimator: " + ", ".join(f"{m} {s:.1f}" for m, s in by_method.most_common()))
        print("  by density:   " + ", ".join(f"{d} {s:.1f}" for d, s in sorted(by_density.items())))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
