"""``curv estimate`` on tiles: its flags, when it tiles, its progress line and its summary.

``curv estimate IN -o OUT [--tile-size N] [--memory 4GB] [--scheduler ADDRESS]`` runs tile by tile
(:func:`curv.tiles.estimate_file`) when asked (``--tile-size``, ``--scheduler``) or when the whole
input's estimate would not fit in the memory budget (``--memory``, default half the machine's total
memory, :func:`curv.tiles.budget.default_budget`: the same answer whatever other processes hold now;
:func:`curv.tiles.budget.needs_tiles`); otherwise the command runs as it always did.
"""

from __future__ import annotations

import sys

from ..core.errors import CurvError

__all__ = ["add_arguments", "wants_tiles", "run", "las_output", "check_las_output"]


def add_arguments(parser) -> None:
    """The tiled run's flags of ``curv estimate``."""
    from ..formats.laswrite import GROUPS

    group = parser.add_argument_group("large inputs (tiles)")
    group.add_argument("--tile-size", type=int, metavar="N",
                       help="estimate tile by tile, at most N points (vertices) a tile, whatever the input's size; "
                            "the result equals the whole estimate's (docs/LARGE_SCANS.md); -o .ply, .vtu, .vtp, or .las/.laz "
                            "for a LAS input")
    group.add_argument("--memory", metavar="SIZE",
                       help="memory budget of the whole run, every process (e.g. 4GB); an input whose estimate "
                            "would not fit is tiled. Default half the machine's total memory")
    group.add_argument("--scheduler", metavar="ADDRESS",
                       help="run the tiles on the Dask cluster at ADDRESS (tcp://host:8786); its workers must see "
                            "the input and the scratch folder")
    group.add_argument("--workers", type=int, metavar="N",
                       help="worker processes of the local cluster (default: the cores the budget can feed)")
    group.add_argument("--scratch", metavar="DIR",
                       help="the tiled run's scratch folder (default .OUTPUT.tiles beside the output); an "
                            "interrupted run resumes from it")
    group.add_argument("--keep-scratch", action="store_true", help="keep the scratch folder after the run")
    group.add_argument("--las-extra", nargs="+", choices=list(GROUPS), default=(), metavar="GROUP",
                       help="LAS/LAZ output: also write " + ", ".join(GROUPS) + " as extra bytes")


def las_output(path) -> bool:
    """Whether ``path`` is a LAS/LAZ output (the input's records kept, :mod:`curv.formats.laswrite`)."""
    from pathlib import Path

    return path is not None and Path(path).suffix.lower() in (".las", ".laz")


def wants_tiles(args, counts, *, points: bool) -> bool:
    """Whether this ``curv estimate`` runs on tiles (module notes). ``counts`` is ``(points, faces)``
    from the file's header, or None when the header does not say (then only when asked)."""
    from .budget import default_budget, needs_tiles, parse_memory

    if args.tile_size is not None or args.scheduler is not None:
        return True
    if counts is None or (args.memory is None and not args.memory_check):
        return False
    try:
        total = parse_memory(args.memory) if args.memory is not None else default_budget()
    except ValueError as exc:
        raise CurvError(str(exc)) from None
    return needs_tiles(counts[0], counts[1], args.method, total, points=points)


def check_las_output(args) -> None:
    """A LAS/LAZ output keeps the input's records: refuse it for another input (one line); its
    ``errors`` group needs the standard errors computed (``--standard-errors``, opt-in)."""
    from pathlib import Path

    if las_output(args.output) and Path(args.input).suffix.lower() not in (".las", ".laz"):
        raise CurvError(f"{args.output}: a LAS/LAZ output keeps the input's point records; the input must be "
                        f"LAS/LAZ (write .ply, .vtu or .vtp instead)")
    if "errors" in args.las_extra and not args.standard_errors:
        raise CurvError("--las-extra errors writes the standard errors k1_se and k2_se: add --standard-errors "
                        "(they are computed only when asked)")


def _refuse_for_tiles(args, points: bool) -> None:
    """The options a tiled run cannot take, refused in one line before any work."""
    if not args.output:
        raise CurvError("a tiled run writes its result to a file: give -o OUT (.ply, .vtu, .vtp, "
                        "or .las/.laz for a LAS input)")
    given = [flag for flag, value in (("--vertices", args.vertices), ("--region", args.region),
                                      ("--smooth", getattr(args, "smooth", None))) if value is not None]
    if given:
        raise CurvError(f"{', '.join(given)} cannot run on tiles (a tiled run estimates every point whole; "
                        f"estimate a region of a large file with curv.estimate(vertices=) on the part you read)")
    if args.tile_size is not None and args.tile_size < 1:
        raise CurvError(f"--tile-size must be a positive number of points; got {args.tile_size}")


def run(args, *, points: bool, progress=None) -> int:
    """``curv estimate`` on tiles: the run, its progress and its summary on stdout.

    ``progress`` is the command's :class:`curv.progress.PhaseProgress` (default one of its own on
    stderr): the run is its phase ``tiles``, whose live words say the tiles done, the points a
    second and the time left (:func:`curv.tiles.iter_estimate_file`'s messages).
    """
    from ..progress import PhaseProgress
    from ..core.ranges import resolve
    from ..estimators import get_spec
    from .budget import parse_memory
    from .files import iter_estimate_file

    _refuse_for_tiles(args, points)
    spec = get_spec(args.method)
    rng = resolve(spec, args.range, args.radius, args.knn)
    keywords = _keywords(args, points)
    try:
        memory = parse_memory(args.memory) if args.memory is not None else None
    except ValueError as exc:
        raise CurvError(str(exc)) from None
    gen = iter_estimate_file(args.input, args.output, spec.name, rng.k, radius=rng.radius, knn=rng.knn,
                             tile_size=args.tile_size, memory=memory, workers=args.workers, scheduler=args.scheduler,
                             scratch=args.scratch, keep_scratch=args.keep_scratch, quantity=args.quantity,
                             cmap=args.cmap, clim=tuple(args.clim) if args.clim else None,
                             las_extra=tuple(args.las_extra), **keywords)
    own = progress is None
    if own:
        progress = PhaseProgress(mode="off" if args.quiet else None)
    progress.label = f"{spec.name} {rng.label}"
    progress.phase("tiles")
    try:
        while True:
            try:
                step = next(gen)
            except StopIteration as stop:
                run_ = stop.value
                break
            progress.update(float(step))
            progress.status(getattr(step, "message", "") or "")
    except KeyboardInterrupt:
        gen.close()
        progress.close(completed=False)
        print(f"curv: interrupted; no output written. The same command resumes from the finished tiles "
              f"(scratch folder kept)", file=sys.stderr)
        raise
    except BaseException:
        gen.close()
        progress.close(completed=False)
        raise
    progress.close()
    _summary(args, run_, rng)
    return 0


def _keywords(args, points: bool) -> dict:
    """The estimate's keywords from the command's flags (as the in-memory command passes them)."""
    out = {}
    if points:
        out["normals"] = args.normals
        out["orient"] = args.orient_normals
    else:
        if args.normals == "fit":
            out["normals"] = "fit"
        elif args.normals not in (None, "max"):
            out["normal_weighting"] = args.normals
        if args.features is not None:
            from ..core.features import check_angle

            out["features"] = check_angle(args.features)
    if args.fit_range is not None:
        out["fit_range"] = args.fit_range
    for name in ("degree", "weights", "width", "noise_model"):
        if getattr(args, name, None) is not None:
            out[name] = getattr(args, name)
    if args.standard_errors:
        out["standard_errors"] = True
    return out


def _summary(args, run_, rng) -> None:
    from ..memory import format_bytes

    unit = "vertices" if run_.mesh else "points"
    reasons = dict(run_.reasons)
    valid = reasons.pop("OK", 0)
    invalid = ", ".join(f"{k.lower().replace('_', ' ')} {v:,}" for k, v in reasons.items())
    budget = run_.budget
    if budget is not None:
        where = (f"{run_.tiles} tiles of at most {budget.tile_size:,} {unit} on {run_.where}"
                 f" (memory budget {format_bytes(budget.total)})")
    else:
        where = f"read whole ({run_.where})"
    if run_.resumed:
        where += f"; {run_.resumed} tiles finished by an earlier run"
    print(f"{args.input}: {run_.points:,} {unit}; {where}")
    if run_.read:
        print(f"  halos: the tiles read {run_.read / max(run_.points, 1):.2f} {unit} a {unit[:-1] if unit == 'points' else 'vertex'}"
              f"; {run_.redone:,} redone on a wider region")
    print(f"{args.method} {rng.label}: {valid:,} of {run_.points:,} {unit} valid "
          f"({100 * valid / max(run_.points, 1):.1f} %)" + (f"; invalid: {invalid}" if invalid else ""))
    s = run_.seconds
    print(f"time: plan {s['plan']:.2f} s, tiles {s['tiles']:.2f} s, write {s['write']:.2f} s "
          f"(total {s['total']:.2f} s); wrote {args.output}")
