"""What the viewer's Estimate in region costs on a large mesh (run by hand).

    .venv/bin/python benchmarks/bench_region.py 10000000

For balls of 10 and 30 mean edges around one vertex of a torus: finding the region, the estimate
(mru R2, without and with a 30 degree feature angle, twice: the first estimate with features computes
the mesh's dihedral angles, later ones reuse them from the mesh), and recolouring the whole mesh with
the rest grey.
"""

from __future__ import annotations

import sys
import time

import curv
from curv.surfaces import SURFACES

from app.model.colors import colormap, map_colours
from app.model.region import REST_COLOUR, ball_region, outside_region


def main(n_vertices: int) -> None:
    t = time.perf_counter()
    mesh = SURFACES["torus"]().mesh(n_vertices=n_vertices).mesh
    print(f"torus of {mesh.n_vertices} vertices in {time.perf_counter() - t:.1f} s")
    t = time.perf_counter()
    curv.estimate(mesh, method="mru", range=2, vertices=[0])
    print(f"connectivity, normals and kernels (once per mesh) {time.perf_counter() - t:.1f} s")
    for edges in (10, 30):
        t = time.perf_counter()
        region = ball_region(mesh, 12345, edges * float(mesh.mean_edge_length))
        found = time.perf_counter() - t
        for features in (None, 30.0, 30.0):
            t = time.perf_counter()
            part = curv.estimate(mesh, method="mru", range=2, vertices=region.vertices, features=features)
            took = time.perf_counter() - t
            t = time.perf_counter()
            rgba = map_colours(part.mean, (-1.0, 1.0), colormap("coolwarm"))
            rgba[outside_region(part, region)] = REST_COLOUR
            painted = time.perf_counter() - t
            print(f"{region.size} vertices (ball of {edges} edges), features={features}: region {found:.2f} s, "
                  f"estimate {took:.2f} s, colours {painted:.2f} s")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000)
