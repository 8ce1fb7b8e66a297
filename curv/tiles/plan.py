"""Cutting an input into tiles sized by point count, and the regions (tile plus halo) they read.

The input's points are counted on a fine grid (:class:`Histogram`, a chunk at a time for a file);
:func:`plan_tiles` cuts its cells into boxes holding about ``tile_size`` points each: the box
with the most points is split across its longest side at the cell boundary that divides its
count in proportion to the number of tiles each side will hold (a k-d tree on counts), until
every box holds at most ``tile_size``. Each point belongs to the one tile whose cells hold it
(:meth:`TilePlan.tile_of`); a tile reads the points of its **region**, its box widened by a halo
on every side that has points beyond it (:class:`Region`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Histogram", "Region", "Tile", "TilePlan", "plan_tiles", "MAX_CELLS"]

MAX_CELLS = 1 << 21
"""Cells of the counting grid (2M: 16 MB of counts), spread over the bounding box in cubes."""


@dataclass
class Histogram:
    """Point counts on a uniform grid of cubic cells over known bounds.

    Attributes
    ----------
    lo : (3,) float64
        The input's least coordinates.
    cell : float
        Cell edge.
    dims : (3,) int64
        Cells along x, y, z.
    counts : (dims) int64
    """

    lo: np.ndarray
    cell: float
    dims: np.ndarray
    counts: np.ndarray

    @classmethod
    def over(cls, lo, hi, *, max_cells: int = MAX_CELLS) -> "Histogram":
        """An empty histogram over the box ``lo``..``hi`` with at most about ``max_cells`` cubic cells."""
        lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
        extent = np.maximum(hi - lo, 0.0)
        widest = float(extent.max())
        if not widest > 0:
            dims = np.ones(3, np.int64)
            return cls(lo, 1.0, dims, np.zeros(tuple(dims), np.int64))
        # the volume of the box, with thin sides counted as a tenth of the widest (a flat terrain)
        sides = np.maximum(extent, widest * 1e-3)
        cell = float(np.prod(sides) / max_cells) ** (1.0 / 3.0)
        cell = max(cell, widest / max_cells)
        dims = np.maximum(np.ceil(extent / cell).astype(np.int64), 1)
        while int(np.prod(dims)) > 4 * max_cells:  # rounding up many thin sides
            cell *= 1.25
            dims = np.maximum(np.ceil(extent / cell).astype(np.int64), 1)
        return cls(lo, cell, dims, np.zeros(tuple(dims), np.int64))

    def cells(self, points: np.ndarray) -> np.ndarray:
        """(m, 3) int64 cell of each point (clipped into the grid)."""
        c = np.floor((np.asarray(points, np.float64) - self.lo) / self.cell).astype(np.int64)
        np.clip(c, 0, self.dims - 1, out=c)
        return c

    def add(self, points: np.ndarray) -> None:
        """Count ``points`` (m, 3)."""
        c = self.cells(points)
        flat = np.ravel_multi_index((c[:, 0], c[:, 1], c[:, 2]), tuple(self.dims))
        self.counts += np.bincount(flat, minlength=self.counts.size).reshape(self.counts.shape)

    @property
    def total(self) -> int:
        return int(self.counts.sum())


@dataclass(frozen=True)
class Region:
    """A box of the input's space that a tile reads: every point inside belongs to it.

    Attributes
    ----------
    lo, hi : (3,) float64
        The box (closed).
    open_lo, open_hi : (3,) bool
        Sides at the input's bounds: no point lies beyond them, so they limit nothing.
    """

    lo: np.ndarray
    hi: np.ndarray
    open_lo: np.ndarray
    open_hi: np.ndarray

    @classmethod
    def around(cls, lo, hi, halo: float, bounds: tuple) -> "Region":
        """The box ``lo``..``hi`` widened by ``halo`` on every side, clipped to the input's ``bounds``
        ``(least, greatest)``: the sides that reach them are open."""
        least, greatest = (np.asarray(b, np.float64) for b in bounds)
        rlo = np.asarray(lo, np.float64) - halo
        rhi = np.asarray(hi, np.float64) + halo
        open_lo, open_hi = rlo <= least, rhi >= greatest
        return cls(np.where(open_lo, least, rlo), np.where(open_hi, greatest, rhi), open_lo, open_hi)

    def contains(self, points: np.ndarray) -> np.ndarray:
        """(m,) bool: points inside the box (its open sides unbounded)."""
        p = np.asarray(points, np.float64)
        inside = np.ones(p.shape[0], bool)
        for a in range(3):
            if not self.open_lo[a]:
                inside &= p[:, a] >= self.lo[a]
            if not self.open_hi[a]:
                inside &= p[:, a] <= self.hi[a]
        return inside

    def room(self, points: np.ndarray) -> np.ndarray:
        """(m,) distance from each point to the nearest closed side (inf when every side is open).

        A point outside the region lies farther than this from a point inside: a ball of at most
        this radius holds only points of the region. Shrunk by a relative 1e-12 of the coordinates
        so that the rounding of the subtraction never overstates it.
        """
        p = np.asarray(points, np.float64)
        room = np.full(p.shape[0], np.inf)
        for a in range(3):
            if not self.open_lo[a]:
                np.minimum(room, p[:, a] - self.lo[a], out=room)
            if not self.open_hi[a]:
                np.minimum(room, self.hi[a] - p[:, a], out=room)
        slack = 1e-12 * (np.abs(p).max(axis=1) + np.abs(room, where=np.isfinite(room), out=np.zeros_like(room)))
        return room - slack

    @property
    def everything(self) -> bool:
        return bool(self.open_lo.all() and self.open_hi.all())


@dataclass(frozen=True)
class Tile:
    """One tile: the cells ``cell_lo``..``cell_hi`` (exclusive) of the plan's histogram.

    Attributes
    ----------
    index : int
    cell_lo, cell_hi : (3,) int64
    count : int
        Points in its cells.
    lo, hi : (3,) float64
        Its box in the input's coordinates.
    """

    index: int
    cell_lo: tuple
    cell_hi: tuple
    count: int
    lo: tuple
    hi: tuple


@dataclass
class TilePlan:
    """The tiles of an input: their boxes and the lookup from a histogram cell to its tile.

    Attributes
    ----------
    histogram : Histogram
    tiles : list of Tile
    bounds : ((3,), (3,)) float64
        The input's least and greatest coordinates.
    lookup : (dims) int32
        The tile of every histogram cell.
    """

    histogram: Histogram
    tiles: list
    bounds: tuple
    lookup: np.ndarray = field(repr=False)

    def tile_of(self, points: np.ndarray) -> np.ndarray:
        """(m,) int32: the tile of each point."""
        c = self.histogram.cells(points)
        return self.lookup[c[:, 0], c[:, 1], c[:, 2]]

    def region(self, tile: Tile, halo: float) -> Region:
        """``tile``'s box widened by ``halo`` (:meth:`Region.around`)."""
        return Region.around(tile.lo, tile.hi, halo, self.bounds)

    def tiles_meeting(self, region: Region) -> list:
        """The tiles whose boxes meet ``region`` (whose points it may hold)."""
        out = []
        eps = 1e-9 * self.histogram.cell  # a point of a tile may lie a rounding outside its box
        for t in self.tiles:
            lo, hi = np.asarray(t.lo), np.asarray(t.hi)
            below = (~region.open_hi) & (lo - eps > region.hi)
            above = (~region.open_lo) & (hi + eps < region.lo)
            if not (below.any() or above.any()):
                out.append(t)
        return out


def _split(counts_box: np.ndarray, axis: int, fraction: float) -> int:
    """The cell boundary along ``axis`` (1 .. size-1) whose share of the count below is nearest ``fraction``."""
    along = counts_box.sum(axis=tuple(a for a in range(3) if a != axis))
    cum = np.cumsum(along)
    total = cum[-1]
    k = int(np.searchsorted(cum, fraction * total))  # first boundary reaching the share
    candidates = [c for c in (k, k + 1) if 1 <= c <= along.size - 1]
    if not candidates:
        return max(1, min(along.size - 1, k))
    return min(candidates, key=lambda c: abs(cum[c - 1] - fraction * total))


def plan_tiles(histogram: Histogram, tile_size: int, bounds: tuple) -> TilePlan:
    """Cut ``histogram``'s cells into tiles of at most about ``tile_size`` points (module notes).

    A box that is a single cell is not cut further, whatever it holds (the grid's resolution is
    the limit: a plan over :data:`MAX_CELLS` cells holds a few hundred points per tile at the least).
    """
    counts = histogram.counts
    dims = histogram.dims
    lookup = np.zeros(tuple(dims), np.int32)
    # the boxes to cut, as (cell_lo, cell_hi, count, tiles wanted)
    work = [(np.zeros(3, np.int64), dims.copy())]
    done = []
    while work:
        lo, hi = work.pop()
        box = counts[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]]
        total = int(box.sum())
        wanted = max(1, math.ceil(total / tile_size))
        # shrink to the cells that hold points, so that empty space is never split
        if total:
            nz = [np.flatnonzero(box.sum(axis=tuple(b for b in range(3) if b != a))) for a in range(3)]
            lo, hi = lo + np.array([z[0] for z in nz]), lo + np.array([z[-1] + 1 for z in nz])
            box = counts[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]]
        sizes = (hi - lo) * histogram.cell
        if wanted == 1 or np.all(hi - lo <= 1):
            done.append((lo, hi, total))
            continue
        splittable = np.flatnonzero(hi - lo > 1)
        axis = int(splittable[np.argmax(sizes[splittable])])
        below = wanted // 2
        at = _split(box, axis, below / wanted)
        mid = lo.copy()
        mid[axis] += at
        upper_lo = lo.copy()
        upper_lo[axis] = mid[axis]
        upper_hi = hi.copy()
        lower_hi = hi.copy()
        lower_hi[axis] = mid[axis]
        work.append((upper_lo, upper_hi))
        work.append((lo, lower_hi))
    tiles = []
    least, greatest = (np.asarray(b, np.float64) for b in bounds)
    # every cell belongs to a tile: empty cells (no points) go to the tile that was cut around them,
    # found by the nearest tile box along each axis (their points never exist, so any tile will do)
    lookup[...] = -1
    for i, (lo, hi, total) in enumerate(sorted(done, key=lambda d: tuple(d[0]))):
        lookup[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]] = i
        box_lo = histogram.lo + lo * histogram.cell
        box_hi = histogram.lo + hi * histogram.cell
        # the outermost cells reach the input's bounds exactly
        box_lo = np.where(lo == 0, least, box_lo)
        box_hi = np.where(hi == dims, greatest, box_hi)
        tiles.append(Tile(i, tuple(int(v) for v in lo), tuple(int(v) for v in hi), total,
                          tuple(float(v) for v in box_lo), tuple(float(v) for v in box_hi)))
    if (lookup < 0).any():
        _fill_empty(lookup)
    return TilePlan(histogram, tiles, (least, greatest), lookup)


def _fill_empty(lookup: np.ndarray) -> None:
    """Give every cell without a tile (an empty cell outside every tile's trimmed box) the tile of the
    nearest cell that has one (no point lies in such a cell; this only keeps the lookup total)."""
    from scipy import ndimage

    missing = lookup < 0
    _, nearest = ndimage.distance_transform_edt(missing, return_indices=True)
    lookup[missing] = lookup[tuple(ix[missing] for ix in nearest)]
