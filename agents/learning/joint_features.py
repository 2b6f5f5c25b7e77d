"""Joint-space servo features: the tool-space vectors a servo acts on, through the arm's Jacobian.

A joint-action policy must turn "the tile is 3 cm to the left of the tool" into six joint
moves, a function of the arm's configuration that a small network learns slowly from a few
thousand demonstrations. These features hand it the joint-space image of each vector instead:
at the observed joint angles, one damped least-squares step of the arm's own kinematic model
(`planners.tool_step_ik.ToolStepIK.servo_steps`, the public ``assets/irb140/irb140.xml``; the
env hands out nothing new) for

- the tile's position minus the tool's (x, y, z) [m] (reach and descend),
- the slot's (x, y) minus the tile's [m] (carry),
- the turn that levels the tool (pointing straight down at its observed yaw),

each (6,) [rad], and the first two also squashed at fine scales, tanh(dq / s) for s in
`FINE_JOINT_SCALES` [rad] (within a few millimetres of a target, where the seal and the
placement are decided). `agents.learning.obs_norm.NormalizedStateExtractor` appends them with
``joint_space: true``.
"""

from __future__ import annotations

import numpy as np
import torch

from envs.observations.fields import ROBOT_FIELDS, SLOT_DIM, TILE_DIM

JOINT_POS = ROBOT_FIELDS["joint_pos"]
TOOL_POS = ROBOT_FIELDS["tool_pos"]
TOOL_YAW = ROBOT_FIELDS["tool_yaw"]
FINE_JOINT_SCALES = (0.003, 0.015)
"""Scales [rad] of the fine copies tanh(dq / s) of the reach and carry steps (at the arm's
0.5-0.8 m reach, about 2 and 10 mm at the tool)."""
JOINT_FEATURES_DIM = 3 * 6 + 2 * 6 * len(FINE_JOINT_SCALES)
"""Features appended: reach, carry and level steps (6 each) and the fine copies of the first two."""


class JointServoFeatures:
    """Computes the features of a batch of ``state`` observations (numpy, one arm model)."""

    def __init__(self) -> None:
        from planners.tool_step_ik import ToolStepIK  # noqa: PLC0415 - MuJoCo model load

        self.ik = ToolStepIK()

    def __call__(self, observations: dict[str, torch.Tensor]) -> torch.Tensor:
        """Features of a batch, shape (B, `JOINT_FEATURES_DIM`) float32."""
        robot = observations["robot"].detach().double().cpu().numpy()
        tile = observations["tiles"][:, :TILE_DIM].detach().double().cpu().numpy()
        slot = observations["slots"][:, :SLOT_DIM].detach().double().cpu().numpy()
        n = len(robot)
        errors = np.zeros((n, 2, 4))
        errors[:, 0, :3] = tile[:, :3] - robot[:, TOOL_POS]
        errors[:, 1, :2] = slot[:, :2] - tile[:, :2]
        yaw = np.arctan2(robot[:, TOOL_YAW.start + 1], robot[:, TOOL_YAW.start])
        steps = np.stack(
            [self.ik.servo_steps(robot[i, JOINT_POS], errors[i], yaw[i]) for i in range(n)]
        )
        moves = steps[:, :2].reshape(n, 12)
        fine = [np.tanh(moves / s) for s in FINE_JOINT_SCALES]
        out = np.concatenate([steps.reshape(n, 18), *fine], axis=1)
        return torch.as_tensor(out, dtype=torch.float32)


__all__ = ["FINE_JOINT_SCALES", "JOINT_FEATURES_DIM", "JointServoFeatures"]
