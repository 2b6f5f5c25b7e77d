"""The scripted low-level controller of the one-tile task in the ``joint`` action mode.

`LowLevelJointExpert` composes two parts:

1. `agents.experts.cartesian.LowLevelExpert` decides the move, phase by phase (approach, seal,
   lift, carry round the front of the robot, align, set down, release, retreat), as the tool
   move (dx, dy, dz, dyaw) of a ``cartesian`` action in units of ``tool_step`` / ``yaw_step``
   per control period, plus the vacuum.
2. `planners.tool_step_ik.ToolStepIK` maps that move onto the arm's joints on the agent's own
   copy of the arm model (``assets/irb140/irb140.xml``, the public kinematic model): from the
   observed joint angles, damped least squares on the tool's Jacobian to the moved tool point
   with the tool pointing straight down at the moved yaw.

The joint action is the joint change divided by the env's ``task_spec.joint_step`` (each axis'
speed limit times the control period), scaled down as a whole when an axis would exceed 1 (the
direction of the tool move is kept, not clipped axis by axis). Like the cartesian controller it
reads only the ``state`` observation and the `envs.task_spec.TaskSpec` and keeps no memory.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from agents.errors import AgentError
from agents.experts.cartesian import (
    EXPERT_CONFIG,
    TOOL_POS,
    TOOL_YAW,
    LowLevelExpert,
    load_expert_config,
)
from configs import load_config
from configs.checks import check_fields, checked
from envs.task_spec import TaskSpec
from planners.errors import PlannerError
from planners.tool_step_ik import ToolStepConfig, ToolStepIK

JOINT_EXPERT_CONFIG = "lowlevel_joint_expert"
"""Bundled config name (``configs/lowlevel_joint_expert.yaml``)."""
N_JOINTS = 6
"""Arm joints in a ``joint`` action (the vacuum follows)."""


@dataclass(frozen=True)
class LowLevelJointExpertConfig:
    """Settings of `LowLevelJointExpert`.

    Attributes:
        phases: Settings of the phase logic (`agents.experts.cartesian.LowLevelExpertConfig`), a
            name under ``configs/`` or a path.
        tool_step: Tool move of a full cartesian action in one control period [m] (x, y, z).
        yaw_step: Tool turn of a full cartesian action in one control period [rad].
        damping: Damping of the least-squares step (m and rad of pose error).
        iterations: Gauss-Newton iterations per control period.
        orientation_weight: Weight of the tool's rotation error against its position error
            [m/rad].
    """

    phases: str = "lowlevel_expert"
    tool_step: float = checked(0.02, gt=0)
    yaw_step: float = checked(0.12, gt=0)
    damping: float = checked(0.01, ge=0)
    iterations: int = checked(3, gt=0)
    orientation_weight: float = checked(0.2, gt=0)

    def __post_init__(self) -> None:
        check_fields(self, AgentError, qualify=True)
        if not self.phases:
            raise AgentError("LowLevelJointExpertConfig.phases must name a config, got ''")


def load_joint_expert_config(
    name_or_path: str | None = JOINT_EXPERT_CONFIG, **overrides: Any
) -> LowLevelJointExpertConfig:
    """Load a `LowLevelJointExpertConfig` strictly (unknown keys are a `configs.ConfigError`)."""
    return load_config(LowLevelJointExpertConfig, name_or_path, **overrides)


class LowLevelJointExpert:
    """Scripted ``joint`` controller: the cartesian controller's moves mapped onto the joints.

    Args:
        env: A ``joint`` env with ``state`` (or ``rgb+state``) observations (any wrapper).
        config: Settings (default: ``configs/lowlevel_joint_expert.yaml``).

    Raises:
        AgentError: The env is not in the ``joint`` action mode, has no state rows, or the
            settings are invalid.
    """

    def __init__(self, env: gym.Env, config: LowLevelJointExpertConfig | None = None) -> None:
        spec: TaskSpec = env.get_wrapper_attr("task_spec")
        if spec.action_mode != "joint" or spec.joint_step is None:
            raise AgentError(
                f"LowLevelJointExpert acts in the 'joint' action mode, the env's is "
                f"{spec.action_mode!r}"
            )
        self.cfg = config or load_joint_expert_config()
        cfg = self.cfg
        step = (cfg.tool_step, cfg.tool_step, cfg.tool_step, cfg.yaw_step)
        self.planner = LowLevelExpert(env, load_expert_config(cfg.phases), tool_step=step)
        try:
            self.ik = ToolStepIK(
                ToolStepConfig(
                    damping=cfg.damping,
                    iterations=cfg.iterations,
                    orientation_weight=cfg.orientation_weight,
                )
            )
        except PlannerError as exc:
            raise AgentError(f"LowLevelJointExpert: {exc}") from exc
        self.move_step = np.asarray(step, float)
        self.joint_step = np.asarray(spec.joint_step, float)
        self.observation_space = env.observation_space
        self.action_space = env.action_space

    def predict(
        self, obs: dict[str, Any], state: Any = None, episode_start: Any = None, **_: Any
    ) -> tuple[np.ndarray, None]:
        """The action for ``obs`` (SB3 style: ``(action, None)``; no memory is kept)."""
        del state, episode_start
        return self.act(obs), None

    def __call__(self, obs: dict[str, Any]) -> np.ndarray:
        """The action for ``obs``."""
        return self.act(obs)

    def act(self, obs: dict[str, Any]) -> np.ndarray:
        """The action for one observation, float32 (7,) in [-1, 1]."""
        cartesian = self.planner.act(obs)
        robot = np.asarray(obs["robot"], float)
        q = robot[:N_JOINTS]
        move = cartesian[:4] * self.move_step
        yaw = math.atan2(robot[TOOL_YAW][1], robot[TOOL_YAW][0])
        target = self.ik.move(q, robot[TOOL_POS] + move[:3], yaw + float(move[3]))
        a = (target - q) / self.joint_step
        a /= max(1.0, float(np.max(np.abs(a))))
        return np.array([*a, cartesian[4]], np.float32)


def lowlevel_controller(env: gym.Env, config: str = "") -> LowLevelExpert | LowLevelJointExpert:
    """The scripted low-level controller of the env's action mode, with the settings ``config``.

    ``joint``: `LowLevelJointExpert` (``config`` a `LowLevelJointExpertConfig` name or path);
    otherwise `LowLevelExpert` (a `agents.experts.cartesian.LowLevelExpertConfig`). "" the
    bundled settings.

    Raises:
        AgentError: The env's action mode is neither ``joint`` nor ``cartesian``.
    """
    if env.get_wrapper_attr("task_spec").action_mode == "joint":
        return LowLevelJointExpert(env, load_joint_expert_config(config or JOINT_EXPERT_CONFIG))
    return LowLevelExpert(env, load_expert_config(config or EXPERT_CONFIG))


__all__ = [
    "LowLevelJointExpert",
    "LowLevelJointExpertConfig",
    "load_joint_expert_config",
    "lowlevel_controller",
]
