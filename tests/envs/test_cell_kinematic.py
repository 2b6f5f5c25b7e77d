"""Kinematic mode (set_qpos) carries a held tile and agrees with the dynamic execution."""

from __future__ import annotations

import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.tiles.shapes import basic_shapes
from tests.envs.cell_motion import ArmIK, pick, place, tool_down, world_grasp

SHAPES = basic_shapes()


def _kinematic_pick_place(
    cell: Cell, ik: ArmIK, i: int, target: tuple[float, float, float]
) -> None:
    t = cell.cfg.tiles.thickness
    p, yaw = world_grasp(cell, i)
    q_touch = ik.solve(p + [0, 0, 0.0005], tool_down(yaw), cell.qpos)
    cell.set_qpos(q_touch)
    cell.vacuum(True)
    assert cell.held_tile == i
    g = cell.tiles[i].grasp
    c, s = np.cos(target[2]), np.sin(target[2])
    goal = np.array(
        [
            target[0] + c * g[0] - s * g[1],
            target[1] + s * g[0] + c * g[1],
            cell.geometry.mesh_top + t + 0.0005,
        ]
    )
    q_above = ik.solve(goal + [0, 0, 0.05], tool_down(target[2]), q_touch)
    for a in np.linspace(0, 1, 20):  # a straight joint-space sweep, no dynamics
        cell.set_qpos((1 - a) * q_touch + a * q_above)
    cell.set_qpos(ik.solve(goal, tool_down(target[2]), q_above))
    cell.vacuum(False)
    cell.set_qpos(q_above)
    cell.step(250)  # the released tile settles under physics


@pytest.mark.parametrize("i", [0, 3, 6], ids=["square", "l_shape", "ring"])
def test_kinematic_and_dynamic_outcomes_agree(i: int) -> None:
    results = []
    for mode in ("dynamic", "kinematic"):
        cell = Cell(None, SHAPES, seed=3)
        ik = ArmIK(cell)
        target = (cell.geometry.output_centre[0] + 0.03, cell.geometry.output_centre[1], 0.7)
        try:
            if mode == "dynamic":
                assert pick(cell, ik, i)
                place(cell, ik, i, target, cell.geometry.mesh_top)
                cell.step(250)
            else:
                _kinematic_pick_place(cell, ik, i, target)
            pose = cell.tile_poses()
            results.append(np.array([pose.pos[i, 0], pose.pos[i, 1], pose.yaw[i]]))
            assert np.hypot(*(results[-1][:2] - target[:2])) < 1e-3
            assert cell.warnings() == 0 and cell.n_dropped == 0
        finally:
            cell.close()
    diff = results[0] - results[1]
    assert np.hypot(diff[0], diff[1]) < 1e-3
    assert abs(np.degrees((diff[2] + np.pi) % (2 * np.pi) - np.pi)) < 1.0


def test_set_qpos_moves_the_arm_exactly() -> None:
    cell = Cell(None, SHAPES[:1], seed=0)
    try:
        q = np.array([0.3, 0.2, -0.4, 0.5, 1.1, -0.6])
        cell.set_qpos(q)
        assert np.array_equal(cell.qpos, q) and np.all(cell.qvel == 0)
        cell.step(50)  # the servo holds it
        assert np.max(np.abs(cell.qpos - q)) < np.radians(0.05)
    finally:
        cell.close()
