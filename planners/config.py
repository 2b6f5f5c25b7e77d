"""Configuration of the planners (IK, trajectories, pick-and-place cycle).

Every number is a field of a frozen dataclass with its unit; bundled defaults live in
``configs/planner.yaml``. Load with `load_planner_config`; validation happens in
``__post_init__`` and raises `LimitError` naming the field and what is allowed.

Facts and assumptions:
    * Joint ranges and axis speed limits are read from the robot model (`planners.robot`: the
      MJCF holds the ABB IRB 140 datasheet values).
    * ABB publishes no per-axis acceleration or jerk limits. The defaults assume each axis reaches
      its top speed in 1/9 s (acceleration = 9 x speed per second) with jerk 10 x acceleration
      (about 15-19 m/s^2 at the tool at the 0.5-0.6 m radius of the work areas). Calibrated, not
      conservative: ABB's 25/300/25 mm standard cycle (1 kg) is quoted at about 0.85 s for the
      IRB 140, for a blended path. Planned here with the top of the cycle flown through as the
      cell flies through its approach points, it takes 0.851 s at 9 x (0.819 s at 10 x, 0.884 s
      at 8 x); stopping at all six corners takes 1.41 s at 9 x, which says nothing about the
      limits. These are assumptions: change them in the YAML.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from configs import load_config
from configs.checks import check_fields, checked
from planners.errors import LimitError, PlannerError
from planners.robot import robot_joint_lower, robot_joint_speeds, robot_joint_upper

N_JOINTS = 6
"""Number of arm joints."""

ACCEL_PER_SPEED = 9.0
"""Default axis acceleration limit per unit of speed limit [1/s] (assumption, see above)."""
JERK_PER_ACCEL = 10.0
"""Default axis jerk limit per unit of acceleration limit [1/s] (assumption, see above)."""


def _from_speeds(times_accel: float) -> tuple[float, ...]:
    """The model's axis speeds x ``ACCEL_PER_SPEED`` x ``times_accel`` (default limits)."""
    return tuple(times_accel * ACCEL_PER_SPEED * v for v in robot_joint_speeds())


@dataclass(frozen=True)
class JointLimits:
    """Kinematic limits of the six axes.

    Attributes:
        lower: Lower joint limits, shape (6,) [rad]. Default: the robot model's joint ranges
            (``assets/irb140/irb140.xml``, their one home; `planners.robot`); set only to narrow
            them (the IK solver never goes beyond the model's ranges).
        upper: Upper joint limits, shape (6,) [rad]. Default: the robot model's.
        max_velocity: Axis speed limits, shape (6,) [rad/s]. Default: the robot model's velocity
            actuators' control ranges (datasheet: 200, 200, 260, 360, 360, 450 deg/s).
        max_acceleration: Axis acceleration limits, shape (6,) [rad/s^2] (assumption: 9 x speed,
            calibrated on ABB's standard cycle time, see the module docstring).
        max_jerk: Axis jerk limits, shape (6,) [rad/s^3] (assumption: 10 x acceleration).
    """

    lower: tuple[float, ...] = checked(factory=robot_joint_lower, length=N_JOINTS, finite=True)
    upper: tuple[float, ...] = checked(factory=robot_joint_upper, length=N_JOINTS, finite=True)
    max_velocity: tuple[float, ...] = checked(factory=robot_joint_speeds, length=N_JOINTS, gt=0)
    max_acceleration: tuple[float, ...] = checked(
        factory=lambda: _from_speeds(1.0), length=N_JOINTS, gt=0
    )
    max_jerk: tuple[float, ...] = checked(
        factory=lambda: _from_speeds(JERK_PER_ACCEL), length=N_JOINTS, gt=0
    )

    def __post_init__(self) -> None:
        check_fields(self, LimitError, qualify=True)
        for i, (lo, hi) in enumerate(zip(self.lower, self.upper, strict=True)):
            if lo >= hi:
                raise LimitError(
                    f"JointLimits: joint {i + 1} lower {lo} rad must be below upper {hi} rad"
                )

    def scaled(self, speed: float = 1.0, accel: float = 1.0) -> JointLimits:
        """These limits with velocity scaled by ``speed`` and acceleration/jerk by ``accel``.

        Raises:
            LimitError: A scale is zero, negative or not finite.
        """
        for name, s in (("speed", speed), ("accel", accel)):
            if not (math.isfinite(s) and s > 0):
                raise LimitError(f"JointLimits.scaled: {name} scale must be > 0, got {s!r}")
        return JointLimits(
            lower=self.lower,
            upper=self.upper,
            max_velocity=tuple(v * speed for v in self.max_velocity),
            max_acceleration=tuple(a * accel for a in self.max_acceleration),
            max_jerk=tuple(j * accel for j in self.max_jerk),
        )


@dataclass(frozen=True)
class IKConfig:
    """Differential IK with mink.

    Attributes:
        site: Name of the tool-centre-point site in the robot model.
        joint_names: Names of the six arm joints, base to flange.
        position_tolerance: Converged when the TCP is within this distance [m].
        orientation_tolerance_deg: ... and within this rotation angle [deg].
        max_iterations: Iterations per attempt.
        step_dt: Integration step of one iteration [s]; with `VelocityLimit` it bounds the joint
            step to ``max_velocity * step_dt`` per iteration.
        damping: Levenberg-Marquardt damping of the frame task (mink ``lm_damping``).
        regularisation: Tikhonov damping of the QP (mink ``damping``).
        position_cost: Frame-task position weight [1/m].
        orientation_cost: Frame-task orientation weight [1/rad].
        solver: QP solver name for qpsolvers.
        restarts: Extra attempts from other seeds when the first one fails.
        restart_seed: Random generator seed of the restart perturbations (determinism).
        restart_spread: Standard deviation of the random perturbation of restart seeds [rad].
        collision_min_distance: Minimum distance kept from the caller's obstacle geoms [m].
        collision_detection_distance: Distance at which collision constraints activate [m].
        limit_margin: Solutions must lie this far inside each joint range [rad].
        memory: Known-good solutions kept as restart seeds (nearest-first).
    """

    site: str = "tcp"
    joint_names: tuple[str, ...] = checked(
        ("joint1", "joint2", "joint3", "joint4", "joint5", "joint6"), length=N_JOINTS
    )
    position_tolerance: float = checked(1e-4, gt=0)
    orientation_tolerance_deg: float = checked(0.1, gt=0)
    max_iterations: int = checked(40, gt=0)
    step_dt: float = checked(0.1, gt=0)
    damping: float = checked(1e-4, ge=0)
    regularisation: float = checked(1e-9, ge=0)
    position_cost: float = checked(1.0, gt=0)
    orientation_cost: float = checked(1.0, gt=0)
    solver: str = "daqp"
    restarts: int = checked(6, ge=0)
    restart_seed: int = 0
    restart_spread: float = checked(0.6, ge=0)
    collision_min_distance: float = checked(0.002, ge=0)
    collision_detection_distance: float = checked(0.05, gt=0)
    limit_margin: float = checked(1e-3, ge=0)
    memory: int = checked(256, gt=0)

    def __post_init__(self) -> None:
        check_fields(self, LimitError, qualify=True)
        import qpsolvers  # noqa: PLC0415 - mink's QP back end, only needed to check the name

        if self.solver not in qpsolvers.available_solvers:
            raise PlannerError(
                f"ik.solver {self.solver!r} is not an installed QP solver; allowed: "
                f"{sorted(qpsolvers.available_solvers)}"
            )


@dataclass(frozen=True)
class TrajectoryConfig:
    """Sampling and blending of ruckig trajectories.

    Attributes:
        sample_dt: Period of the sampled `JointTrajectory` [s] (the control period).
        blend: Pass the approach points with non-zero velocity instead of stopping.
        wrap_joints: Indices (0-based) of the joints whose targets are unwrapped to the
            nearest equivalent angle (multiples of 2 pi) inside their range: joints 4 and 6.
        limit_tolerance: Relative slack when validating sampled trajectories against limits
            (ruckig's own numerical error plus finite-difference error).
    """

    sample_dt: float = checked(0.002, gt=0)
    blend: bool = True
    wrap_joints: tuple[int, ...] = checked((3, 5), ge=0, lt=N_JOINTS)
    limit_tolerance: float = checked(1e-3, ge=0)

    def __post_init__(self) -> None:
        check_fields(self, LimitError, qualify=True)


@dataclass(frozen=True)
class CycleConfig:
    """One pick-and-place cycle.

    Attributes:
        approach_height: Height of the approach points above the pick and place contact
            poses [m]; motion below them is vertical.
        approach_speed: Vertical tool speed when passing an approach point with blending [m/s].
        approach_alternatives: Other approach heights each cycle is also planned with [m]; the
            fastest plan is kept (a higher approach lets the vertical moves rise at full jerk
            through the clearance height, which pays when the base's turn limits the cycle;
            where the arm's other joints limit it, the lower one is faster). Each one costs a
            whole plan.
        lead_bisections: Bisection steps searching the largest lead at each approach point (the
            transfer's motion started during the lift and finished during the descent, up to
            the vertical move's duration) whose lateral drift below `lateral_clearance_height`
            stays within `max_lateral_drift`.
        lead_joints: Joints (0-based) whose transfer motion is started early (the lead): the
            base and the wrist rotations, which the vertical moves barely use.
        lead_share: Fraction of the lead joints' acceleration and jerk given to the lead; the
            vertical moves keep the rest (the sum respects every limit), in (0, 1).
        counter_swing: Counter-swing lengths tried in this order where even a lead over the
            whole vertical move breaks the drift at the clearance crossing [s]: the
            ``counter_swing_joints`` first turn away from their target at full jerk for that
            long (reaching a contact: they overshoot and come back), so at the crossing they
            already move faster within the same drift, and the transfer can start with the
            vertical move (end with it). The first valid length is used if it is faster than
            the plain lead. Ascending; empty: plain leads only.
        counter_swing_joints: Joints (0-based, among ``lead_joints``) that counter-swing: the
            base, whose turn is the sideways drift.
        lateral_clearance_height: Below this height above a contact pose the tool carrying a
            tile (lift off the pick, descent to the place) may drift at most
            `max_lateral_drift` sideways (the held tile's underside clear of its neighbours'
            tops: tile thickness plus a margin) [m].
        empty_clearance_height: The same for the empty pad (descent to the pick, retreat from
            the place): the pad's face only has to clear the tops of the tiles around the
            contact, which are level with the contact (equal thickness), so a small margin
            suffices [m]. At most `lateral_clearance_height`.
        max_lateral_drift: Allowed sideways drift below the clearance height [m].
        transfer_clearance: Minimum tool height above the lower contact pose during the
            transfer [m].
        pick_press: The pad goes this far below the given pick height to seal [m].
        place_gap: The pad releases this far above the given place height [m].
        pick_dwell: Time at the pick with vacuum on before lifting (vacuum build-up) [s].
        place_dwell: Time at the place with vacuum off before retreating (release) [s].
        belt_match_time: On a moving belt, the tool travels with the belt for this long around
            contact (covers the pick dwell) [s]; it is at least `pick_dwell`.
        predict_iterations: Most fixed-point iterations predicting where a moving tile is at
            contact (each one a full plan).
        predict_tolerance: Stop iterating when the pad would meet the tile this close to its
            grip point [m].
        predict_margin: Without a fixed point, aim this much later than the latest contact time
            found and wait at the start for the difference [s].
        max_tilt_deg: Largest tool tilt from straight down accepted at a contact pose [deg].
    """

    approach_height: float = checked(0.015, gt=0)
    approach_speed: float = checked(0.25, gt=0)
    approach_alternatives: tuple[float, ...] = (0.025,)
    lead_bisections: int = checked(8, ge=0)
    lead_joints: tuple[int, ...] = checked((0, 3, 5), ge=0, lt=N_JOINTS)
    lead_share: float = checked(0.99, gt=0, lt=1)
    counter_swing: tuple[float, ...] = checked(
        (0.006, 0.007, 0.008, 0.009, 0.010, 0.011, 0.012), gt=0
    )
    counter_swing_joints: tuple[int, ...] = (0,)
    lateral_clearance_height: float = checked(0.006, gt=0)
    empty_clearance_height: float = checked(0.002, gt=0)
    max_lateral_drift: float = checked(0.001, gt=0)
    transfer_clearance: float = checked(0.008, ge=0)
    pick_press: float = checked(0.0005, ge=0)
    place_gap: float = checked(0.0005, ge=0)
    pick_dwell: float = checked(0.05, ge=0)
    place_dwell: float = checked(0.05, ge=0)
    belt_match_time: float = checked(0.05, ge=0)
    predict_iterations: int = checked(6, gt=0)
    predict_tolerance: float = checked(2e-4, gt=0)
    predict_margin: float = checked(0.02, gt=0)
    max_tilt_deg: float = checked(0.5, gt=0)

    def __post_init__(self) -> None:
        check_fields(self, LimitError, qualify=True)
        swings = self.counter_swing
        if list(swings) != sorted(swings):
            raise LimitError(f"CycleConfig.counter_swing: lengths must be ascending, got {swings}")
        if not set(self.counter_swing_joints) <= set(self.lead_joints):
            raise LimitError(
                f"CycleConfig.counter_swing_joints {self.counter_swing_joints} must be among "
                f"lead_joints {self.lead_joints}"
            )
        for height in self.approach_alternatives:
            if not (math.isfinite(height) and height >= self.lateral_clearance_height):
                raise LimitError(
                    f"CycleConfig.approach_alternatives: {height!r} m must be finite and at "
                    f"least lateral_clearance_height {self.lateral_clearance_height} m"
                )
        if self.lateral_clearance_height > self.approach_height:
            raise LimitError(
                "CycleConfig.lateral_clearance_height "
                f"{self.lateral_clearance_height} m must not exceed approach_height "
                f"{self.approach_height} m"
            )
        if self.empty_clearance_height > self.lateral_clearance_height:
            raise LimitError(
                "CycleConfig.empty_clearance_height "
                f"{self.empty_clearance_height} m must not exceed lateral_clearance_height "
                f"{self.lateral_clearance_height} m"
            )


@dataclass(frozen=True)
class PlannerConfig:
    """All planner settings.

    Attributes:
        limits: Joint kinematic limits.
        ik: Differential IK settings.
        trajectory: Ruckig sampling and blending.
        cycle: Pick-and-place cycle geometry and timing.
    """

    limits: JointLimits = field(default_factory=JointLimits)
    ik: IKConfig = field(default_factory=IKConfig)
    trajectory: TrajectoryConfig = field(default_factory=TrajectoryConfig)
    cycle: CycleConfig = field(default_factory=CycleConfig)


def load_planner_config(
    name_or_path: str | Path | None = "planner", **overrides: Any
) -> PlannerConfig:
    """Load the planner configuration (bundled ``configs/planner.yaml`` by default).

    Args:
        name_or_path: Bundled name or YAML path; None uses the dataclass defaults.
        **overrides: Top-level sections (``limits``, ``ik``, ``trajectory``, ``cycle``) as
            mappings or dataclass instances.

    Raises:
        configs.ConfigError: Unknown key or wrong type.
        LimitError: A value out of its allowed range.
    """
    return load_config(PlannerConfig, name_or_path, **overrides)


__all__ = [
    "N_JOINTS",
    "CycleConfig",
    "IKConfig",
    "JointLimits",
    "PlannerConfig",
    "TrajectoryConfig",
    "load_planner_config",
]
