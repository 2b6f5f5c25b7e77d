"""A planned pick-and-place cycle (`planners.pick_place.PickPlacePlanner.plan_cycle`)."""

from __future__ import annotations

from dataclasses import dataclass

from planners.cycle.moves import Array
from planners.joints import JointState
from planners.trajectory import JointTrajectory, Piecewise


@dataclass(frozen=True)
class CyclePlan:
    """A planned pick-and-place cycle.

    Attributes:
        trajectory: The sampled joint trajectory (times from 0 at the cycle's start).
        piecewise: The exact segments (labels as in the module docstring).
        vacuum_on: Time the vacuum switches on (pad at the pick contact) [s].
        vacuum_off: Time the vacuum switches off (tile at the place contact) [s].
        lift_off: Time the tool starts lifting the tile [s].
        duration: Total duration [s].
        bound: Lower bound of the cycle, vacuum dwells included [s] (see the module docstring;
            with ``retreat_end``, the time-optimal retreat included).
        motion_bound: Lower bound of the motion alone: start -> pick contact -> place contact
            (-> retreat end), time-optimal, no dwell [s].
        pick_q: Configuration at the pick contact, shape (6,) [rad].
        place_q: Configuration at the place contact, shape (6,) [rad].
        pick_position: Predicted tile top centre at contact, shape (3,) [m].
        place_position: Target tile top centre at the place, shape (3,) [m].
        pick_yaw: Tool yaw at the pick [rad].
        place_yaw: Tool yaw at the place [rad] (the chosen equivalent rotation).
        leads: Lead time used at each approach point (start out, pick in, pick out, place in)
            [s]; 0 for a vertical pass, NaN for a stop.
        contact_error: Predicted distance between the pad and the moving tile's grip point at
            contact [m] (residual of the contact-time prediction; 0 on a static belt).
        plan_ms: Wall-clock planning time [ms] (IK + trajectories + checks).
    """

    trajectory: JointTrajectory
    piecewise: Piecewise
    vacuum_on: float
    vacuum_off: float
    lift_off: float
    duration: float
    bound: float
    motion_bound: float
    pick_q: Array
    place_q: Array
    pick_position: Array
    place_position: Array
    pick_yaw: float
    place_yaw: float
    leads: tuple[float, float, float, float]
    contact_error: float
    plan_ms: float

    @property
    def end(self) -> JointState:
        """State at the end of the cycle."""
        return self.piecewise.end

    @property
    def ratio(self) -> float:
        """Cycle duration over its lower bound (dwells included)."""
        return self.duration / self.bound

    @property
    def motion_ratio(self) -> float:
        """Cycle duration over the motion-only bound (no dwell)."""
        return self.duration / self.motion_bound


__all__ = ["CyclePlan"]
