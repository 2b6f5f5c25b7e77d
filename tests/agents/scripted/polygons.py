"""Exact test polygons of the scripted placement's contract tests (mm), and how to pose them."""

from __future__ import annotations

import math

import numpy as np

from qshape import Figure
from spatial.angles import rotate_xy

RED = (0.8, 0.2, 0.2)
BLUE = (0.2, 0.3, 0.8)
SQUARE = np.array([[0, 0], [40, 0], [40, 40], [0, 40]], float)
ELL = np.array([[0, 0], [40, 0], [40, 14], [14, 14], [14, 40], [0, 40]], float)


def turned(points: np.ndarray, deg: float, at: tuple[float, float] = (250.0, -80.0)) -> np.ndarray:
    """``points`` turned by ``deg`` about their area centroid, the centroid moved to ``at``."""
    c = np.asarray(Figure.from_polygon(points).centroid)
    return rotate_xy(points - c, math.radians(deg)) + np.asarray(at)
