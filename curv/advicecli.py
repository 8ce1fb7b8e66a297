"""``curv advise FILE`` and ``curv estimate --method auto``: the advisor on a file, its progress on
stderr, and its call written as the command's flags."""

from __future__ import annotations

from .core.errors import CurvError
from .progress import PhaseProgress

__all__ = ["apply_advice", "cmd_advise", "cli_arguments"]


def cli_arguments(kwargs: dict) -> str:
    """The ``curv estimate`` flags of a call's keyword arguments: ``--method jet --range 4 --degree 4``."""
    flags = {"method": "--method", "range": "--range", "radius": "--radius", "knn": "--knn", "degree": "--degree",
             "weights": "--weights", "width": "--width", "noise_model": "--noise-model", "normals": "--normals",
             "fit_range": "--fit-range", "features": "--features"}
    return " ".join(f"{flag} {kwargs[k]:g}" if isinstance(kwargs[k], float) else f"{flag} {kwargs[k]}"
                    for k, flag in flags.items() if k in kwargs)


def _load_for_advice(args, points: bool):
    from .io import load

    if points:
        return load(args.input)
    return load(args.input, merge_vertices=args.merge_vertices, remove_degenerate=args.remove_degenerate,
                orient=args.orient, remove_unreferenced=args.remove_unreferenced)


def _advise_with_progress(shape, *, check, quiet: bool, seed: int = 0):
    """``curv.iter_advise`` with a progress bar on stderr (Ctrl-C stops it: the check yields often)."""
    from .advice.advising import iter_advise

    with PhaseProgress("advise", mode="off" if quiet else None) as progress:
        progress.phase("advise")
        return progress.follow(iter_advise(shape, check=check, seed=seed))


def apply_advice(args, *, points: bool = False) -> None:
    """``--method auto``: put the advisor's whole call (method, range or radius or knn, options) into
    ``args``, announced on stdout."""
    given = [flag for flag, value in (("--range", args.range), ("--radius", args.radius), ("--knn", args.knn),
                                      ("--degree", args.degree), ("--weights", args.weights),
                                      ("--width", args.width), ("--fit-range", args.fit_range))
             if value is not None]
    if args.normals not in (None, "max"):
        given.append("--normals")
    if given:
        raise CurvError(f"--method auto chooses the range and the options too; drop {', '.join(given)}")
    shape = _load_for_advice(args, points)
    adv = _advise_with_progress(shape, check=None, quiet=args.quiet)
    kwargs = dict(adv.kwargs)
    if args.features is not None:  # the user's own crease angle wins
        kwargs.pop("features", None)
    print(f"auto: {adv.label} ({adv.why}); the same as {cli_arguments(kwargs)}", flush=True)
    args.method = kwargs["method"]
    args.range = None if kwargs.get("range") is None else str(kwargs["range"])
    args.radius, args.knn = kwargs.get("radius"), kwargs.get("knn")
    args.degree, args.weights, args.width = kwargs.get("degree"), kwargs.get("weights"), kwargs.get("width")
    if kwargs.get("normals") in ("fit", "pca"):
        args.normals, args.fit_range = kwargs["normals"], kwargs.get("fit_range")
    if "features" in kwargs:
        args.features = kwargs["features"]


def cmd_advise(args) -> int:
    import json

    from .io import is_point_file

    points = is_point_file(args.input)
    if points:
        given = [flag for flag in ("merge_vertices", "remove_degenerate", "orient", "remove_unreferenced")
                 if getattr(args, flag)]
        if given:
            raise CurvError(f"{args.input} is a point cloud; --{given[0].replace('_', '-')} needs a mesh's faces")
    shape = _load_for_advice(args, points)
    check = False if args.no_check else (True if args.check else None)
    adv = _advise_with_progress(shape, check=check, quiet=args.quiet or args.json, seed=args.seed)
    if args.json:
        print(json.dumps({"input": args.input, **adv.as_dict()}, indent=2, default=float))
        return 0
    from .advice.report import check_lines, feature_lines, ranking_lines

    print("\n".join(feature_lines(args.input, adv)))
    print(f"advice: {adv.why}")
    print(f"  call: {adv.call}")
    print(f"  or:   curv estimate {args.input} {cli_arguments(adv.kwargs)}")
    if adv.suggested_features is not None:
        print(f"  sharp edges: the call above estimates with features={adv.suggested_features:g}")
    print("\n".join(check_lines(adv) + ranking_lines(adv, args.top)))
    return 0
