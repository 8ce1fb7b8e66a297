"""The rim of an open scan where the angular gap does not show it: one-sided supports.

The gap test (:func:`.normals.border_points`: the widest angle between a point's projected
neighbours at :data:`.normals.BORDER_RANGE`) finds the outermost points of a scan, but a point a
fraction of a spacing inside the rim sees the thin band of points between itself and the rim
spread over the empty side: on 8000 uniform random points of an open quadratic patch, half of the
points within half a spacing of the rim kept a gap below 135 degrees, and qs R2 gave a value at 31 %
of them (fitted over a one-sided support). What those points do show is where their support's mass
lies: the mean offset of a one-sided ball's points, in its tangent plane, is about 0.6 of their RMS
distance (a half disc), inside a scan about 0 (an even disc).

:func:`one_sided_points` measures that share over a ball :data:`RIM_SCALE` times the border test's
(more points: a void of uniform random sampling reads as one-sided far less often), at the points
whose gap is wide enough to be a rim's (:data:`RIM_GAP`, which keeps its cost to a few per cent of
the border test), and marks those above :data:`RIM_OFFSET`. Measured (docs/ADVISOR.md, "The
open-scan rim"): on that patch 4 % of the rim points stay valid and 97.8 % of the others, and no
closed test cloud gains a false border (uniform random spheres of 200,000 points: 7 and 25 with
the gap test alone, the same with this; a torus and a spheroid of 20,000 and a blue-noise sphere:
none).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import iter_chunks, jit_parallel, launch, prange, run_to_end, slice_bounds
from ..core.pointcloud import PointCloud
from ..geometry.neighbourhood import ball_support
from .one_pass import ball_walk_inputs

__all__ = ["one_sided_points", "rim_radii", "RIM_SCALE", "RIM_OFFSET", "RIM_GAP"]

RIM_SCALE = 2.0
"""The one-sidedness ball's radius over the border test's (:func:`.normals.border_radii`): R6."""

RIM_OFFSET = 0.5
"""A point is on the rim when its ball's mean tangent offset exceeds this share of the RMS
tangent distance of the ball's points (a half disc about 0.6, an even disc about 0)."""

RIM_GAP = math.pi / 3
"""Only points whose angular gap (at the border test's range) exceeds this (60 degrees) are
measured: 2.5 % of the points of a closed uniform random sphere (so the wider ball costs a few
per cent of the border test), every rim point but 1 % of those within half a spacing of an open
patch's rim."""


@jit_parallel
def _offset_kernel(centres, lo, hi, radius, support, normals, scratch, share):
    """``share[p]`` for ``centres[lo:hi]`` (:func:`offset_shares`); ``support`` and ``scratch`` as
    :func:`.one_pass.ball_walk_inputs` makes them."""
    adj_ptr, adj, x, y, z = support
    stamps, queues = scratch
    parts = stamps.shape[0]
    for t in prange(parts):
        queue = queues[t]
        stamp = stamps[t]
        start, stop = slice_bounds(lo, hi, t, parts)
        for i in range(start, stop):
            p = centres[i]
            nx, ny, nz = normals[p, 0], normals[p, 1], normals[p, 2]
            if not (math.isfinite(nx) and math.isfinite(ny) and math.isfinite(nz)):
                share[p] = math.nan
                continue
            count, queue = ball_support(p, radius[p] ** 2, adj_ptr, adj, x, y, z, stamp, queue)
            sx = sy = sz = ss = 0.0
            m = 0
            for j in range(count):
                q = queue[j]
                if q == p:
                    continue
                dx, dy, dz = x[q] - x[p], y[q] - y[p], z[q] - z[p]
                h = dx * nx + dy * ny + dz * nz  # the offset's part along the normal is left out
                tx, ty, tz = dx - h * nx, dy - h * ny, dz - h * nz
                sx += tx
                sy += ty
                sz += tz
                ss += tx * tx + ty * ty + tz * tz
                m += 1
            if m < 3 or not ss > 0.0:
                share[p] = math.nan
            else:
                share[p] = math.sqrt((sx * sx + sy * sy + sz * sz) / (m * ss))


def offset_shares(cloud: PointCloud, normals: np.ndarray, radii: np.ndarray, centres: np.ndarray):
    """(n,) float64, a generator: each centre's mean tangent offset over the RMS tangent distance of its
    ball's points (NaN under 3 points or without a normal; rows outside ``centres`` unset)."""
    centres, radius, support, scratch = ball_walk_inputs(cloud, radii, centres)
    share = np.full(cloud.n_points, np.nan)
    normals = np.ascontiguousarray(normals, dtype=np.float64)

    def run(lo: int, hi: int) -> None:
        launch(_offset_kernel, centres, lo, hi, radius, support, normals, scratch, share)

    yield from iter_chunks(centres.size, run)
    return share


def rim_radii(gap: np.ndarray, border_radii: np.ndarray) -> np.ndarray:
    """(n,) float64 radius of the ball the one-sided test reads at each point: :data:`RIM_SCALE`
    times the border test's radius where the angular gap exceeds :data:`RIM_GAP`, 0 where the test
    does not run (what a point's border flag reads, :mod:`curv.tiles.reach`, asks this)."""
    return np.where(np.asarray(gap) > RIM_GAP, RIM_SCALE * np.asarray(border_radii, float), 0.0)


def one_sided_points(cloud: PointCloud, normals: np.ndarray, gap: np.ndarray, border_radii: np.ndarray) -> np.ndarray:
    """(n,) bool: points whose support is one-sided: of the points whose angular gap exceeds
    :data:`RIM_GAP`, those whose ball of :data:`RIM_SCALE` times the border test's radius has a mean
    tangent offset above :data:`RIM_OFFSET` (in the tangent plane of ``normals``, the border test's
    PCA normals)."""
    out = np.zeros(cloud.n_points, bool)
    radii = rim_radii(gap, border_radii)
    centres = np.flatnonzero(radii > 0)
    if centres.size:
        share = run_to_end(offset_shares(cloud, normals, radii, centres))
        out[centres] = share[centres] > RIM_OFFSET
    return out
