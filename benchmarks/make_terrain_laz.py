"""Make an aerial-LiDAR-like LAZ (or LAS) of any size, a flight line at a time: the large-scan benchmark's input.

    PYTHONPATH=. python benchmarks/make_terrain_laz.py 100000000 terrain100M.laz

Rolling terrain (a few sines, a valley) at about 10 points a square metre over a square of the
size the count asks, with buildings (flat and gabled roofs, class 6) and vegetation (rounded
crowns of trees and shrubs, class 5, with a second return on the ground below some of them),
ground class 2. Every point has an intensity (by class, with noise), a return number, a scan
angle, a point source (its flight line) and a GPS time increasing along its line. Coordinates are
kept in centimetres (LAS scale 0.01) in a projected system (UTM-like offsets), as real tiles are.
The points are written flight line by flight line (strips along y, each swept in x), so the file
is in acquisition order, not sorted in space: a tile of the benchmark gathers its points from the
whole file. Deterministic for a seed; memory stays at one flight line (about 1M points).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

DENSITY = 10.0
"""Points a square metre (ground and objects)."""

LINE_POINTS = 1_000_000
"""Points a flight line (a strip of the square)."""


def _terrain(x, y):
    """Ground height (m): rolling hills and a valley along a diagonal."""
    return (12.0 * np.sin(x / 380.0) * np.cos(y / 290.0) + 5.0 * np.sin((x + 2 * y) / 140.0)
            - 18.0 * np.exp(-((x - y) / 600.0) ** 2) + 0.8 * np.sin(x / 23.0) * np.sin(y / 31.0))


def _buildings(size: float, rng: np.random.Generator):
    """Rectangular buildings on a jittered grid of blocks: centre, half sides, height, gabled."""
    spacing = 60.0
    cx, cy = np.meshgrid(np.arange(spacing / 2, size, spacing), np.arange(spacing / 2, size, spacing))
    cx, cy = cx.ravel(), cy.ravel()
    keep = rng.random(cx.size) < 0.45
    n = int(keep.sum())
    return {"cx": cx[keep] + rng.uniform(-10, 10, n), "cy": cy[keep] + rng.uniform(-10, 10, n),
            "hx": rng.uniform(5, 16, n), "hy": rng.uniform(5, 14, n), "h": rng.uniform(4, 25, n),
            "gable": rng.random(n) < 0.5, "cell": spacing}


def _trees(size: float, rng: np.random.Generator):
    """Tree and shrub crowns: centre, radius, height of the crown's top."""
    count = int(size * size / 150.0)
    return {"x": rng.uniform(0, size, count), "y": rng.uniform(0, size, count), "r": rng.uniform(1.0, 5.0, count),
            "h": rng.uniform(2.0, 22.0, count), "cell": 12.0}


def _index(xs, ys, cell):
    """Objects bucketed by grid cell, for the lookups of a line's points."""
    keys = (np.floor(xs / cell).astype(np.int64) << 32) + np.floor(ys / cell).astype(np.int64)
    order = np.argsort(keys, kind="stable")
    return keys[order], order


def _lookup(x, y, index, cell, reach):
    """For each point, candidate objects in its cell and the neighbours that can reach it: (point, object) pairs."""
    keys, order = index
    pts, objs = [], []
    rings = int(math.ceil(reach / cell))
    for dx in range(-rings, rings + 1):
        for dy in range(-rings, rings + 1):
            k = ((np.floor(x / cell).astype(np.int64) + dx) << 32) + (np.floor(y / cell).astype(np.int64) + dy)
            lo, hi = np.searchsorted(keys, k, "left"), np.searchsorted(keys, k, "right")
            counts = hi - lo
            if not counts.any():
                continue
            p = np.repeat(np.arange(x.size), counts)
            starts = np.repeat(lo, counts)
            offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
            pts.append(p)
            objs.append(order[starts + offsets])
    if not pts:
        return np.empty(0, np.int64), np.empty(0, np.int64)
    return np.concatenate(pts), np.concatenate(objs)


def make(n_points: int, path: Path, *, seed: int = 7, chunk: int = LINE_POINTS) -> dict:
    import laspy

    rng = np.random.default_rng(seed)
    size = math.sqrt(n_points / DENSITY)
    houses = _buildings(size, rng)
    trees = _trees(size, rng)
    house_index = _index(houses["cx"], houses["cy"], houses["cell"])
    tree_index = _index(trees["x"], trees["y"], trees["cell"])
    header = laspy.LasHeader(point_format=1, version="1.2")
    header.scales = np.array([0.01, 0.01, 0.01])
    header.offsets = np.array([500000.0, 4000000.0, 0.0])
    header.system_identifier = "curvlab benchmark"
    header.generating_software = "make_terrain_laz.py"
    lines = max(1, int(math.ceil(n_points / chunk)))
    width = size / lines
    written = 0
    t0 = time.perf_counter()
    with laspy.open(path, mode="w", header=header, do_compress=path.suffix.lower() == ".laz") as writer:
        for line in range(lines):
            m = min(chunk, n_points - written)
            if m <= 0:
                break
            x = rng.uniform(0, size, m)
            y = rng.uniform(line * width, (line + 1) * width, m)
            order = np.lexsort((y, np.floor(x / 0.5)))  # swept across the line, scan by scan
            x, y = x[order], y[order]
            z = _terrain(x, y)
            cls = np.full(m, 2, np.uint8)
            returns = np.ones(m, np.uint8)
            n_returns = np.ones(m, np.uint8)
            # buildings: roofs over their footprint
            p, o = _lookup(x, y, house_index, houses["cell"], 20.0)
            inside = (np.abs(x[p] - houses["cx"][o]) <= houses["hx"][o]) & (np.abs(y[p] - houses["cy"][o]) <= houses["hy"][o])
            p, o = p[inside], o[inside]
            ridge = np.where(houses["gable"][o], 0.35 * (houses["hy"][o] - np.abs(y[p] - houses["cy"][o])), 0.0)
            z[p] = _terrain(houses["cx"][o], houses["cy"][o]) + houses["h"][o] + ridge
            cls[p] = 6
            # vegetation: rounded crowns; a quarter of their points fall through to the ground (2 returns)
            p, o = _lookup(x, y, tree_index, trees["cell"], 5.0)
            d2 = (x[p] - trees["x"][o]) ** 2 + (y[p] - trees["y"][o]) ** 2
            inside = (d2 <= trees["r"][o] ** 2) & (cls[p] != 6)
            p, o, d2 = p[inside], o[inside], d2[inside]
            top = _terrain(trees["x"][o], trees["y"][o]) + trees["h"][o] - 0.6 * d2 / trees["r"][o]
            first = rng.random(p.size) < 0.75
            z[p[first]] = np.maximum(z[p[first]], top[first] + rng.normal(0, 0.15, int(first.sum())))
            cls[p[first]] = 5
            n_returns[p] = 2
            returns[p[~first]] = 2
            z += rng.normal(0, 0.02, m)  # a 2 cm ranging noise
            points = laspy.ScaleAwarePointRecord.zeros(m, header=header)
            points.x, points.y, points.z = x, y, z
            points.classification = cls
            points.return_number = returns
            points.number_of_returns = n_returns
            base = np.where(cls == 2, 40.0, np.where(cls == 6, 90.0, 25.0))
            points.intensity = np.clip(base + rng.normal(0, 8, m), 0, 65535).astype(np.uint16)
            points.scan_angle_rank = np.clip((x - x.mean()) / max(size, 1) * 40, -90, 90).astype(np.int8)
            points.point_source_id = np.full(m, line + 1, np.uint16)
            points.gps_time = 1e5 + line * 3600.0 + np.arange(m) * 1e-5  # 100 kHz along the line
            writer.write_points(points)
            written += m
    return {"points": written, "side_m": size, "buildings": int(houses["cx"].size), "crowns": int(trees["x"].size),
            "seconds": time.perf_counter() - t0}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("points", type=int)
    parser.add_argument("output", type=Path)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args(argv)
    info = make(args.points, args.output, seed=args.seed)
    print(f"{args.output}: {info['points']:,} points over {info['side_m']:.0f} m x {info['side_m']:.0f} m, "
          f"{info['buildings']:,} buildings, {info['crowns']:,} crowns, written in {info['seconds']:.1f} s")


if __name__ == "__main__":
    main()
