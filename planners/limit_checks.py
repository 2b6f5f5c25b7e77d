"""Checks of trajectories against the joint limits.

Peak usage of a segment, a sampled trajectory's report, and validation raising `LimitError`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planners.config import N_JOINTS, JointLimits
from planners.errors import LimitError, PlannerError
from planners.joints import Array, check_in_range
from planners.trajectory import JointTrajectory, Segment


def peak_usage(seg: Segment, limits: JointLimits) -> tuple[Array, Array]:
    """Exact peak |acceleration| and |jerk| of a ruckig segment per joint, as limit fractions.

    Read from ruckig's phase profiles (sampling misses jerk phases shorter than the period).

    Returns:
        Acceleration and jerk usage, each shape (6,).

    Raises:
        PlannerError: ``seg`` is not a ruckig segment.
    """
    if seg.ruckig is None:
        raise PlannerError(f"segment {seg.label!r} is not a ruckig segment")
    acc, jerk = np.zeros(N_JOINTS), np.zeros(N_JOINTS)
    for dof, prof in enumerate(seg.ruckig.profiles[0]):
        active = np.asarray(prof.t) > 0.0
        j = np.abs(np.asarray(prof.j))[active]
        jerk[dof] = j.max() if j.size else 0.0
        acc[dof] = np.abs(np.asarray(prof.a)).max()
    return acc / np.asarray(limits.max_acceleration), jerk / np.asarray(limits.max_jerk)


def segment_within_limits(seg: Segment, limits: JointLimits, dt: float, tolerance: float) -> bool:
    """Whether a segment sampled every ``dt`` [s] stays within every limit (relative slack)."""
    n = max(2, int(math.ceil(seg.duration / dt)) + 1)
    times = np.linspace(0.0, seg.duration, n)
    traj = JointTrajectory(times, *seg.states(times))
    rep = limit_report(traj, limits)
    worst = max(rep.velocity.max(), rep.acceleration.max(), rep.jerk.max())
    return bool(rep.in_range and worst <= 1.0 + tolerance)


@dataclass(frozen=True)
class LimitReport:
    """Peak usage of each limit by a sampled trajectory, as fractions of the limit.

    Attributes:
        velocity: max |qd| / max_velocity per joint, shape (6,).
        acceleration: max |qdd| / max_acceleration per joint, shape (6,).
        jerk: max |finite-difference jerk| / max_jerk per joint, shape (6,).
        in_range: All positions inside the joint ranges.
    """

    velocity: Array
    acceleration: Array
    jerk: Array
    in_range: bool


def limit_report(traj: JointTrajectory, limits: JointLimits) -> LimitReport:
    """Measure how much of each limit a sampled trajectory uses."""
    vel = np.max(np.abs(traj.qd), axis=0) / np.asarray(limits.max_velocity)
    acc = np.max(np.abs(traj.qdd), axis=0) / np.asarray(limits.max_acceleration)
    if traj.times.size > 2:
        jerk_fd = np.diff(traj.qdd, axis=0) / np.diff(traj.times)[:, None]
        jerk = np.max(np.abs(jerk_fd), axis=0) / np.asarray(limits.max_jerk)
    else:
        jerk = np.zeros(N_JOINTS)
    lo, hi = np.asarray(limits.lower), np.asarray(limits.upper)
    in_range = bool(np.all((traj.q >= lo - 1e-9) & (traj.q <= hi + 1e-9)))
    return LimitReport(vel, acc, jerk, in_range)


def validate(traj: JointTrajectory, limits: JointLimits, tolerance: float = 1e-3) -> None:
    """Raise `LimitError` if a sampled trajectory breaks a limit by more than ``tolerance``.

    Args:
        traj: The trajectory.
        limits: Kinematic limits.
        tolerance: Relative slack (finite-difference jerk at segment joins is excluded by
            ruckig's construction; this covers rounding).

    Raises:
        LimitError: Names the joint, the quantity, the peak and the limit.
    """
    if not (np.all(np.isfinite(traj.q)) and np.all(np.isfinite(traj.qd))):
        raise LimitError("trajectory contains non-finite values")
    rep = limit_report(traj, limits)
    if not rep.in_range:
        outside = (traj.q < np.asarray(limits.lower)) | (traj.q > np.asarray(limits.upper))
        check_in_range(traj.q[int(np.argmax(np.any(outside, axis=1)))], limits, "trajectory")
    for name, use, lim in (
        ("velocity", rep.velocity, limits.max_velocity),
        ("acceleration", rep.acceleration, limits.max_acceleration),
        ("jerk", rep.jerk, limits.max_jerk),
    ):
        over = np.flatnonzero(use > 1.0 + tolerance)
        if over.size:
            i = int(over[0])
            raise LimitError(
                f"trajectory: joint {i + 1} {name} peaks at {use[i] * lim[i]:.4f}, "
                f"limit {lim[i]:.4f} (SI units, rad-based)"
            )


__all__ = ["LimitReport", "limit_report", "peak_usage", "segment_within_limits", "validate"]
