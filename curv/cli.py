"""Command line: ``curv list``, ``curv estimate``, ``curv advise``, ``curv study``.

Errors in the input end the program with a one-line message on stderr and a non-zero status,
never a traceback.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import traceback
import time
import warnings
from pathlib import Path

import numpy as np

from .core.errors import CurvError, CurvWarning
from .advicecli import apply_advice, cmd_advise
from .progress import PhaseProgress

__all__ = ["main"]

EXIT_INPUT = 2
EXIT_INTERNAL = 3
EXIT_INTERRUPTED = 130


def _cmd_list(args) -> int:
    from .estimators import ESTIMATORS
    from .core.ranges import range_label, takes_any_range

    print(f"{'name':<6} {'ranges':<12} {'polygons':<9} {'points':<7} {'borders':<8} title / reference")
    print(f"{'':<6} (k>=1, r: any real range Rk from that k on, or a fixed radius r)")
    for spec in ESTIMATORS.values():
        ranges = (f"k>={min(spec.ranges):g}, r" if takes_any_range(spec)
                  else ",".join(range_label(k) for k in spec.ranges))
        print(f"{spec.name:<6} {ranges:<12} {'no' if spec.triangles_only else 'yes':<9} "
              f"{'yes' if spec.takes_points else 'no':<7} {'invalid' if spec.closed_ring else 'fitted':<8} {spec.title}")
        print(f"{'':<45} {spec.reference}")
    return 0


def _stats_line(name: str, values: np.ndarray) -> str:
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return f"  {name:<10} (no valid values)"
    lo, med, hi = np.percentile(finite, [0, 50, 100])
    return f"  {name:<10} min {lo: .6g}   median {med: .6g}   max {hi: .6g}"


def _check_output(path: str) -> None:
    """Fail before the long work when the output file cannot be written."""
    out = Path(path)
    folder = out.parent if str(out.parent) else Path(".")
    if out.is_dir():
        raise CurvOutputError(f"{out}: is a directory; give a file name for the output")
    if not folder.is_dir():
        raise CurvOutputError(f"{out}: cannot write: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise CurvOutputError(f"{out}: cannot write: no permission to write in {folder}")


def _check_colours(args) -> None:
    """Refuse an unknown colour map or reversed limits before any work (one line)."""
    from .colors import check_cmap, check_limits

    try:
        if args.cmap is not None:
            check_cmap(args.cmap)
        if args.clim:
            check_limits(*args.clim)
    except ValueError as exc:
        raise CurvUsageError(str(exc)) from None


def _check_memory(args, n_vertices: int, n_faces: int, method: str, rng, *, points: bool = False,
                  tiles: bool = False) -> None:
    from .memory import check_memory

    if not args.memory_check:
        return
    est = check_memory(n_vertices, n_faces, method, points=points)
    if not est.fits:
        size = f"{n_vertices:,} points" if points else f"{n_vertices:,} vertices and {n_faces:,} faces"
        raise CurvMemoryError(
            f"{args.input}: {method} {rng.label} on {size} "
            f"{est.describe()}; refusing to start ({_tiles_hint(args, tiles)}"
            f"use a smaller range, another estimator, a bigger machine, or --no-memory-check)")


def _tiles_hint(args, tiles: bool) -> str:
    """How to run an estimate too large for the memory free now on tiles (whether it tiles by itself
    depends on --memory and the machine's total memory only: curv.tiles.budget)."""
    if tiles:
        return "give -o OUT to run it on tiles, or "
    return "run it on tiles with --tile-size N or a --memory below what is free, or " if args.output else ""


def _cmd_estimate(args) -> int:
    # progress on stderr (curv.progress), closed before an error's line
    with PhaseProgress(mode="off" if args.quiet else None) as progress:
        return _estimate(args, progress)


def _estimate(args, progress: PhaseProgress) -> int:
    from .api import iter_estimate
    from .estimators import DEFAULT_ESTIMATORS, get_spec
    from .io import check_output_suffix, is_point_file, load, peek_counts, save_result
    from .pointcli import check_mesh_options, check_point_options
    from .formats.pointio import peek_points
    from .core.quantities import EXPORTED
    from .core.ranges import resolve
    from .core.validity import describe_reasons

    points = is_point_file(args.input)
    if args.method is None:
        args.method = DEFAULT_ESTIMATORS["points" if points else "mesh"]
    if args.method == "auto":
        apply_advice(args, points=points)
    spec = get_spec(args.method)
    rng = resolve(spec, args.range, args.radius, args.knn)
    if points:
        check_point_options(args, spec)
    else:
        check_mesh_options(args)
        args.normals = args.normals or "max"
    _check_colours(args)
    from .tiles import command as tiled

    if args.output:
        try:
            if not tiled.las_output(args.output):  # a LAS/LAZ output keeps the input's records
                check_output_suffix(args.output)
        except ValueError as exc:
            raise CurvOutputError(str(exc)) from None
        tiled.check_las_output(args)
        _check_output(args.output)
    counts = peek_counts(args.input)  # a PLY header, mesh or points
    if counts is None and points:
        n_points = peek_points(args.input)
        counts = None if n_points is None else (n_points, 0)
    if tiled.wants_tiles(args, counts, points=points):  # asked, or too large for memory whole
        if not args.output and args.tile_size is None and args.scheduler is None:
            # too large whole and no file for tiles to write: say how much it needs, and how to run it
            _check_memory(args, *counts, spec.name, rng, points=points, tiles=True)
        return tiled.run(args, points=points, progress=progress)
    if counts is not None:  # refuse before reading a file that will not fit
        _check_memory(args, *counts, spec.name, rng, points=points)
    progress.label = f"{spec.name} {rng.label}"
    progress.phase("load")
    t0 = time.perf_counter()
    if points:
        mesh = load(args.input)
    else:
        mesh = load(args.input, merge_vertices=args.merge_vertices, remove_degenerate=args.remove_degenerate,
                    orient=args.orient, remove_unreferenced=args.remove_unreferenced)
    t_load = time.perf_counter() - t0
    if counts is None:
        _check_memory(args, mesh.n_vertices, getattr(mesh, "n_faces", 0), spec.name, rng, points=points)
    if points:
        from .pointcli import estimate_keywords

        options = estimate_keywords(args, mesh)
    else:
        options = {"normals": "fit"} if args.normals == "fit" else {"normal_weighting": args.normals}
        if args.features is not None:
            from .core.features import check_angle

            options["features"] = check_angle(args.features)
        options["smooth"] = args.smooth
    if args.fit_range is not None:
        if args.normals not in ("fit", "pca"):
            raise CurvUsageError("--fit-range is the range of the fitted normals: give it with --normals fit"
                                 + (" or pca" if points else ""))
        options["fit_range"] = args.fit_range
    if args.degree is not None:
        options["degree"] = args.degree
    if args.weights is not None:
        options["weights"] = args.weights
    if args.width is not None:
        options["width"] = args.width
    if args.noise_model is not None:
        options["noise_model"] = args.noise_model
    if args.standard_errors:
        options["standard_errors"] = True
    region = _region_vertices(args, mesh)
    if rng.knn is not None:
        options["knn"] = rng.knn
    gen = iter_estimate(mesh, spec.name, rng.k, radius=rng.radius, vertices=region, **options)
    t1 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CurvWarning)  # the summary says it (res.info["warnings"])
        res = progress.follow(gen)
    t_est = time.perf_counter() - t1
    t_write = None
    if args.output:
        progress.phase("write")
        t2 = time.perf_counter()
        try:
            if tiled.las_output(args.output):
                from .formats.laswrite import save_las

                save_las(args.output, args.input, res, groups=tuple(args.las_extra))
            else:
                save_result(args.output, mesh, res, quantity=args.quantity, cmap=args.cmap,
                            clim=tuple(args.clim) if args.clim else None)
        except CurvError:
            raise
        except OSError as exc:
            raise CurvOutputError(f"{args.output}: cannot write: {exc.strerror or exc}") from None
        t_write = time.perf_counter() - t2
    progress.close()
    t3 = time.perf_counter()
    if points:
        from .pointcli import report_lines

        for line in report_lines(args, mesh, res):
            print(line)
    else:
        _print_mesh_report(args, mesh)
    t_report = time.perf_counter() - t3
    reasons = describe_reasons(res.reason)
    n_isolated = 0 if points else int(mesh.isolated_vertices.sum())
    if n_isolated and reasons.get("DEGENERATE", 0) >= n_isolated:  # unreferenced vertices: say so
        reasons["DEGENERATE"] -= n_isolated
        reasons = {**{k: v for k, v in reasons.items() if v}, "ISOLATED (no face)": n_isolated}
    invalid = ", ".join(f"{k.lower().replace('_', ' ')} {v}" for k, v in reasons.items() if k != "OK")
    if region is not None:
        print(f"region: {region.size} vertices estimated, the other {mesh.n_vertices - region.size} not computed")
    unit = "points" if points else "vertices"
    print(f"{res.method} {res.info['range_label']}: {res.valid.sum()} of {mesh.n_vertices} {unit} valid "
          f"({100 * res.valid_fraction:.1f} %)" + (f"; invalid: {invalid}" if invalid else ""))
    for note in res.info.get("warnings", ()):
        print(f"warning: {note}")
    for name in EXPORTED:
        print(_stats_line(name, res.quantity(name)))
    written = f", write {t_write:.2f} s; wrote {args.output}" if args.output else ""
    print(f"time: load {t_load:.2f} s, estimate {t_est:.2f} s, report {t_report:.2f} s{written}")
    return 0


def _print_mesh_report(args, mesh) -> None:
    rep = mesh.report()
    # a hint below gives the flag; the report's line would suggest it again as the library's keyword
    lines = dataclasses.replace(rep, suggested_features=None).lines()
    print(f"{args.input}: {lines[0]}")
    for line in lines[1:]:
        print(f"  {line}")
    for line in mesh.info.get("repairs", []):
        print(f"  repair: {line}")
    for line in _hints(args, rep):
        print(f"  hint: {line}")


def _region_vertices(args, mesh):
    """``--vertices FILE`` or ``--region X Y Z R`` as vertex indices, or None for the whole mesh."""
    from .geometry.region import read_vertex_file, vertices_in_ball

    if args.vertices is not None and args.region is not None:
        raise CurvError("give either --vertices or --region, not both")
    if args.vertices is not None:
        return read_vertex_file(args.vertices, mesh.n_vertices)
    if args.region is not None:
        *centre, radius = args.region
        return vertices_in_ball(mesh, centre, radius)
    return None


def _hints(args, rep) -> list[str]:
    """Repairs that would likely help, for the defects the report shows."""
    out = []
    if rep.duplicate_vertices and not args.merge_vertices:
        out.append(f"{rep.duplicate_vertices} vertices repeat another's position: try --merge-vertices")
    if rep.degenerate_faces and not args.remove_degenerate:
        out.append("degenerate faces found: try --remove-degenerate")
    if rep.inconsistent_edges and not args.orient:
        out.append("faces of opposite orientation meet (their vertices are invalid): try --orient")
    if rep.suggested_features is not None and args.features is None:
        out.append(f"many sharp edges: if they are creases, try --features {rep.suggested_features:g}")
    return out


class CurvUsageError(CurvError, ValueError):
    """A command-line value that is wrong in itself (a colour map, limits)."""


class CurvOutputError(CurvError, OSError):
    """The output file cannot be written."""


class CurvMemoryError(CurvError, MemoryError):
    """The estimate would not fit in the available memory."""


def build_parser() -> argparse.ArgumentParser:
    from .uncertainty import NOISE_MODELS
    from .estimators.jet import WEIGHTS as JET_WEIGHTS
    from .estimators.jet import WIDTHS as JET_WIDTHS
    from .estimators.registry import DEFAULT_ESTIMATORS
    from .io import OUTPUT_FORMATS
    from .formats.pointio import POINT_SUFFIXES
    from .core.quantities import QUANTITIES
    from .core.quantities import describe as describe_quantities

    parser = argparse.ArgumentParser(prog="curv", description="Curvature estimation on surface meshes and point clouds.")
    sub = parser.add_subparsers(dest="command", required=True)

    p_list = sub.add_parser("list", help="list the estimators and their ranges")
    p_list.set_defaults(func=_cmd_list)

    p_est = sub.add_parser("estimate", help="estimate curvature on a mesh or point-cloud file")
    p_est.add_argument("input", help="mesh file (PLY, OBJ, OFF, STL, glTF, ...) or point cloud (PLY without "
                       "faces, " + ", ".join(POINT_SUFFIXES) + ")")
    p_est.add_argument("--method", "-m",
                       help=f"estimator name (see `curv list`), or auto (ask `curv advise`); default "
                            f"{DEFAULT_ESTIMATORS['mesh']} on a mesh, {DEFAULT_ESTIMATORS['points']} on a point cloud")
    p_est.add_argument("--range", "-r", help="range k of Rk: 2, R2 or any real k such as 2.5 (at least the "
                       "estimator's smallest); default R2, or the estimator's one range (meyer R1)")
    p_est.add_argument("--radius", type=float, help="instead of --range: the same ball radius in mesh units at "
                       "every vertex")
    p_est.add_argument("--knn", type=int, metavar="K", help="point clouds, instead of --range: the K nearest points")
    p_est.add_argument("--output", "-o", help="write the result: " + "; ".join(
        f"{suffix} {what}" for suffix, what in OUTPUT_FORMATS.items())
        + "; .las/.laz (a LAS/LAZ input) its records with the curvature as extra bytes")
    p_est.add_argument("--quantity", default="mean", choices=list(QUANTITIES),
                       help="what the output colours show; default mean (" + "; ".join(describe_quantities()) + ")")
    p_est.add_argument("--cmap", help="matplotlib colour map; default coolwarm (signed) or viridis")
    p_est.add_argument("--clim", nargs=2, type=float, metavar=("LO", "HI"), help="colour limits")
    p_est.add_argument("--normals", choices=["max", "area", "angle", "fit", "pca"],
                       help="vertex normals: Max, area or angle weighted face normals, or a local jet fit "
                            "(R2); default max (the paper's protocol). Point clouds: the file's normals, "
                            "else fit (jet fits, R2); pca: local plane fits")
    p_est.add_argument("--orient-normals", nargs="+", metavar="up|top|outward|X Y Z",
                       help="point clouds whose normals are estimated: up (nz >= 0 at every point; default for "
                            "LAS/LAZ), top (propagated from each part's top turned up; default otherwise), "
                            "outward (closed objects), or towards a viewpoint X Y Z (a scanner's position)")
    p_est.add_argument("--fit-range", help="range k of the fitted normals (with --normals fit); "
                       "default 2")
    p_est.add_argument("--degree", type=int, choices=[2, 3, 4], help="jet degree (estimator jet); default 2")
    p_est.add_argument("--standard-errors", action=argparse.BooleanOptionalAction, default=False,
                       help="also the standard errors of k1 and k2 of the least-squares fits (nc, qs, an, mru, jet), "
                            "written as k1_se, k2_se: the same curvatures, at about a quarter more time (an: half); "
                            "default off")
    p_est.add_argument("--noise-model", choices=list(NOISE_MODELS),
                       help="standard errors of an and mru: sampled (default: the errors the neighbours' normals "
                            "take from the noisy positions, measured at 2000 vertices and applied to all), "
                            "independent equations, or normals (that model at every vertex, 3-5x slower)")
    p_est.add_argument("--weights", choices=list(JET_WEIGHTS),
                       help="jet fit weights: uniform (default) or smooth, (1 - d²/r²)^4 falling to 0 at the ball's "
                            "edge (estimator jet)")
    p_est.add_argument("--width", choices=list(JET_WIDTHS),
                       help="jet ball width: fixed (default: the range's ball) or adaptive, a choice per point "
                            "among narrower balls and a smooth degree-2 fit by intersecting their confidence "
                            "intervals (estimator jet; for wide ranges on noisy scans, about 4x the cost)")
    p_est.add_argument("--smooth", choices=["mesh", "values"], help="smooth the mesh before or the values after")
    p_est.add_argument("--merge-vertices", action="store_true", help="merge vertices at identical positions")
    p_est.add_argument("--remove-degenerate", action="store_true", help="drop zero-area / repeated-index faces")
    p_est.add_argument("--orient", action="store_true", help="make face orientation consistent")
    p_est.add_argument("--remove-unreferenced", action="store_true", help="drop vertices no face uses")
    p_est.add_argument("--features", metavar="DEGREES",
                       help="edges whose dihedral angle exceeds this are creases: supports stop there and "
                            "crease vertices are marked FEATURE")
    p_est.add_argument("--vertices", metavar="FILE", help="estimate only at these vertices (one index a line)")
    p_est.add_argument("--region", nargs=4, type=float, metavar=("X", "Y", "Z", "R"),
                       help="estimate only at the vertices within R of the point (X, Y, Z)")
    p_est.add_argument("--quiet", "-q", action="store_true",
                       help="no progress (else a bar per phase on a terminal, a line every few seconds elsewhere)")
    p_est.add_argument("--no-memory-check", dest="memory_check", action="store_false",
                       help="estimate even when the predicted peak memory exceeds the available memory")
    from .tiles.command import add_arguments as add_tile_arguments

    add_tile_arguments(p_est)
    p_est.set_defaults(func=_cmd_estimate)

    p_adv = sub.add_parser("advise", help="which estimator, range and options for this mesh or point cloud "
                           "(the study's table, checked on noisy copies of the input's smooth twin)")
    p_adv.add_argument("input", help="mesh file (PLY, OBJ, OFF, STL, glTF, ...) or point cloud")
    p_adv.add_argument("--json", action="store_true", help="features, ranking, check and advice as JSON")
    p_adv.add_argument("--top", type=int, default=12, help="variants of the ranking shown; default 12")
    checking = p_adv.add_mutually_exclusive_group()
    checking.add_argument("--no-check", action="store_true", help="the table's ranking alone (a mesh; a point "
                          "cloud: the prior order), no self-check")
    checking.add_argument("--check", action="store_true", help="check even an input above the size the check "
                          "is skipped at")
    p_adv.add_argument("--seed", type=int, default=0, help="seed of the check's centres and noise; default 0")
    p_adv.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    for flag, text in (("--merge-vertices", "merge vertices at identical positions"),
                       ("--remove-degenerate", "drop zero-area / repeated-index faces"),
                       ("--orient", "make face orientation consistent"),
                       ("--remove-unreferenced", "drop vertices no face uses")):
        p_adv.add_argument(flag, action="store_true", help=text)
    p_adv.set_defaults(func=cmd_advise)

    try:
        from .study.cli import add_study_parser
    except ImportError:  # the study needs the optional matplotlib/dask extras
        pass
    else:
        add_study_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except CurvError as exc:
        print(f"curv: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except MemoryError:
        print("curv: error: out of memory (try a smaller range or a smaller mesh)", file=sys.stderr)
        return EXIT_INPUT
    except OSError as exc:
        if isinstance(exc, BrokenPipeError):  # `curv list | head`: the reader has what it wanted
            sys.stderr.close()
            return 0
        print(f"curv: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("curv: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # a bug in curv: still one line for the user, the details on request
        if os.environ.get("CURV_DEBUG"):
            traceback.print_exc()
        text = " ".join(str(exc).split())[:300]
        print(f"curv: internal error: {type(exc).__name__}: {text} (a bug; set CURV_DEBUG=1 for details)",
              file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
