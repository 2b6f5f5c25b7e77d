"""The belts: the input belt's surface speed carries tiles, tiles past the end are lost,
stream/batch feeding; in the env a moving input belt carries tiles and pick_place cycles catch
them on the move."""

from __future__ import annotations

import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.config import CellConfig, InputBeltConfig, TileConfig, load_cell_config
from envs.cell.tiles.shapes import basic_shapes, tile_shapes_from_design
from envs.errors import CellError
from envs.mosaic_env import MosaicAssemblyEnv
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


BELT_SPEED = 0.1
"""Input belt speed of these tests [m/s] (the paper's cell)."""
N_TILES = 6
"""Tiles picked from the moving belt and placed."""
MIN_TRAVEL = 0.03
"""Belt travel of a tile between choosing the action and the pad's contact, at least [m]."""


def test_belt_carries_an_unheld_tile_at_its_speed() -> None:
    env = MosaicAssemblyEnv(
        action_mode="joint",
        obs_mode="state",
        belt_speed=BELT_SPEED,
        feed="stream",
        stream_initial=1,
        max_slots=2,
    )
    try:
        env.reset(seed=0)
        cell = env.cell
        tile = int(np.flatnonzero(cell.on_stage)[0])
        start, t0 = cell.tile_poses().pos[tile].copy(), cell.time
        for _ in range(25):  # 1 s
            env.step(np.zeros(7, np.float32))
        moved = cell.tile_poses().pos[tile] - start
        expected = BELT_SPEED * (cell.time - t0)
        assert moved[0] == pytest.approx(expected, rel=0.05)
        assert abs(moved[1]) < 1e-3 and abs(moved[2]) < 1e-3
        assert cell.warnings() == 0
    finally:
        env.close()


def _next_tile(env: MosaicAssemblyEnv) -> int:
    """The fed tile farthest downstream on the input belt (waiting, arm still, for a feed)."""
    cell = env.cell
    wait = round(env.config.control_dt / cell.model.opt.timestep)
    for _ in range(round(env.config.cell.tiles.stream_period / env.config.control_dt) + 1):
        on_input = cell.on_stage & ~cell.lost & ~env.task.placement().on_mesh
        candidates = np.flatnonzero(on_input)
        if len(candidates):
            return int(candidates[np.argmax(cell.tile_poses().pos[candidates, 0])])
        cell.step(wait)
    raise AssertionError(f"no tile fed within a stream period (t = {cell.time:.2f} s)")


def test_dynamic_pick_place_from_a_moving_belt() -> None:
    env = MosaicAssemblyEnv(
        design="paper_mixed",
        action_mode="pick_place",
        execution="dynamic",
        obs_mode="state",
        belt_speed=BELT_SPEED,
        feed="stream",
    )
    try:
        env.reset(seed=0)
        cell = env.cell
        placed: list[int] = []
        for k in range(N_TILES):
            tile = _next_tile(env)
            t_choice = cell.time
            _, reward, _, _, info = env.step(env.expert_action(tile, tile))
            ev = info["evaluation"]
            assert not info["action_failed"], info["action_error"]
            events = [e for e in cell.events if e.tile == tile]
            assert [e.kind for e in events] == ["grasp", "release"]
            # The belt carried the tile on by centimetres between the choice and the contact:
            # the pad met it where the planner predicted.
            assert BELT_SPEED * (events[0].time - t_choice) > MIN_TRAVEL
            assert ev["correct"] == k + 1, (k, tile, ev)
            assert ev["misplaced"] == ev["dropped"] == ev["lost"] == 0
            assert reward == pytest.approx(env.config.reward_correct)
            placed.append(tile)
        p = env.task.placement()
        assert np.all(p.correct[placed])
        assert np.nanmax(p.position_error[placed]) <= env.config.position_tolerance
        assert np.degrees(np.nanmax(p.yaw_error[placed])) <= env.config.yaw_tolerance_deg
        assert cell.n_dropped == 0 and cell.n_lost == 0 and cell.warnings() == 0
        assert info["sim_time"] > N_TILES * 2.0  # dynamic cycles, not kinematic jumps
    finally:
        env.close()
