"""What ``curv estimate`` does differently for a point-cloud file: its checks, options and report.

The rest of the command (range, colours, output, region, progress, the written file) is the
mesh command's own; :mod:`curv.cli` asks :func:`curv.formats.pointio.is_point_file` once and calls here.
"""

from __future__ import annotations

import numpy as np

from .core.errors import CurvError

__all__ = ["check_point_options", "check_mesh_options", "estimate_keywords", "report_lines", "MESH_ONLY"]

MESH_ONLY = {"merge_vertices": "--merge-vertices", "remove_degenerate": "--remove-degenerate",
             "orient": "--orient", "remove_unreferenced": "--remove-unreferenced",
             "features": "--features", "smooth": "--smooth"}
"""Options that need faces or edges, by their argparse names."""

_MESH_NORMALS = ("max", "area", "angle")


def _orientation(words):
    """``--orient-normals``: ``"up"``, ``"top"``, ``"outward"``, a viewpoint (3,) from three numbers,
    or None (the cloud's default, :func:`curv.point_normals.default_orientation`)."""
    if words is None:
        return None
    if len(words) == 1 and words[0] in ("up", "top", "outward"):
        return words[0]
    try:
        point = np.array([float(w) for w in words], dtype=np.float64)
    except ValueError:
        point = np.empty(0)
    if point.shape != (3,) or not np.isfinite(point).all():
        raise CurvError(f"--orient-normals takes up, top, outward or a viewpoint X Y Z; got {' '.join(words)}")
    return point


def check_point_options(args, spec) -> None:
    """Refuse, before any work, what cannot run on a point cloud (one line each).

    The estimator's refusal is the registry's (:func:`curv.estimators.refusal`), asked about a
    stand-in cloud because the file is not read yet.
    """
    from .estimators import refusal
    from .core.pointcloud import PointCloud

    why_not = refusal(spec, PointCloud(np.zeros((1, 3))))
    if why_not is not None:
        raise CurvError(why_not)
    given = [flag for name, flag in MESH_ONLY.items() if getattr(args, name, None) not in (None, False)]
    if given:
        flags = given[0] if len(given) == 1 else f"{', '.join(given[:-1])} and {given[-1]}"
        verb = "needs" if len(given) == 1 else "need"
        raise CurvError(f"{args.input} is a point cloud; {flags} {verb} a mesh's faces")
    if args.normals in _MESH_NORMALS:
        raise CurvError(f"--normals {args.normals} weights face normals; on a point cloud use fit (jet) or pca "
                        f"(default: the file's normals, else jet fits)")
    args.orient_normals_given = args.orient_normals is not None
    args.orient_normals = _orientation(args.orient_normals)


def check_mesh_options(args) -> None:
    """Refuse the point-cloud options on a mesh (one line)."""
    if args.knn is not None:
        raise CurvError("--knn is for point clouds; on a mesh give --range or --radius")
    if args.orient_normals is not None:
        raise CurvError("--orient-normals is for point clouds; a mesh's normals follow its faces")
    if args.normals == "pca":
        raise CurvError("--normals pca is for point clouds; on a mesh use max, area, angle or fit")


def estimate_keywords(args, cloud) -> dict:
    """The normals keywords of :func:`curv.iter_estimate` for a loaded point cloud."""
    if args.normals is None and cloud.normals is not None and args.orient_normals_given:
        raise CurvError(f"{args.input}: the normals come from the file; add --normals pca or fit to estimate "
                        f"and orient them")
    return {"normals": args.normals, "orient": args.orient_normals}


def report_lines(args, cloud, res) -> list[str]:
    """The point cloud's part of the summary: points, spacing, normals, coincident and border points."""
    from .core.ranges import describe_spacing
    from .point_normals import describe_orientation

    spaced = describe_spacing(cloud)
    label = res.info.get("normals", "")
    if label == "file":
        normals = "normals from the file"
    else:
        normals = f"normals estimated ({label}, oriented {describe_orientation(res.info['orientation'])})"
    info = res.info
    lines = [f"{args.input}: {cloud.n_points:,} points; {spaced}; {normals}",
             f"  coincident points {info.get('coincident_points', 0):,} (repeats of an earlier point: degenerate)",
             f"  border points {info.get('border_points', 0):,} (on the rim of an open scan)"]
    if info.get("ambiguous_normals"):
        lines.append(f"  ambiguous normals {info['ambiguous_normals']:,} (orientation undecided: no estimate there)")
    if info.get("one_sided_normals"):
        lines.append(f"  one-sided normals {info['one_sided_normals']:,} (fitted across an empty side: no estimate there)")
    lines += _grid_lines(args, cloud, info)
    return lines


def _grid_lines(args, cloud, info) -> list[str]:
    """What the coordinates' grid did (:data:`curv.point_normals.MIN_SUPPORT_STEPS`): the normals
    widened to it, the estimates over narrower supports marked, and the range that clears it."""
    from .estimators import get_spec
    from .point_normals import MIN_SUPPORT_STEPS, range_above_grid

    widened, marked = info.get("widened_normals", 0), info.get("quantised_supports", 0)
    if not (widened or marked):
        return []
    step, floor = info["coordinate_step"], info["support_floor"]
    lines = [f"  coordinates stored on a grid of step {step:.4g}: a fit narrower than {floor:.4g} "
             f"({MIN_SUPPORT_STEPS} steps) sees its stairs, not the surface"]
    if widened:
        lines.append(f"  normals fitted over at least {floor:.4g} at {widened:,} points")
    if marked:
        k = range_above_grid(cloud, uses_normals=get_spec(args.method).uses_normals)
        lines.append(f"  {marked:,} estimates over narrower supports are SINGULAR (no estimate there): "
                     f"try -r {k} or more")
    return lines
