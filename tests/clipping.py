"""Exact area of one triangle inside a ball, through the estimators' own clipping kernel."""

import numpy as np

import curv
from curv.estimators._ball_clipping import face_in_ball_area
from curv.geometry.neighbourhood import coordinate_columns


def triangle_in_ball_area(a, b, c, centre, radius) -> float:
    """Area of triangle (a, b, c) (3-vectors) inside the ball of ``radius`` around ``centre``."""
    mesh = curv.Mesh(np.array([a, b, c], float), [[0, 1, 2]])
    x, y, z = coordinate_columns(mesh)
    px, py, pz = np.asarray(centre, float)
    return face_in_ball_area(mesh.triangles, 0, x, y, z, mesh.face_vector_areas, mesh.face_areas, px, py, pz,
                             float(radius) ** 2)
