"""Closed-form duration of the time-optimal jerk-limited move between two configurations at rest.

One axis moving a distance ``d`` from rest to rest under velocity, acceleration and jerk limits
``v``, ``a``, ``j`` speeds up to a peak velocity ``vp``, maybe cruises, and slows down
symmetrically. Speeding up from rest to ``vp`` takes

* ``2 sqrt(vp / j)`` when ``vp <= a^2 / j`` (jerk up, jerk down: the acceleration limit is not
  reached),
* ``vp / a + a / j`` otherwise (jerk up, hold ``a``, jerk down),

and covers ``vp`` times half that time (the velocity curve is point-symmetric about its
midpoint). Without a cruise the whole move covers ``d = vp * t_up(vp)``: solved for ``vp`` in
each case (a cube root, a quadratic); with ``vp = v`` the remainder is cruised at ``v``.

Several axes: every axis can also take any longer duration from rest to rest (stretch its
profile), so the synchronised time-optimal duration (ruckig's, with all axes arriving together)
is the largest single-axis duration. Boundary states that are not at rest can make some longer
durations infeasible for an axis; those moves are ruckig's (`planners.trajectory.plan_segment`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from planners.config import JointLimits
from planners.errors import LimitError

Array = npt.NDArray[np.float64]


def axis_duration(distance: float, v: float, a: float, j: float) -> float:
    """Time-optimal rest-to-rest duration [s] of one axis.

    Args:
        distance: Distance to travel, either sign [rad or m].
        v: Velocity limit (> 0) [unit/s].
        a: Acceleration limit (> 0) [unit/s^2].
        j: Jerk limit (> 0) [unit/s^3].
    """
    d = abs(distance)
    if d == 0.0:
        return 0.0
    a_over_j = a / j
    # Speeding up to v, then its distance if there were no cruise.
    t_up = 2.0 * math.sqrt(v / j) if v * j <= a * a else v / a + a_over_j
    if d >= v * t_up:
        return 2.0 * t_up + (d - v * t_up) / v
    if d <= 2.0 * a * a_over_j * a_over_j:  # peak velocity at most a^2 / j: jerk phases only
        return 4.0 * math.cbrt(0.5 * d / j)
    # d = vp^2 / a + vp a / j, solved for vp in its cancellation-free form.
    vp = 2.0 * d / (a_over_j + math.sqrt(a_over_j * a_over_j + 4.0 * d / a))
    return 2.0 * (vp / a + a_over_j)


def rest_to_rest_duration(
    q0: Array | Sequence[float], q1: Array | Sequence[float], limits: JointLimits
) -> float:
    """Synchronised time-optimal duration [s] from rest at ``q0`` to rest at ``q1``.

    Equals ruckig's duration for the same move (to its numerical precision, ~1e-12 s).

    Args:
        q0: Start configuration, shape (n,) [rad].
        q1: Target configuration, shape (n,) [rad] (already unwrapped).
        limits: Velocity, acceleration and jerk limits of the n axes.

    Raises:
        LimitError: Shapes differ from the limits' number of axes.
    """
    start = q0.tolist() if isinstance(q0, np.ndarray) else q0
    target = q1.tolist() if isinstance(q1, np.ndarray) else q1
    vmax, amax, jmax = limits.max_velocity, limits.max_acceleration, limits.max_jerk
    n = len(vmax)
    if len(start) != n or len(target) != n:
        raise LimitError(
            f"rest-to-rest move needs {n} start and target angles, got {len(start)} and "
            f"{len(target)}"
        )
    longest = 0.0
    for i in range(n):
        longest = max(longest, axis_duration(target[i] - start[i], vmax[i], amax[i], jmax[i]))
    return longest


__all__ = ["axis_duration", "rest_to_rest_duration"]
