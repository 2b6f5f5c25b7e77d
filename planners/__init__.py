"""Motion planning for the IRB 140 cell: mink IK, ruckig trajectories, pick-and-place cycles.

The package knows MuJoCo models and poses, never tasks, tiles or rewards: functions take tool
poses, sets of equivalent yaws and belt velocities as numbers.

Modules:
    config: frozen dataclass settings (`PlannerConfig`, bundled ``configs/planner.yaml``).
    errors: `PlannerError` and its typed subclasses.
    trajectory: chained jerk-limited time-optimal ruckig segments, `JointTrajectory`.
    rest_to_rest: closed-form duration of the time-optimal move between two rests.
    ik: tool-down IK with mink (`IKSolver`).
    pick_place: one pick-and-place cycle with events and lower bound (`PickPlacePlanner`).
    servo: position + velocity servo commands with inverse-dynamics feed-forward.

The heavy modules (``ik``, ``pick_place``, ``servo``: mink, MuJoCo) are imported explicitly.
"""

from planners.config import (
    CycleConfig,
    IKConfig,
    JointLimits,
    PlannerConfig,
    TrajectoryConfig,
    load_planner_config,
)
from planners.errors import (
    InvalidTargetError,
    LimitError,
    PlannerError,
    TrajectoryError,
    UnreachableError,
)
from planners.joints import JointState
from planners.trajectory import JointTrajectory

__all__ = [
    "CycleConfig",
    "IKConfig",
    "InvalidTargetError",
    "JointLimits",
    "JointState",
    "JointTrajectory",
    "LimitError",
    "PlannerConfig",
    "PlannerError",
    "TrajectoryConfig",
    "TrajectoryError",
    "UnreachableError",
    "load_planner_config",
]
