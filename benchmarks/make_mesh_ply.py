"""Make a binary PLY triangle (or quad) mesh of any size, a row of vertices at a time: the large-mesh benchmark's input.

    PYTHONPATH=. python benchmarks/make_mesh_ply.py 100000000 terrain100M.ply
    PYTHONPATH=. python benchmarks/make_mesh_ply.py 5000000 quads5M.ply --quads

A terrain height field (hills, a valley, small bumps like the output of a photogrammetry run) on
a jittered grid of about the asked number of vertices (float32 coordinates), triangulated along
alternating diagonals: about two triangles a vertex, an open surface with a border; with
``--quads`` one quad a grid cell (about one a vertex), as a remesher writes. The vertices are
numbered row by row, as meshers write them. Memory stays at a few rows.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

ROWS_A_BLOCK = 64


def _height(x, y):
    return (12.0 * np.sin(x / 380.0) * np.cos(y / 290.0) + 5.0 * np.sin((x + 2 * y) / 140.0)
            - 18.0 * np.exp(-((x - y) / 600.0) ** 2) + 0.4 * np.sin(x / 3.0) * np.sin(y / 4.0))


def make(n_vertices: int, path: Path, *, seed: int = 3, spacing: float = 0.5, quads: bool = False) -> dict:
    rng = np.random.default_rng(seed)
    side = max(2, int(math.sqrt(n_vertices)))
    nx = ny = side
    n = nx * ny
    m = (1 if quads else 2) * (nx - 1) * (ny - 1)
    header = (f"ply\nformat binary_little_endian 1.0\ncomment curvlab benchmark terrain {nx} x {ny}\n"
              f"element vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
              f"element face {m}\nproperty list uchar int vertex_indices\nend_header\n").encode("ascii")
    t0 = time.perf_counter()
    with open(path, "wb") as fh:
        fh.write(header)
        for r0 in range(0, ny, ROWS_A_BLOCK):
            rows = np.arange(r0, min(ny, r0 + ROWS_A_BLOCK))
            x = (np.arange(nx)[None, :] + rng.uniform(-0.2, 0.2, (rows.size, nx))) * spacing
            y = (rows[:, None] + rng.uniform(-0.2, 0.2, (rows.size, nx))) * spacing
            block = np.empty((rows.size, nx, 3), "<f4")
            block[..., 0], block[..., 1], block[..., 2] = x, y, _height(x, y)
            fh.write(block.tobytes())
        record = np.dtype([("count", "u1"), ("v", "<i4", (4 if quads else 3,))])
        for r0 in range(0, ny - 1, ROWS_A_BLOCK):
            rows = np.arange(r0, min(ny - 1, r0 + ROWS_A_BLOCK))
            i, j = np.meshgrid(rows, np.arange(nx - 1), indexing="ij")
            a = i * nx + j
            b, c, d = a + 1, a + nx + 1, a + nx
            if quads:
                out = np.empty(a.size, record)
                out["count"] = 4
                out["v"] = np.stack([a, b, c, d], -1).reshape(-1, 4)
                fh.write(out.tobytes())
                continue
            flip = ((i + j) % 2).astype(bool)
            t1 = np.stack([a, b, np.where(flip, d, c)], -1)
            t2 = np.stack([np.where(flip, b, a), c, d], -1)
            faces = np.stack([t1, t2], axis=2).reshape(-1, 3)
            out = np.empty(faces.shape[0], record)
            out["count"] = 3
            out["v"] = faces
            fh.write(out.tobytes())
    return {"vertices": n, "faces": m, "seconds": time.perf_counter() - t0}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("vertices", type=int)
    parser.add_argument("output", type=Path)
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--quads", action="store_true", help="one quad a grid cell instead of two triangles")
    args = parser.parse_args(argv)
    info = make(args.vertices, args.output, seed=args.seed, quads=args.quads)
    kind = "quads" if args.quads else "triangles"
    print(f"{args.output}: {info['vertices']:,} vertices, {info['faces']:,} {kind}, written in {info['seconds']:.1f} s")


if __name__ == "__main__":
    main()
