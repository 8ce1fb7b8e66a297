"""Triangulations of the creased solids: stacked rings for solids of revolution, a lattice for a box.

Both build one closed, outward-oriented manifold whose creases are rows of shared vertices: the
faces on either side of a crease use the same vertices, so no vertex is duplicated.
"""

from __future__ import annotations

import numpy as np

__all__ = ["revolution_mesh", "box_lattice_mesh"]


def revolution_mesh(rho, z, counts) -> tuple[np.ndarray, np.ndarray]:
    """Rings around the z axis, joined in order from the first to the last.

    Ring ``k`` has ``counts[k]`` vertices at radius ``rho[k]`` and height ``z[k]``, evenly spaced
    in angle and turned by half a step on every other ring (equal rings then join in near-equilateral
    triangles). A ring of one vertex is a pole on the axis. Walking the profile ``(rho, z)`` from
    the first ring to the last with the solid on the left (e.g. from the bottom pole up to the top
    pole, outside the axis) gives outward faces.

    Parameters
    ----------
    rho, z : (r,) array_like
        Radius and height of each ring; ``rho = 0`` where ``counts = 1``.
    counts : (r,) array_like of int
        Vertices per ring: 1 (a pole) or >= 3.

    Returns
    -------
    vertices : (sum(counts), 3) float64
        Ring by ring, in angle order.
    faces : (f, 3) int64
        Counter-clockwise seen from outside.
    """
    rho, z = np.asarray(rho, dtype=np.float64), np.asarray(z, dtype=np.float64)
    counts = np.asarray(counts, dtype=np.int64)
    if np.any((counts != 1) & (counts < 3)):
        raise ValueError(f"a ring needs 1 (a pole) or >= 3 vertices, got {counts.tolist()}")
    starts = np.concatenate([[0], np.cumsum(counts)])
    ring = np.repeat(np.arange(counts.size), counts)
    step = 2.0 * np.pi / counts[ring]
    angle = step * (np.arange(ring.size) - starts[ring] + 0.5 * (ring % 2))
    vertices = np.stack([rho[ring] * np.cos(angle), rho[ring] * np.sin(angle), z[ring]], axis=1)
    strips = [
        _ring_strip(np.arange(starts[k], starts[k + 1]), angle[starts[k]:starts[k + 1]],
                    np.arange(starts[k + 1], starts[k + 2]), angle[starts[k + 1]:starts[k + 2]])
        for k in range(counts.size - 1)
    ]
    return vertices, np.concatenate(strips)


def _ring_strip(a, a_angle, b, b_angle) -> np.ndarray:
    """Triangles between ring ``a`` and the next ring ``b`` (indices and ascending angles).

    A sweep once around the axis over the edges of both rings, in the order of their midpoints'
    angles: an edge ``a_i -> a_i+1`` gives ``(a_i, a_i+1, b_j)`` and an edge ``b_j -> b_j+1`` gives
    ``(a_i, b_j+1, b_j)``, with ``a_i, b_j`` the current vertices of the sweep; so each triangle's
    apex is the vertex of the other ring about over its base's middle. Both kinds are outward when
    ``b`` follows ``a`` on the profile; at a pole one kind collapses and is dropped.
    """
    two_pi = 2.0 * np.pi
    a_rel = a_angle - a_angle[0]                        # the sweep starts at a[0]
    a_mid = a_rel + 0.5 * np.diff(np.concatenate([a_rel, [two_pi]]))
    b_rel = np.mod(b_angle - a_angle[0], two_pi)
    b_order = np.argsort(b_rel, kind="stable")
    b, b_rel = b[b_order], b_rel[b_order]
    b_mid = np.mod(b_rel + 0.5 * np.mod(np.roll(b_rel, -1) - b_rel, two_pi), two_pi)
    # start ring b at the edge whose midpoint comes first after a[0]
    first = np.argmin(b_mid)
    b, b_mid = np.roll(b, -first), np.roll(b_mid, -first)
    moves_a = np.concatenate([np.ones(a.size, bool), np.zeros(b.size, bool)])
    order = np.lexsort((~moves_a, np.concatenate([a_mid, b_mid])))  # ties: move a first
    moves_a = moves_a[order]
    i = np.cumsum(moves_a) - moves_a                   # a-edges before this one
    j = np.cumsum(~moves_a) - ~moves_a
    ai, ai1 = a[i % a.size], a[(i + 1) % a.size]
    bj, bj1 = b[j % b.size], b[(j + 1) % b.size]
    tri = np.where(moves_a[:, None], np.stack([ai, ai1, bj], 1), np.stack([ai, bj1, bj], 1))
    keep = np.where(moves_a, a.size > 1, b.size > 1)
    return tri[keep]


def box_lattice_mesh(cells) -> tuple[np.ndarray, np.ndarray]:
    """The surface of the lattice box ``[0, nx] x [0, ny] x [0, nz]``, each unit square in two triangles.

    Vertices are named by their integer coordinates, so the faces of two sides meeting at an edge
    share its vertices exactly.

    Parameters
    ----------
    cells : (3,) sequence of int
        Cells ``nx, ny, nz`` along each axis, >= 1.

    Returns
    -------
    lattice : (n, 3) int64
        Integer coordinates of the vertices (on the box's surface).
    faces : (2 * 2 (nx ny + ny nz + nz nx), 3) int64
        Counter-clockwise seen from outside. Every square is cut along the same diagonal of its
        side's grid, so inner vertices have valence 6.
    """
    cells = np.asarray(cells, dtype=np.int64)
    if cells.shape != (3,) or np.any(cells < 1):
        raise ValueError(f"a box needs >= 1 cell along each axis, got {cells.tolist()}")
    points, triangles, offset = [], [], 0
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3  # e_u x e_v = e_axis
        iu, iv = np.meshgrid(np.arange(cells[u] + 1), np.arange(cells[v] + 1), indexing="ij")
        cu, cv = np.meshgrid(np.arange(cells[u]), np.arange(cells[v]), indexing="ij")
        cu, cv = cu.ravel(), cv.ravel()
        rows = cells[v] + 1
        p00, p10 = cu * rows + cv, (cu + 1) * rows + cv
        quads = np.concatenate([np.stack([p00, p10, p10 + 1], 1), np.stack([p00, p10 + 1, p00 + 1], 1)])
        for side in (0, 1):
            grid = np.zeros((iu.size, 3), dtype=np.int64)
            grid[:, u], grid[:, v], grid[:, axis] = iu.ravel(), iv.ravel(), side * cells[axis]
            points.append(grid)
            # counter-clockwise in (u, v) faces +axis: right on the far side, reversed on the near one
            triangles.append(offset + (quads if side else quads[:, ::-1]))
            offset += grid.shape[0]
    lattice, index = np.unique(np.concatenate(points), axis=0, return_inverse=True)
    return lattice, index.reshape(-1)[np.concatenate(triangles)]
