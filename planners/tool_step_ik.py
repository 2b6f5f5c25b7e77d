"""One small tool-down move as joint deltas: damped least squares on the arm's Jacobian.

`ToolStepIK` keeps its own copy of the arm model (``assets/irb140/irb140.xml``: the robot's
base is the world origin, as in the cell). Given the arm's joint angles and a small move of the
tool-centre point (dx, dy, dz) and of its yaw, it returns the joint angles that make the move
with the tool pointing straight down: a few Gauss-Newton iterations, each one

    dq = J^T (J J^T + damping^2 I)^-1 e,

with ``J`` the (6, 6) site Jacobian (`mujoco.mj_jacSite`, world frame, position rows then
rotation rows) and ``e`` the pose error (the position error [m] and the rotation vector [rad]
from the current orientation to the tool-down one at the target yaw). Near a singularity the
damping shortens the step instead of blowing it up. The joint angles stay inside the model's
joint ranges. Unlike `planners.ik.IKSolver` (mink, restarts, exact convergence) this is
one continuous step from the current configuration, meant for a controller that calls it
every control period.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from configs.checks import check_fields, checked
from planners.config import N_JOINTS
from planners.errors import InvalidTargetError, LimitError, PlannerError
from planners.robot import ROBOT_XML, joint_ranges
from planners.tool_pose import tool_down_rotation

Array = npt.NDArray[np.float64]


@dataclass(frozen=True)
class ToolStepConfig:
    """Settings of `ToolStepIK`.

    Attributes:
        site: The tool-centre-point site of the arm model.
        damping: Damping of the least-squares step (units of the pose error: m and rad); larger
            is steadier near singularities and shorter.
        iterations: Gauss-Newton iterations per move (each re-linearises at the new angles).
        orientation_weight: Weight of the rotation error [m/rad] against the position error
            (1: a radian counts as a metre).
    """

    site: str = "tcp"
    damping: float = checked(0.01, ge=0)
    iterations: int = checked(3, gt=0)
    orientation_weight: float = checked(0.2, gt=0)

    def __post_init__(self) -> None:
        check_fields(self, LimitError, qualify=True)


class ToolStepIK:
    """Tool-down moves mapped to joint angles on the agent's own copy of the arm model.

    Args:
        config: Settings (default `ToolStepConfig()`).
        model: An arm-only model (six hinge joints); None loads ``assets/irb140/irb140.xml``.

    Raises:
        PlannerError: The model has other joints or lacks the site.
    """

    def __init__(self, config: ToolStepConfig | None = None, model: mujoco.MjModel | None = None):
        self.cfg = config or ToolStepConfig()
        self.model = model if model is not None else mujoco.MjModel.from_xml_path(str(ROBOT_XML))
        if self.model.nq != N_JOINTS or self.model.nv != N_JOINTS:
            raise PlannerError(
                f"ToolStepIK needs an arm-only model with {N_JOINTS} joints; this one has "
                f"nq={self.model.nq}, nv={self.model.nv}"
            )
        self.site = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, self.cfg.site)
        if self.site < 0:
            raise PlannerError(f"the arm model has no site {self.cfg.site!r}")
        self.data = mujoco.MjData(self.model)
        self.lower, self.upper = joint_ranges(self.model)
        self._jac = np.zeros((6, N_JOINTS))

    def tool_pose(self, q: npt.ArrayLike) -> tuple[Array, Array]:
        """Tool-centre point (3,) [m] and rotation matrix (3, 3) at joint angles ``q`` (6,)."""
        self._set(q)
        return self.data.site_xpos[self.site].copy(), self.data.site_xmat[self.site].reshape(
            3, 3
        ).copy()

    def move(self, q: npt.ArrayLike, target: npt.ArrayLike, yaw: float) -> Array:
        """Joint angles (6,) [rad] moving the tool to ``target`` (3,) [m], down at ``yaw`` [rad].

        Starts from ``q`` (6,) [rad]; meant for moves of a few centimetres (one control period).

        Raises:
            InvalidTargetError: Non-finite or wrongly shaped inputs.
        """
        q = np.array(q, float)
        goal = np.asarray(target, float)
        if q.shape != (N_JOINTS,) or goal.shape != (3,):
            raise InvalidTargetError(
                f"q must have shape (6,) and target (3,), got {q.shape} and {goal.shape}"
            )
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(goal)) and np.isfinite(yaw)):
            raise InvalidTargetError(f"non-finite move: q {q}, target {goal}, yaw {yaw}")
        cfg, w = self.cfg, self.cfg.orientation_weight
        goal_rot = tool_down_rotation(float(yaw))
        eye = cfg.damping**2 * np.eye(6)
        for _ in range(cfg.iterations):
            self._set(q)
            rot = self.data.site_xmat[self.site].reshape(3, 3)
            err = np.concatenate(
                [goal - self.data.site_xpos[self.site], w * _rotation_vector(goal_rot @ rot.T)]
            )
            mujoco.mj_jacSite(self.model, self.data, self._jac[:3], self._jac[3:], self.site)
            jac = self._jac.copy()
            jac[3:] *= w
            q = np.clip(q + jac.T @ np.linalg.solve(jac @ jac.T + eye, err), self.lower, self.upper)
        return q

    def _set(self, q: npt.ArrayLike) -> None:
        self.data.qpos[:] = q
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_comPos(self.model, self.data)


def _rotation_vector(rot: Array) -> Array:
    """Axis times angle [rad] (3,) of a rotation matrix (world frame)."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rot.reshape(-1))
    vel = np.zeros(3)
    mujoco.mju_quat2Vel(vel, quat, 1.0)
    return vel


__all__ = ["ToolStepConfig", "ToolStepIK"]
