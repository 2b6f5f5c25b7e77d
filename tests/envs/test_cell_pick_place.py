"""Scripted straight-down pick and place of every test shape through fast moves, and the kinematic
mode (set_qpos), which carries a held tile and agrees with the dynamic execution."""

from __future__ import annotations

import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.config import load_cell_config
from envs.cell.tiles.shapes import basic_shapes
from tests.envs.cell_motion import ArmIK, ArmIKFor, pick, place, tool_down, world_grasp

SHAPES = basic_shapes()


@pytest.fixture
def cell() -> Cell:
    """A fresh cell per test: a test's outcome must not depend on which ran before it."""
    c = Cell(None, SHAPES, seed=3)
    yield c
    c.close()


@pytest.fixture
def ik(cell: Cell, arm_ik: ArmIKFor) -> ArmIK:
    return arm_ik(cell)


@pytest.mark.parametrize("i", range(len(SHAPES)), ids=[s.name for s in SHAPES])
def test_pick_hold_fast_move_and_place(cell: Cell, ik: ArmIK, i: int) -> None:
    assert cell.tiles[i].shape.name == SHAPES[i].name
    assert pick(cell, ik, i), f"{SHAPES[i].name} not held after lifting"
    assert cell.vacuum_on and cell.tile_held
    x = cell.geometry.output_centre[0] - 0.09 + 0.03 * i
    y = cell.geometry.output_centre[1] + 0.05 * (i % 2)
    yaw = 0.4 * i - 1.2
    drops = cell.n_dropped
    peak = place(cell, ik, i, (x, y, yaw), cell.geometry.mesh_top, speed_scale=0.95)
    assert peak > 1.0, "the transfer was not a fast move"
    assert cell.n_dropped == drops, "tile dropped during the fast move"
    assert not cell.vacuum_on and not cell.tile_held and cell.held_tile == -1
    cell.step(250)  # settle 0.5 s after the pad left
    poses = cell.tile_poses()
    assert np.hypot(poses.pos[i, 0] - x, poses.pos[i, 1] - y) < 1e-3
    yaw_err = (poses.yaw[i] - yaw + np.pi) % (2 * np.pi) - np.pi
    assert abs(np.degrees(yaw_err)) < 1.0
    assert poses.pos[i, 2] == pytest.approx(
        cell.geometry.mesh_top + cell.cfg.tiles.thickness / 2, abs=5e-4
    )
    assert [e.kind for e in cell.events[-2:]] == ["grasp", "release"]
    assert cell.warnings() == 0


@pytest.mark.parametrize("name", ["square", "ring"])
def test_compact_layout_pick_and_place(name: str, arm_ik: ArmIKFor) -> None:
    cfg = load_cell_config(
        layout={"belt_separation": 0.5, "work_x": 0.5}, input_belt={"length": 0.6}
    )
    shapes = [s for s in SHAPES if s.name == name]
    cell = Cell(cfg, shapes, seed=2)
    ik = arm_ik(cell)
    try:
        assert pick(cell, ik, 0)
        target = (cell.geometry.output_centre[0] + 0.1, cell.geometry.output_centre[1] - 0.1, 2.0)
        assert place(cell, ik, 0, target, cell.geometry.mesh_top) > 1.0
        cell.step(250)
        pose = cell.tile_poses()
        assert np.hypot(pose.pos[0, 0] - target[0], pose.pos[0, 1] - target[1]) < 1e-3
        assert cell.n_dropped == 0 and cell.warnings() == 0
    finally:
        cell.close()


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
def test_kinematic_and_dynamic_outcomes_agree(i: int, arm_ik: ArmIKFor) -> None:
    results = []
    for mode in ("dynamic", "kinematic"):
        cell = Cell(None, SHAPES, seed=3)
        ik = arm_ik(cell)
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
