"""Planar angles: wrapping, 2D rotation and yaw error modulo a rotational symmetry.

The one home of these conversions for planners, envs and agents (all angles in radians,
counter-clockwise seen from above, world x, y).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


def wrap_angle(a: float | Array) -> float | Array:
    """Angle(s) wrapped to [-pi, pi) [rad]; a float for a float, an array for an array.

    A float is wrapped exactly (an angle already in range comes back unchanged).
    """
    if isinstance(a, float) or np.ndim(a) == 0:
        x = a if isinstance(a, float) else float(np.asarray(a))
        w = math.remainder(x, 2.0 * math.pi)
        return -math.pi if w == math.pi else w
    return (np.asarray(a, dtype=float) + math.pi) % (2.0 * math.pi) - math.pi


def rotate_xy(xy: npt.ArrayLike, yaw: float) -> Array:
    """Planar vector(s) turned by ``yaw`` [rad] counter-clockwise; shape (2,) or (n, 2)."""
    c, s = math.cos(yaw), math.sin(yaw)
    v = np.asarray(xy, dtype=float)
    out: Array = v @ np.array([[c, s], [-s, c]])
    return out


def yaw_error(yaw: float | Array, target: float | Array, symmetry: int | Array) -> float | Array:
    """|yaw - target| modulo the shape's rotational symmetry [rad].

    Args:
        yaw: Measured yaw(s) [rad].
        target: Wanted yaw(s) [rad].
        symmetry: Rotational symmetry order(s): 1 none, k a k-fold symmetry, 0 continuous
            (error 0).

    Returns:
        The error in [0, pi / symmetry]; a float for scalar inputs.
    """
    sym = np.asarray(symmetry)
    period = np.where(sym > 0, 2.0 * math.pi / np.maximum(sym, 1), 1.0)
    d = np.asarray(yaw, dtype=float) - np.asarray(target, dtype=float)
    err = np.where(sym > 0, np.abs((d + period / 2) % period - period / 2), 0.0)
    return float(err) if np.ndim(err) == 0 else err


__all__ = ["rotate_xy", "wrap_angle", "yaw_error"]
