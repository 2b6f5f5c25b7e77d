"""Input belt: surface speed carries tiles, tiles past the end are lost, stream/batch feeding."""

from __future__ import annotations

import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.config import CellConfig, InputBeltConfig, TileConfig, load_cell_config
from envs.cell.tiles.shapes import basic_shapes, tile_shapes_from_design
from envs.errors import CellError
from qshape.design import Design


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


def _take_away(cell: Cell, idx: np.ndarray) -> None:
    """Lift tiles off the input belt onto the floor far away (as if picked and carried off)."""
    qadr = cell.ids.tile_qpos_index[idx]
    cell.data.qpos[qadr[:, 0]] = -3.0 - 0.3 * np.arange(len(idx))
    cell.data.qpos[qadr[:, 1]] = -3.0
    cell.data.qpos[qadr[:, 2]] = cell.cfg.tiles.thickness / 2 + 1e-3
    cell.data.qvel[cell.ids.tile_dof_index[idx]] = 0.0


def test_batch_feeding_indexes_the_next_batch_once_no_real_tile_is_left() -> None:
    shapes, slots = tile_shapes_from_design(Design.load("hexagon"))
    cfg = load_cell_config(
        tiles={"feed": "batch", "batch_size": 10, "batch_index_time": 0.3, "distractor_rate": 0.2}
    )
    cell = Cell(cfg, shapes, slots, seed=3)
    try:
        n = len(cell.tiles)
        first = cell.on_stage.copy()
        assert first.sum() == 10 and n > 20
        real, fake = first & ~cell.is_distractor, first & cell.is_distractor
        assert fake.any(), "seed 3 puts a distractor into the first batch"
        cell.step(100)
        _take_away(cell, np.flatnonzero(real)[1:])  # one real tile left: the batch stays
        dt = cell.model.opt.timestep

        def wait(seconds: float) -> None:
            for _ in range(round(seconds / (5 * dt))):
                cell.step(5)

        wait(1.0)
        assert np.array_equal(cell.on_stage, first)
        _take_away(cell, np.flatnonzero(real)[:1])
        wait(0.25)  # < batch_index_time
        assert np.array_equal(cell.on_stage, first)
        wait(0.1)
        second = cell.on_stage & ~first
        assert 0 < second.sum() <= 10
        assert np.array_equal(cell.retired, fake), "leftover distractors leave with the batch"
        assert not (cell.on_stage & fake).any()
        cell.step(100)
        pos = cell.tile_poses().pos[second]
        assert np.all(np.abs(pos[:, 2] - cell.geometry.belt_top - 0.0025) < 1e-3)
        assert np.all(np.abs(pos[:, 1] - cell.geometry.input_y) < cfg.input_belt.tile_area[1] / 2)
        assert cell.warnings() == 0 and cell.n_lost == real.sum()  # the taken ones: on the floor
    finally:
        cell.close()
