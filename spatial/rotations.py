"""Yaw (rotation about world z) to and from quaternions and rotation matrices.

The one home of these conversions. Quaternions are MuJoCo's (w, x, y, z); yaw in [rad],
counter-clockwise seen from above; for a body lying flat (z up) the yaw is its whole rotation.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


def yaw_from_quat(quat: npt.ArrayLike) -> Array:
    """Yaw [rad] of quaternions (w, x, y, z), shape (..., 4) -> (...)."""
    q = np.asarray(quat, dtype=np.float64)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.asarray(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y**2 + z**2)))


def yaw_from_matrix(rotation: npt.ArrayLike) -> float:
    """Yaw [rad] of a rotation's x axis in the world xy plane; ``rotation`` shape (3, 3)."""
    r = np.asarray(rotation)
    return math.atan2(r[1, 0], r[0, 0])


def quat_from_yaw(yaw: npt.ArrayLike) -> Array:
    """Quaternions (w, x, y, z) of rotations about z by ``yaw`` [rad], shape (..., 4)."""
    a = np.asarray(yaw, dtype=float)
    q = np.zeros((*a.shape, 4))
    q[..., 0] = np.cos(a / 2)
    q[..., 3] = np.sin(a / 2)
    return q


__all__ = ["quat_from_yaw", "yaw_from_matrix", "yaw_from_quat"]
