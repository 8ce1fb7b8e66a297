"""``python -m tools.advice_table [extend|fill|refeature|reselect] ...``: build, extend, fill or
refeature the advisor's table (the commands and their order: the package's docstring)."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from . import __doc__ as _PACKAGE_DOC
from .base import (DEFAULT_CLOSED, DEFAULT_CLOSED_VERTICES, DEFAULT_DENSITIES, DEFAULT_IRREGULARITY, DEFAULT_NOISE,
                   DEFAULT_OUT, DEFAULT_SAMPLES, build_table, table_command, table_settings)
from .extend import (COARSE_CLOSED_VERTICES, coarse_jobs, extend_table, extension_jobs, fill_jobs, fill_table,
                     load_base, noise_jobs, run_extension)
from .kernel import key_text
from .refeature import FEATURE_MEASURES, _write_selected, feature_row, refeature_table, reselect_table

def extend_main(argv) -> int:
    """``python -m tools.advice_table extend``: add the options and the coarse meshes to a table."""
    parser = argparse.ArgumentParser(prog="python -m tools.advice_table extend", description=extend_main.__doc__)
    parser.add_argument("--base", default=str(DEFAULT_OUT), help="table to extend; default the packaged one")
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    parser.add_argument("--work", default="advisor-extension", help="keeps the computed meshes (resumes)")
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--samples", type=int, default=1, help="samples of each coarse setting")
    parser.add_argument("--option-samples", type=int, default=1, help="base samples the options run on")
    parser.add_argument("--dry-run", action="store_true", help="count the jobs and stop")
    args = parser.parse_args(argv)
    base = load_base(args.base)
    jobs = extension_jobs(base, samples=args.samples, option_samples=args.option_samples)
    if args.dry_run:
        print(f"{len(jobs)} jobs, {sum(len(j[1]) for j in jobs)} estimates")
        return 0
    t0 = time.process_time()
    done = run_extension(jobs, args.work, workers=args.workers, progress=lambda t: print(t, flush=True))
    command = table_command(argv, "extend")
    table = extend_table(base, done, command=command, jobs=jobs)
    table["metadata"]["extension_cpu_seconds_main_process"] = round(time.process_time() - t0, 1)
    with open(args.out, "w") as fh:
        json.dump(table, fh, separators=(",", ":"))
    print(f"wrote {args.out}: {len(table['points'])} meshes x {len(table['variants'])} variants; bandwidth "
          f"{table['kernel']['bandwidth']} (LOO mean regret {table['kernel']['loo_mean_regret']})", flush=True)
    return 0



def fill_main(argv) -> int:
    """``python -m tools.advice_table fill``: run the variants a table's meshes of some kinds have no
    value for (by default the option candidates on the closed surfaces of samples 1 and 2)."""
    parser = argparse.ArgumentParser(prog="python -m tools.advice_table fill", description=fill_main.__doc__)
    parser.add_argument("--table", default=str(DEFAULT_OUT))
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    parser.add_argument("--work", default="advisor-fill", help="keeps the computed meshes (resumes)")
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--kinds", nargs="*", default=list(DEFAULT_CLOSED),
                        help="kinds of mesh whose empty cells are run (none: only --coarse-samples)")
    parser.add_argument("--coarse-samples", type=int, default=1,
                        help="random surfaces per coarse setting: the missing ones are added as new rows")
    parser.add_argument("--sizes", type=int, nargs="+", default=None,
                        help="fill only the meshes of these densities / vertex counts (default all)")
    parser.add_argument("--coarse-closed-vertices", type=int, nargs="+", default=None,
                        help="coarse closed-surface sizes (default the table's, else "
                             f"{' '.join(map(str, COARSE_CLOSED_VERTICES))}): sizes it lacks are added")
    parser.add_argument("--noise-levels", type=float, nargs="+", default=(),
                        help="add the noise twins at these levels (fractions of the paper's) of every noise-free "
                             "mesh (of --sizes if given) as new rows, every variant")
    parser.add_argument("--dry-run", action="store_true", help="count the jobs and stop")
    args = parser.parse_args(argv)
    with open(args.table) as fh:
        table = json.load(fh)
    sizes = args.coarse_closed_vertices or table.get("metadata", {}).get("coarse", {}).get(
        "closed_vertices", list(COARSE_CLOSED_VERTICES))
    new = coarse_jobs(table, args.coarse_samples, sizes) + noise_jobs(table, args.noise_levels, args.sizes)
    jobs = fill_jobs(table, kinds=tuple(args.kinds), sizes=args.sizes) + new
    if args.dry_run:
        print(f"{len(jobs)} jobs, {sum(len(j[1]) for j in jobs)} estimates")
        return 0
    done = run_extension(jobs, args.work, workers=args.workers, progress=lambda t: print(t, flush=True))
    out = fill_table(table, done, command=table_command(argv, "fill"),
                     new_keys=[j[0] for j in new], closed_vertices=sizes)
    if args.noise_levels:  # the levels between the grid's, as rows of every noise-free mesh's twins
        meta = out["metadata"]
        meta["twin_noise_levels"] = sorted({*meta.get("twin_noise_levels", []), *map(float, args.noise_levels)})
    with open(args.out, "w") as fh:
        json.dump(out, fh, separators=(",", ":"))
    print(f"wrote {args.out}: {out['metadata']['filled_cells']} cells filled", flush=True)
    return 0



def reselect_main(argv) -> int:
    """``python -m tools.advice_table reselect``: choose the kernel's axes again over a table's stored
    points (no mesh is built or measured)."""
    parser = argparse.ArgumentParser(prog="python -m tools.advice_table reselect", description=reselect_main.__doc__)
    parser.add_argument("--table", default=str(DEFAULT_OUT), help="table to reselect; default the packaged one")
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    args = parser.parse_args(argv)
    with open(args.table) as fh:
        table = json.load(fh)
    t0 = time.perf_counter()
    out = reselect_table(table, command=table_command(argv, "reselect"),
                         progress=lambda t: print(t, flush=True))
    out["metadata"]["reselect_seconds"] = round(time.perf_counter() - t0, 1)
    return _write_selected(out, args.out)


def refeature_main(argv) -> int:
    """``python -m tools.advice_table refeature``: measure the extra columns on a table's meshes
    (rebuilt from their keys; no estimator runs but the measuring fit) and choose the kernel's axes."""
    parser = argparse.ArgumentParser(prog="python -m tools.advice_table refeature",
                                     description=refeature_main.__doc__)
    parser.add_argument("--table", default=str(DEFAULT_OUT), help="table to refeature; default the packaged one")
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    parser.add_argument("--work", default="advisor-refeature", help="keeps the measured rows (resumes)")
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args(argv)
    from curv.study.executors import open_executor

    with open(args.table) as fh:
        table = json.load(fh)
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    path = work / "features.json"
    rows = json.loads(path.read_text()) if path.exists() else {}
    if rows.get("measures") != FEATURE_MEASURES:
        rows = {"measures": FEATURE_MEASURES}
    todo = [k for k in table["truth"]["key"] if key_text(k) not in rows]
    t0, c0 = time.perf_counter(), time.process_time()
    with open_executor(workers=args.workers) as ex:
        for b in range(0, len(todo), 64):
            part = todo[b:b + 64]
            for k, row in zip(part, ex.map(feature_row, part)):
                rows[key_text(k)] = row
            path.write_text(json.dumps(rows))
            print(f"{min(b + 64, len(todo))}/{len(todo)} meshes measured, {time.perf_counter() - t0:.0f} s", flush=True)
    command = table_command(argv, "refeature")
    out = refeature_table(table, rows, command=command, progress=lambda t: print(t, flush=True))
    out["metadata"]["refeature_seconds"] = round(time.perf_counter() - t0, 1)
    out["metadata"]["refeature_cpu_seconds_main_process"] = round(time.process_time() - c0, 1)
    return _write_selected(out, args.out)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["extend"]:
        return extend_main(argv[1:])
    if argv[:1] == ["fill"]:
        return fill_main(argv[1:])
    if argv[:1] == ["refeature"]:
        return refeature_main(argv[1:])
    if argv[:1] == ["reselect"]:
        return reselect_main(argv[1:])
    parser = argparse.ArgumentParser(prog="python -m tools.advice_table", description=_PACKAGE_DOC.splitlines()[0])
    parser.add_argument("--out", default=str(DEFAULT_OUT), help="table to write; default the packaged one")
    parser.add_argument("--work", default="advisor-study", help="study directory (resumes); default ./advisor-study")
    parser.add_argument("--samples", type=int, default=DEFAULT_SAMPLES)
    parser.add_argument("--densities", type=int, nargs="+", default=list(DEFAULT_DENSITIES),
                        help="hexagon vertex counts 3s(s+1)+1")
    parser.add_argument("--noise", type=float, nargs="+", default=list(DEFAULT_NOISE))
    parser.add_argument("--irregularity", type=float, nargs="+", default=list(DEFAULT_IRREGULARITY))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=None, help="local processes; default the study's")
    parser.add_argument("--closed", nargs="*", default=list(DEFAULT_CLOSED), help="closed surfaces to add")
    parser.add_argument("--closed-vertices", type=int, nargs="+", default=list(DEFAULT_CLOSED_VERTICES))
    args = parser.parse_args(argv)
    settings = table_settings(samples=args.samples, densities=args.densities, noise=args.noise,
                              irregularity=args.irregularity, seed=args.seed)
    command = table_command(argv)
    table = build_table(settings, args.work, workers=args.workers, command=command,
                        closed=tuple(args.closed), closed_vertices=tuple(args.closed_vertices),
                        progress=lambda text: print(text, flush=True))
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w") as fh:
        json.dump(table, fh, separators=(",", ":"))
    meta = table["metadata"]
    print(f"wrote {args.out}: {meta['n_meshes']} meshes x {len(table['variants'])} variants; "
          f"calibration {table['calibration']}; bandwidth {table['kernel']['bandwidth']} "
          f"(LOO mean regret {table['kernel']['loo_mean_regret']}); study {meta['study_seconds']} s, "
          f"features {meta['features_seconds']} s, closed surfaces {meta['closed_seconds']} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
