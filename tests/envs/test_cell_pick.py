"""Scripted straight-down pick and place of every test shape through fast moves."""

from __future__ import annotations

import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.config import load_cell_config
from envs.cell.tiles.shapes import basic_shapes
from tests.envs.cell_motion import ArmIK, pick, place

SHAPES = basic_shapes()


@pytest.fixture
def cell() -> Cell:
    """A fresh cell per test: a test's outcome must not depend on which ran before it."""
    c = Cell(None, SHAPES, seed=3)
    yield c
    c.close()


@pytest.fixture
def ik(cell: Cell) -> ArmIK:
    return ArmIK(cell)


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
def test_compact_layout_pick_and_place(name: str) -> None:
    cfg = load_cell_config(
        layout={"belt_separation": 0.5, "work_x": 0.5}, input_belt={"length": 0.6}
    )
    shapes = [s for s in SHAPES if s.name == name]
    cell = Cell(cfg, shapes, seed=2)
    ik = ArmIK(cell)
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
