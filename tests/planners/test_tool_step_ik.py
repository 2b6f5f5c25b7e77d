"""Small tool-down moves mapped onto the joints by damped least squares on the arm model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.errors import InvalidTargetError, LimitError
from planners.tool_step_ik import ToolStepConfig, ToolStepIK
from spatial.rotations import yaw_from_matrix

HOME = np.array([0.0, 0.0, 0.0, 0.0, math.pi / 2, 0.0])
"""The cell's home posture [rad]: the tool pointing down at (0.45, 0, 0.547) m."""


@pytest.fixture(scope="module")
def ik() -> ToolStepIK:
    return ToolStepIK()


def test_home_points_the_tool_down(ik: ToolStepIK) -> None:
    pos, rot = ik.tool_pose(HOME)
    np.testing.assert_allclose(pos, [0.45, 0.0, 0.547], atol=1e-6)
    np.testing.assert_allclose(rot[:, 2], [0.0, 0.0, -1.0], atol=1e-9)


@pytest.mark.parametrize(
    ("move", "turn"),
    [
        ([0.02, 0.0, 0.0], 0.0),
        ([0.0, -0.02, 0.0], 0.0),
        ([0.0, 0.0, -0.02], 0.12),
        ([0.01] * 3, -0.1),
    ],
)
def test_one_control_period_move_lands_on_the_target(
    ik: ToolStepIK, move: list[float], turn: float
) -> None:
    pos, _ = ik.tool_pose(HOME)
    target = pos + np.asarray(move)
    q = ik.move(HOME, target, turn)
    reached, rot = ik.tool_pose(q)
    assert np.linalg.norm(reached - target) < 1e-4  # 0.1 mm
    assert math.degrees(math.acos(min(1.0, -rot[2, 2]))) < 0.1  # still pointing down
    assert abs(yaw_from_matrix(rot) - turn) < math.radians(0.1)


def test_repeated_moves_carry_the_tool_across_the_cell(ik: ToolStepIK) -> None:
    """20 mm steps from home to above the mesh side, each from the posture the last one reached."""
    q, goal = HOME.copy(), np.array([0.2, -0.4, 0.3])
    for _ in range(40):
        pos, _ = ik.tool_pose(q)
        err = goal - pos
        step = err * min(1.0, 0.02 / max(float(np.linalg.norm(err)), 1e-12))
        q = ik.move(q, pos + step, 0.0)
    pos, rot = ik.tool_pose(q)
    assert np.linalg.norm(pos - goal) < 1e-3
    assert rot[2, 2] < -0.9999
    assert np.all(q >= ik.lower) and np.all(q <= ik.upper)


def test_bad_inputs_and_settings_raise_typed_errors(ik: ToolStepIK) -> None:
    with pytest.raises(InvalidTargetError, match="shape"):
        ik.move(HOME[:5], [0.4, 0.0, 0.5], 0.0)
    with pytest.raises(InvalidTargetError, match="non-finite"):
        ik.move(HOME, [0.4, np.nan, 0.5], 0.0)
    with pytest.raises(LimitError, match="damping"):
        ToolStepConfig(damping=-1.0)
    with pytest.raises(LimitError, match="iterations"):
        ToolStepConfig(iterations=0)
