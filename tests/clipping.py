"""Exact area of one triangle inside a ball, through the estimators' own clipping kernel."""

import numpy as np

import curv
from curv.estimators._ball_clipping import face_frames, face_geometry, face_in_ball_area


def triangle_in_ball_area(a, b, c, centre, radius) -> float:
    """Area of triangle (a, b, c) (3-vectors) inside the ball of ``radius`` around ``centre``."""
    mesh = curv.Mesh(np.array([a, b, c], float), [[0, 1, 2]])
    normal, area = face_geometry(mesh)
    frames = face_frames(mesh, normal)
    ox, oy, oz = np.asarray(centre, float) - np.asarray(a, float)
    return face_in_ball_area(frames, 0, ox, oy, oz, float(radius) ** 2, area[0])
