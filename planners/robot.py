"""The robot model file and the joint facts read from it (the MJCF is their one home).

Joint ranges come from the hinge joints' ``range`` and axis speed limits from the velocity
actuators' ``ctrlrange`` in ``assets/irb140/irb140.xml``; configurations and the cell read them
here instead of repeating the datasheet numbers.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import mujoco
import numpy as np

from planners.errors import PlannerError

ROBOT_XML = Path(__file__).resolve().parents[1] / "assets" / "irb140" / "irb140.xml"
"""The robot-only MJCF of the ABB IRB 140."""
ARM_JOINTS = ("joint1", "joint2", "joint3", "joint4", "joint5", "joint6")
"""Names of the six arm joints in the model."""


def joint_ranges(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper ranges of the arm joints in a model, each shape (6,) [rad].

    Raises:
        PlannerError: A joint is missing or has no range.
    """
    ids = [_joint_id(model, name) for name in ARM_JOINTS]
    rng = model.jnt_range[ids]
    if not np.all(model.jnt_limited[ids]):
        raise PlannerError(f"every arm joint needs a range in the model; got {rng.tolist()}")
    return rng[:, 0].copy(), rng[:, 1].copy()


def joint_speed_limits(model: mujoco.MjModel) -> np.ndarray:
    """Axis speed limits [rad/s], shape (6,): the ``ctrlrange`` of each joint's velocity actuator.

    Raises:
        PlannerError: A joint has no velocity actuator with a symmetric control range.
    """
    out = np.full(len(ARM_JOINTS), np.nan)
    for a in range(model.nu):
        is_velocity = model.actuator_biasprm[a, 2] < 0.0 and model.actuator_biasprm[a, 1] == 0.0
        j = int(model.actuator_trnid[a, 0])
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        if is_velocity and name in ARM_JOINTS and model.actuator_ctrllimited[a]:
            lo, hi = model.actuator_ctrlrange[a]
            if lo == -hi and hi > 0:
                out[ARM_JOINTS.index(name)] = hi
    if np.any(np.isnan(out)):
        missing = [ARM_JOINTS[i] for i in np.flatnonzero(np.isnan(out))]
        raise PlannerError(f"no velocity actuator with a symmetric ctrlrange for {missing}")
    return out


@cache
def _robot_facts() -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    model = mujoco.MjModel.from_xml_path(str(ROBOT_XML))
    lo, hi = joint_ranges(model)
    speed = joint_speed_limits(model)
    return tuple(map(float, lo)), tuple(map(float, hi)), tuple(map(float, speed))


def robot_joint_lower() -> tuple[float, ...]:
    """Lower joint ranges of the bundled robot model [rad] (6,)."""
    return _robot_facts()[0]


def robot_joint_upper() -> tuple[float, ...]:
    """Upper joint ranges of the bundled robot model [rad] (6,)."""
    return _robot_facts()[1]


def robot_joint_speeds() -> tuple[float, ...]:
    """Axis speed limits of the bundled robot model [rad/s] (6,)."""
    return _robot_facts()[2]


def _joint_id(model: mujoco.MjModel, name: str) -> int:
    j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
    if j < 0:
        raise PlannerError(f"the model has no joint {name!r}; arm joints: {list(ARM_JOINTS)}")
    return int(j)


__all__ = [
    "ARM_JOINTS",
    "ROBOT_XML",
    "joint_ranges",
    "joint_speed_limits",
    "robot_joint_lower",
    "robot_joint_speeds",
    "robot_joint_upper",
]
