"""Input belt: surface speed carries tiles, tiles past the end are lost, stream feeding."""

from __future__ import annotations

import numpy as np
import pytest

from envs.cell import Cell
from envs.cell_config import CellConfig, InputBeltConfig, TileConfig
from envs.errors import CellError
from envs.tiles import basic_shapes


def _cell(speed: float, **tiles: object) -> Cell:
    cfg = CellConfig(input_belt=InputBeltConfig(speed=speed), tiles=TileConfig(**tiles))
    return Cell(cfg, basic_shapes() * 2, seed=5)


@pytest.mark.parametrize("speed", [0.0, 0.05, 0.2])
def test_belt_moves_resting_tiles_at_its_speed(speed: float) -> None:
    cell = _cell(speed)
    try:
        cell.step(100)  # 0.2 s: tiles settle and pick up the belt's speed
        before = cell.tile_poses().pos
        cell.step(250)  # 0.5 s
        after = cell.tile_poses().pos
        assert cell.n_lost == 0
        v = (after - before) / 0.5
        if speed == 0.0:
            assert np.all(np.abs(v) < 1e-4)
        else:
            assert np.allclose(v[:, 0], speed, rtol=0.03)
            assert np.all(np.abs(v[:, 1]) < 0.03 * speed)
        assert cell.warnings() == 0
    finally:
        cell.close()


def test_belt_speed_changes_at_run_time() -> None:
    cell = _cell(0.0)
    try:
        cell.belt_speed = 0.1
        assert cell.belt_speed == 0.1
        cell.step(100)
        before = cell.tile_poses().pos
        cell.step(250)
        v = (cell.tile_poses().pos - before) / 0.5
        assert np.allclose(v[:, 0], 0.1, rtol=0.03)
        with pytest.raises(CellError, match=">= 0"):
            cell.belt_speed = -0.1
    finally:
        cell.close()


def test_tiles_past_the_end_fall_into_the_bin_and_are_lost() -> None:
    cell = _cell(0.3)
    try:
        n = len(cell.tiles)
        cell.step(1000)  # 2 s at 0.3 m/s: every tile travels 0.6 m > 0.45 m to the end
        assert cell.n_lost == n and cell.lost.all()
        pos = cell.tile_poses().pos
        geo = cell.geometry
        assert np.all(pos[:, 0] > geo.input_belt_end)
        assert np.all(pos[:, 2] < geo.belt_top - cell.cfg.input_belt.bin_depth + 0.02)
        assert cell.warnings() == 0
        cell.reset(seed=1)
        assert cell.n_lost == 0
    finally:
        cell.close()


def test_stream_feeding_spawns_tiles_over_time() -> None:
    cell = _cell(0.1, feed="stream", stream_period=0.5, stream_initial=2)
    try:
        assert cell.on_stage.sum() == 2
        for _ in range(152):  # 1.52 s in 10 ms control periods: spawns at 0.5, 1.0, 1.5 s
            cell.step(5)
        assert cell.on_stage.sum() == 5
        staged = cell.tile_poses().pos[cell.on_stage]
        assert np.all(np.abs(staged[:, 2] - cell.geometry.belt_top - 0.0025) < 1e-3)
        assert cell.n_lost == 0 and cell.warnings() == 0
    finally:
        cell.close()
