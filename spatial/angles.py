"""Planar angles: wrapping, 2D rotation and the yaw error modulo a rotational symmetry.

The one home of these facts (all angles in radians, counter-clockwise seen from above). Two
conventions exist at the edge of the wrap, both kept from v0 under one function:
``include_pi=False`` wraps to [-pi, pi) (planners, envs, agents), ``include_pi=True`` to
(-pi, pi] (qshape's figures and matching).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]

TWO_PI = 2.0 * math.pi
"""A full turn [rad]."""


def wrap_angle(a: float | Array, *, include_pi: bool = False) -> float | Array:
    """Angle(s) wrapped to [-pi, pi) [rad], or to (-pi, pi] with ``include_pi``.

    A float (or 0-d array) comes back as a float, wrapped exactly (an angle already in range
    comes back unchanged); an array comes back as an array of the same shape.
    """
    if isinstance(a, float) or np.ndim(a) == 0:
        x = a if isinstance(a, float) else float(np.asarray(a))
        w = math.remainder(x, TWO_PI)
        if include_pi:
            return math.pi if w == -math.pi else w
        return -math.pi if w == math.pi else w
    return wrap_angles(a, include_pi=include_pi)


def wrap_angles(a: npt.ArrayLike, *, include_pi: bool = False) -> Array:
    """`wrap_angle` element-wise, always an array (any shape) [rad]."""
    w = np.remainder(np.asarray(a, dtype=np.float64) + math.pi, TWO_PI) - math.pi
    if include_pi:
        return np.asarray(np.where(w <= -math.pi, math.pi, w), dtype=np.float64)
    return w


def rotate_xy(xy: npt.ArrayLike, yaw: float) -> Array:
    """Planar vector(s) turned by ``yaw`` [rad] counter-clockwise; shape (2,) or (n, 2)."""
    c, s = math.cos(yaw), math.sin(yaw)
    v = np.asarray(xy, dtype=float)
    out: Array = v @ np.array([[c, s], [-s, c]])
    return out


def symmetry_period(symmetry: int) -> float:
    """The turn [rad] that maps a figure of ``symmetry``-fold rotational symmetry onto itself.

    ``2 pi / symmetry`` for a k-fold symmetry (k >= 1; 1: no symmetry, a full turn); 0.0 for a
    continuous one (``symmetry`` 0, a round tile: every turn maps it onto itself). Callers that
    search over one period for a round figure say so (``symmetry_period(s) or TWO_PI``).

    Raises:
        ValueError: A negative symmetry order.
    """
    if symmetry < 0:
        raise ValueError(f"symmetry order must be >= 0 (0: continuous), got {symmetry!r}")
    return 0.0 if symmetry == 0 else TWO_PI / symmetry


def equivalent_yaws(yaw: float, symmetry: int, continuous_steps: int = 1) -> Array:
    """The yaws a ``symmetry``-fold figure makes equivalent to ``yaw``, ``yaw`` first [rad].

    ``yaw + 2 pi j / k`` for j = 0 .. k-1 (not wrapped). A continuous figure (``symmetry`` 0)
    is listed at ``continuous_steps`` evenly spaced yaws.

    Returns:
        Shape (k,) [rad].

    Raises:
        ValueError: A negative symmetry order, or fewer than one yaw to list.
    """
    order = continuous_steps if symmetry == 0 else symmetry
    if symmetry < 0 or order < 1:
        raise ValueError(
            f"symmetry order must be >= 0 and the yaws listed >= 1, got {symmetry!r} and {order!r}"
        )
    out: Array = yaw + TWO_PI * np.arange(order) / order
    return out


def yaw_periods(symmetry: int | Array) -> Array:
    """Period [rad] of the yaw error of each symmetry order: 2 pi / k, 1 for continuous (k = 0).

    The array form of `symmetry_period`, with 1 in place of its 0 (a continuous shape's error
    is 0 whatever the period); `yaw_error` takes these precomputed
    for shapes whose orders do not change (a task's tiles)).
    """
    sym = np.asarray(symmetry)
    out: Array = np.where(sym > 0, TWO_PI / np.maximum(sym, 1), 1.0)
    return out


def yaw_error(
    yaw: float | Array,
    target: float | Array,
    symmetry: int | Array,
    period: Array | None = None,
) -> float | Array:
    """|yaw - target| modulo the shape's rotational symmetry [rad].

    Args:
        yaw: Measured yaw(s) [rad].
        target: Wanted yaw(s) [rad].
        symmetry: Rotational symmetry order(s): 1 none, k a k-fold symmetry, 0 continuous
            (error 0).
        period: ``yaw_periods(symmetry)`` if already known (the same values, computed once).

    Returns:
        The error in [0, pi / symmetry]; a float for scalar inputs, else an array.
    """
    sym = np.asarray(symmetry)
    if period is None:
        period = yaw_periods(sym)
    d = np.asarray(yaw, dtype=float) - np.asarray(target, dtype=float)
    err = np.where(sym > 0, np.abs((d + period / 2) % period - period / 2), 0.0)
    return float(err) if np.ndim(err) == 0 else np.asarray(err, dtype=np.float64)


__all__ = [
    "TWO_PI",
    "equivalent_yaws",
    "rotate_xy",
    "symmetry_period",
    "wrap_angle",
    "wrap_angles",
    "yaw_error",
    "yaw_periods",
]
