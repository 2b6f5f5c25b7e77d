"""The tool pointing down: its orientation at a yaw, and the yaws a tile's symmetry makes equal."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from planners.errors import InvalidTargetError
from spatial.angles import equivalent_yaws

Array = npt.NDArray[np.float64]


_DOWN = np.diag([1.0, -1.0, -1.0])
"""Tool-down orientation at yaw 0: site x along world x, site z along world -z."""


def tool_down_rotation(yaw: float) -> Array:
    """Rotation matrix (3, 3) of the tool pointing down with its x axis at ``yaw`` [rad]."""
    c, s = math.cos(yaw), math.sin(yaw)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return rz @ _DOWN


def symmetric_yaws(yaw: float, order: int) -> Array:
    """The ``order`` yaws equivalent to ``yaw`` under an ``order``-fold rotational symmetry.

    Args:
        yaw: One yaw [rad].
        order: Rotational symmetry order (1: no symmetry, 4: a square).

    Returns:
        Shape (order,) [rad], ``yaw + 2 pi k / order``.

    Raises:
        InvalidTargetError: Non-finite yaw or order below 1.
    """
    if not math.isfinite(yaw):
        raise InvalidTargetError(f"yaw must be finite, got {yaw!r}")
    if order < 1:
        raise InvalidTargetError(f"symmetry order must be >= 1, got {order!r}")
    return equivalent_yaws(yaw, order)


__all__ = ["symmetric_yaws", "tool_down_rotation"]
