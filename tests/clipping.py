"""Exact area of one triangle inside a ball, through the estimators' own clipping kernel."""

import numpy as np

import curv
from curv.estimators._ball_clipping import face_in_ball_area
from curv.estimators._ball_mesh import ball_mesh


def triangle_in_ball_area(a, b, c, centre, radius) -> float:
    """Area of triangle (a, b, c) (3-vectors) inside the ball of ``radius`` around ``centre``."""
    mesh = curv.Mesh(np.array([a, b, c], float), [[0, 1, 2]])
    return face_in_ball_area(ball_mesh(mesh), 0, tuple(np.asarray(centre, float).tolist()), float(radius) ** 2)
