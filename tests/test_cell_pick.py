"""Scripted straight-down pick and place of every test shape through fast moves."""

from __future__ import annotations

import numpy as np
import pytest
from cell_motion import ArmIK, pick, place

from envs.cell import Cell
from envs.tiles import basic_shapes

SHAPES = basic_shapes()


@pytest.fixture(scope="module")
def cell() -> Cell:
    c = Cell(None, SHAPES, seed=3)
    yield c
    c.close()


@pytest.fixture(scope="module")
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
