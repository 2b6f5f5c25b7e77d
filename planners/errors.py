"""Exceptions of the `planners` package.

Every error derives from `PlannerError` (itself a `ValueError`) and names what was wrong (the
pose, the joint, the limit) and what is allowed.
"""

from __future__ import annotations


class PlannerError(ValueError):
    """Base class of every error raised by `planners`."""


class LimitError(PlannerError):
    """A limit or setting is invalid (zero, negative, NaN) or a configuration is out of range."""


class InvalidTargetError(PlannerError):
    """A target (pose, yaw, configuration, velocity) is not finite or has the wrong shape."""


class UnreachableError(PlannerError):
    """No joint configuration reaches the target pose with the tool pointing down.

    Raised instead of returning a wrong pose: outside the reach, a flipped tool, or a yaw that
    joint 6 cannot realise inside its range.
    """


class TrajectoryError(PlannerError):
    """Ruckig could not compute a segment (infeasible state or target velocity)."""


__all__ = [
    "InvalidTargetError",
    "LimitError",
    "PlannerError",
    "TrajectoryError",
    "UnreachableError",
]
