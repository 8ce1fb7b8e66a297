"""Whether two trees of curv give the same results: every estimator on meshes, point clouds, creased
meshes and regions, with and without standard errors, several ranges in one call, the csm/icc
table, point normals, nearest neighbours, supports and the mesh report.

A restructuring (modules split, kernels' arguments bundled) must not change a bit. Run it once with
each tree on the path and compare::

    PYTHONPATH=<tree before> python benchmarks/same_results.py save before.npz
    PYTHONPATH=<tree after>  python benchmarks/same_results.py save after.npz
    python benchmarks/same_results.py compare before.npz after.npz

``compare`` prints how many arrays are bit-identical and, for the others, the largest difference
(absolute, and relative to the array's largest magnitude); it exits 1 when any differs.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def _quad_mesh(side: int = 24):
    import curv

    u, v = np.meshgrid(np.linspace(-1, 1, side), np.linspace(-1, 1, side))
    vertices = np.column_stack([u.ravel(), v.ravel(), 0.3 * (u.ravel() ** 2 - v.ravel() ** 2)])
    i = np.arange(side - 1)
    a = (i[:, None] * side + i[None, :]).ravel()
    faces = np.column_stack([a, a + 1, a + side + 1, a + side])
    return curv.Mesh(vertices, faces)


def _inputs():
    """``{name: (input, estimate keywords)}``: the cases every estimator runs on."""
    import curv
    from curv.surfaces import make_surface

    torus = make_surface("torus", n_vertices=1500, noise=0.05, seed=1).mesh
    patch = make_surface("quadratic", n_vertices=817, seed=2).mesh
    box = make_surface("box", seed=3).mesh
    rng = np.random.default_rng(4)
    sphere = make_surface("sphere", n_vertices=3000, seed=5).mesh.vertices
    cloud = curv.PointCloud(sphere + rng.normal(scale=0.003, size=sphere.shape))
    open_cloud = curv.PointCloud(make_surface("quadratic", n_vertices=1141, noise=0.05, seed=6).mesh.vertices)
    region = np.sort(rng.choice(torus.n_vertices, 200, replace=False))
    return {
        "torus": (torus, {}),
        "patch": (patch, {}),
        "quads": (_quad_mesh(), {}),
        "box-creases": (box, {"features": 40.0}),
        "torus-region": (torus, {"vertices": region}),
        "cloud": (cloud, {}),
        "open-cloud": (open_cloud, {}),
        "cloud-region": (cloud, {"vertices": np.arange(0, cloud.n_vertices, 7)}),
    }


_FIELDS = ("k1", "k2", "d1", "d2", "normals", "valid", "reason", "k1_se", "k2_se")


def _put(out: dict, key: str, res) -> None:
    for field in _FIELDS:
        value = getattr(res, field, None)
        if value is not None:
            out[f"{key}:{field}"] = np.asarray(value)


def collect() -> dict:
    """Every array of the cases, keyed ``case:method:range[:errors]:field``."""
    import curv
    from curv.core.knn import nearest_neighbours, symmetric_graph
    from curv.core.ranges import Range, ball_radii
    from curv.estimators import ESTIMATORS, refusal
    from curv.geometry.neighbourhood import support_sizes, supports
    from curv.point_normals import point_normals

    out: dict[str, np.ndarray] = {}
    for case, (shape, keywords) in _inputs().items():
        for name, spec in ESTIMATORS.items():
            if refusal(spec, shape) is not None:
                continue
            if "features" in keywords and not spec.has_support:
                continue
            ranges = spec.ranges[:3]
            for k in ranges:
                errors = (False, True) if spec.skips_errors and k == ranges[0] else (False,)
                for se in errors:
                    res = curv.estimate(shape, name, k, standard_errors=se, **keywords)
                    _put(out, f"{case}:{name}:R{k}{':se' if se else ''}", res)
            if spec.takes_levels and len(ranges) > 1:
                for i, res in enumerate(curv.estimate_ranges(shape, name, ranges, **keywords)):
                    _put(out, f"{case}:{name}:levels{ranges[i]}", res)
        if not isinstance(shape, curv.PointCloud) and shape.is_triangular:
            table = curv.estimate_table(shape, ("csm", "icc"), (2, 3), **keywords)
            for name, results in table.items():
                for i, res in enumerate(results):
                    _put(out, f"{case}:table:{name}:{i}", res)
        if isinstance(shape, curv.PointCloud) and "vertices" not in keywords:
            indices, distances = nearest_neighbours(shape.vertices, 10)
            out[f"{case}:knn:indices"], out[f"{case}:knn:distances"] = indices, distances
            out[f"{case}:graph:indptr"], out[f"{case}:graph:indices"] = symmetric_graph(indices)
            out[f"{case}:normals"] = np.asarray(point_normals(shape).normals)
        if "vertices" not in keywords:
            radii = ball_radii(shape, Range(k=2.0), uses_normals=False)
            out[f"{case}:supports:indptr"], out[f"{case}:supports:indices"] = supports(shape, radii)
            out[f"{case}:support_sizes"] = support_sizes(shape, radii)[0]
        if not isinstance(shape, curv.PointCloud) and "vertices" not in keywords:
            out[f"{case}:report"] = np.array(repr(shape.report()))
    # kNN where the first ring of cells does not settle it: clumps, a sparse spread, far outliers
    rng = np.random.default_rng(7)
    points = np.concatenate([rng.normal(scale=0.01, size=(2000, 3)), rng.uniform(-1, 1, size=(300, 3)),
                             rng.uniform(-50, 50, size=(5, 3))])
    for k in (1, 10, 40):
        indices, distances = nearest_neighbours(points, k)
        out[f"outliers:knn{k}:indices"], out[f"outliers:knn{k}:distances"] = indices, distances
    return out


def compare(before: str, after: str) -> int:
    a, b = np.load(before), np.load(after)
    keys = sorted(set(a.files) | set(b.files))
    missing = [k for k in keys if k not in a.files or k not in b.files]
    same, worst = 0, []
    for key in keys:
        if key in missing:
            continue
        x, y = a[key], b[key]
        if x.shape == y.shape and x.dtype == y.dtype and np.array_equal(x, y, equal_nan=x.dtype.kind == "f"):
            same += 1
            continue
        if x.shape != y.shape or x.dtype.kind != "f":
            worst.append((np.inf, np.inf, key))
            continue
        both = np.isfinite(x) & np.isfinite(y)
        if not np.array_equal(np.isfinite(x), np.isfinite(y)):
            worst.append((np.inf, np.inf, key + " (NaN at other places)"))
            continue
        diff = float(np.abs(x[both] - y[both]).max())
        scale = float(np.abs(x[both]).max()) or 1.0
        worst.append((diff / scale, diff, key))
    print(f"{same} of {len(keys) - len(missing)} arrays bit-identical; {len(missing)} in one file only")
    for key in missing[:20]:
        print(f"  only in one: {key}")
    for rel, diff, key in sorted(worst, reverse=True)[:20]:
        print(f"  differs: {key}: largest {diff:.3g} ({rel:.3g} relative)")
    return 0 if not worst and not missing else 1


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    save = sub.add_parser("save", help="compute every case and save the arrays (.npz)")
    save.add_argument("path")
    both = sub.add_parser("compare", help="compare two saved files")
    both.add_argument("before")
    both.add_argument("after")
    args = parser.parse_args(argv)
    if args.command == "save":
        arrays = collect()
        np.savez_compressed(args.path, **arrays)
        print(f"{len(arrays)} arrays saved to {args.path}")
        return 0
    return compare(args.before, args.after)


if __name__ == "__main__":
    sys.exit(main())
