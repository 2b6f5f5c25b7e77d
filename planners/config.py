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
from functools import partial
from pathlib import Path
from typing import Any

from configs import check_positive, load_config
from planners.errors import LimitError, PlannerError
from planners.robot import robot_joint_lower, robot_joint_speeds, robot_joint_upper

N_JOINTS = 6
"""Number of arm joints."""

ACCEL_PER_SPEED = 9.0
"""Default axis acceleration limit per unit of speed limit [1/s] (assumption, see above)."""
JERK_PER_ACCEL = 10.0
"""Default axis jerk limit per unit of acceleration limit [1/s] (assumption, see above)."""

_check_positive = partial(check_positive, error=LimitError)
_check_non_negative = partial(check_positive, error=LimitError, strict=False)


def _check_tuple(obj: object, name: str, *, positive: bool = True) -> None:
    value = getattr(obj, name)
    if len(value) != N_JOINTS:
        raise LimitError(
            f"{type(obj).__name__}.{name} needs {N_JOINTS} values (one per joint), got {value!r}"
        )
    for i, v in enumerate(value):
        if not math.isfinite(v) or (positive and v <= 0.0):
            raise LimitError(
                f"{type(obj).__name__}.{name}[{i}] (joint {i + 1}) must be "
                f"{'positive and ' if positive else ''}finite, got {v!r}"
            )


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

    lower: tuple[float, ...] = field(default_factory=robot_joint_lower)
    upper: tuple[float, ...] = field(default_factory=robot_joint_upper)
    max_velocity: tuple[float, ...] = field(default_factory=robot_joint_speeds)
    max_acceleration: tuple[float, ...] = field(
        default_factory=lambda: tuple(ACCEL_PER_SPEED * v for v in robot_joint_speeds())
    )
    max_jerk: tuple[float, ...] = field(
        default_factory=lambda: tuple(
            JERK_PER_ACCEL * ACCEL_PER_SPEED * v for v in robot_joint_speeds()
        )
    )

    def __post_init__(self) -> None:
        _check_tuple(self, "lower", positive=False)
        _check_tuple(self, "upper", positive=False)
        for name in ("max_velocity", "max_acceleration", "max_jerk"):
            _check_tuple(self, name)
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
    joint_names: tuple[str, ...] = ("joint1", "joint2", "joint3", "joint4", "joint5", "joint6")
    position_tolerance: float = 1e-4
    orientation_tolerance_deg: float = 0.1
    max_iterations: int = 40
    step_dt: float = 0.1
    damping: float = 1e-4
    regularisation: float = 1e-9
    position_cost: float = 1.0
    orientation_cost: float = 1.0
    solver: str = "daqp"
    restarts: int = 6
    restart_seed: int = 0
    restart_spread: float = 0.6
    collision_min_distance: float = 0.002
    collision_detection_distance: float = 0.05
    limit_margin: float = 1e-3
    memory: int = 256

    def __post_init__(self) -> None:
        _check_positive(
            self,
            "memory",
            "position_tolerance",
            "orientation_tolerance_deg",
            "max_iterations",
            "step_dt",
            "position_cost",
            "orientation_cost",
            "collision_detection_distance",
        )
        _check_non_negative(
            self,
            "damping",
            "regularisation",
            "restarts",
            "restart_spread",
            "collision_min_distance",
            "limit_margin",
        )
        import qpsolvers  # noqa: PLC0415 - mink's QP back end, only needed to check the name

        if self.solver not in qpsolvers.available_solvers:
            raise PlannerError(
                f"ik.solver {self.solver!r} is not an installed QP solver; allowed: "
                f"{sorted(qpsolvers.available_solvers)}"
            )
        if len(self.joint_names) != N_JOINTS:
            raise LimitError(f"IKConfig.joint_names needs {N_JOINTS} names, got {self.joint_names}")


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

    sample_dt: float = 0.002
    blend: bool = True
    wrap_joints: tuple[int, ...] = (3, 5)
    limit_tolerance: float = 1e-3

    def __post_init__(self) -> None:
        _check_positive(self, "sample_dt")
        _check_non_negative(self, "limit_tolerance")
        for j in self.wrap_joints:
            if not 0 <= j < N_JOINTS:
                raise LimitError(
                    f"TrajectoryConfig.wrap_joints: {j} is not a joint index; allowed 0..5"
                )


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

    approach_height: float = 0.015
    approach_speed: float = 0.25
    approach_alternatives: tuple[float, ...] = (0.025,)
    lead_bisections: int = 8
    lead_joints: tuple[int, ...] = (0, 3, 5)
    lead_share: float = 0.99
    counter_swing: tuple[float, ...] = (0.006, 0.007, 0.008, 0.009, 0.010, 0.011, 0.012)
    counter_swing_joints: tuple[int, ...] = (0,)
    lateral_clearance_height: float = 0.006
    empty_clearance_height: float = 0.002
    max_lateral_drift: float = 0.001
    transfer_clearance: float = 0.008
    pick_press: float = 0.0005
    place_gap: float = 0.0005
    pick_dwell: float = 0.05
    place_dwell: float = 0.05
    belt_match_time: float = 0.05
    predict_iterations: int = 6
    predict_tolerance: float = 2e-4
    predict_margin: float = 0.02
    max_tilt_deg: float = 0.5

    def __post_init__(self) -> None:
        _check_positive(
            self,
            "approach_height",
            "approach_speed",
            "lateral_clearance_height",
            "empty_clearance_height",
            "max_lateral_drift",
            "predict_iterations",
            "predict_tolerance",
            "predict_margin",
            "max_tilt_deg",
        )
        _check_non_negative(
            self,
            "lead_bisections",
            "transfer_clearance",
            "pick_press",
            "place_gap",
            "pick_dwell",
            "place_dwell",
            "belt_match_time",
        )
        swings = self.counter_swing
        if not all(math.isfinite(p) and p > 0.0 for p in swings) or list(swings) != sorted(swings):
            raise LimitError(
                f"CycleConfig.counter_swing: lengths must be finite, > 0 s and ascending, got "
                f"{swings}"
            )
        if not 0.0 < self.lead_share < 1.0:
            raise LimitError(f"CycleConfig.lead_share must be in (0, 1), got {self.lead_share}")
        if not set(self.counter_swing_joints) <= set(self.lead_joints):
            raise LimitError(
                f"CycleConfig.counter_swing_joints {self.counter_swing_joints} must be among "
                f"lead_joints {self.lead_joints}"
            )
        if not all(0 <= j < N_JOINTS for j in self.lead_joints):
            raise LimitError(
                f"CycleConfig.lead_joints: {self.lead_joints} are not joint indices 0..5"
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
