"""Joint vectors and states.

Validated (6,) vectors, joint ranges, and targets unwrapped on wrapping joints to the turn
nearest the start.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from planners.config import N_JOINTS, JointLimits
from planners.errors import InvalidTargetError, LimitError

_TWO_PI = 2.0 * math.pi

Array = npt.NDArray[np.float64]


def as_joint_vector(value: npt.ArrayLike, name: str) -> Array:
    """A finite joint vector of shape (6,) as float64.

    Raises:
        InvalidTargetError: Wrong shape or a non-finite entry (the message names ``name``).
    """
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (N_JOINTS,):
        raise InvalidTargetError(f"{name} must have shape ({N_JOINTS},), got {arr.shape}")
    if not all(map(math.isfinite, arr.tolist())):
        raise InvalidTargetError(f"{name} must be finite, got {arr.tolist()}")
    return arr


def check_in_range(
    q: Array | list[float], limits: JointLimits, name: str, margin: float = 0.0
) -> None:
    """Raise `LimitError` if configuration ``q`` [rad] leaves the joint ranges (plus ``margin``).

    Raises:
        LimitError: Names the joint, its value and its range in degrees.
    """
    values = q.tolist() if isinstance(q, np.ndarray) else q
    bad = [
        i
        for i, (v, lo, hi) in enumerate(zip(values, limits.lower, limits.upper, strict=True))
        if v < lo - margin or v > hi + margin
    ]
    if bad:
        i = bad[0]
        raise LimitError(
            f"{name}: joint {i + 1} at {math.degrees(values[i]):.3f} deg is outside its range "
            f"[{math.degrees(limits.lower[i]):.1f}, {math.degrees(limits.upper[i]):.1f}] deg"
        )


def unwrap_target(
    q_from: npt.ArrayLike,
    q_to: npt.ArrayLike,
    limits: JointLimits,
    joints: Sequence[int] = (3, 5),
) -> Array:
    """Replace each wrapping joint's target by its equivalent angle nearest to ``q_from``.

    Args:
        q_from: Start configuration, shape (6,) [rad].
        q_to: Target configuration, shape (6,) [rad].
        limits: Joint ranges.
        joints: Indices of joints whose angle may change by multiples of 2 pi.

    Returns:
        The target with ``q_to[j] + 2 pi k`` nearest to ``q_from[j]`` inside the range, shape (6,).

    Raises:
        InvalidTargetError: Non-finite input.
        LimitError: No equivalent angle of a wrapping joint lies inside its range.
    """
    a = as_joint_vector(q_from, "q_from").tolist()
    b = as_joint_vector(q_to, "q_to").tolist()
    return np.array(unwrap_values(a, b, limits, joints))


def unwrap_values(
    q_from: list[float], q_to: list[float], limits: JointLimits, joints: Sequence[int] = (3, 5)
) -> list[float]:
    """`unwrap_target` on validated plain lists of 6 angles [rad]: returns a new list.

    Raises:
        LimitError: No equivalent angle of a wrapping joint lies inside its range.
    """
    a, b = q_from, list(q_to)
    for j in joints:
        lo, hi = limits.lower[j], limits.upper[j]
        k_lo = math.ceil((lo - b[j]) / _TWO_PI)
        k_hi = math.floor((hi - b[j]) / _TWO_PI)
        if k_lo > k_hi:
            raise LimitError(
                f"joint {j + 1}: no angle equivalent to {math.degrees(b[j]):.2f} deg inside "
                f"[{math.degrees(lo):.1f}, {math.degrees(hi):.1f}] deg"
            )
        k_near = round((a[j] - b[j]) / _TWO_PI)
        b[j] += _TWO_PI * min(max(k_near, k_lo), k_hi)
    return b


@dataclass(frozen=True)
class JointState:
    """Position, velocity and acceleration of the arm.

    Attributes:
        q: Joint angles, shape (6,) [rad].
        qd: Joint velocities, shape (6,) [rad/s].
        qdd: Joint accelerations, shape (6,) [rad/s^2].
    """

    q: Array
    qd: Array = field(default_factory=lambda: np.zeros(N_JOINTS))
    qdd: Array = field(default_factory=lambda: np.zeros(N_JOINTS))

    @staticmethod
    def at_rest(q: npt.ArrayLike) -> JointState:
        """The arm standing still at ``q`` [rad], shape (6,)."""
        return JointState(as_joint_vector(q, "q"))


__all__ = [
    "Array",
    "JointState",
    "as_joint_vector",
    "check_in_range",
    "unwrap_target",
    "unwrap_values",
]
