"""A moving input belt: it carries tiles, and pick_place cycles catch them on the move."""

from __future__ import annotations

import numpy as np
import pytest

from envs.mosaic_env import MosaicAssemblyEnv

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
