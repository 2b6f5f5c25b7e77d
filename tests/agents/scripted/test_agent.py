"""The scripted agent driving MosaicAssembly-v0 through its public API (pick_place actions).

A tile the pad drops over the input belt is counted on the input, then picked and placed: the
agent drives `pick_place` steps (dynamic execution: the cycle is tracked by the servos and the
vacuum's holding force is checked at every control period). The only privileged set-up is a
vacuum fault during the agent's first cycle: the pad's holding force is cut below a tile's
weight, so the pad drops the tile it just sealed on while lifting it off the input belt; the
force is restored after that step. The dropped tile must be counted on the input (placeable,
not dropped) and the agent must pick it again and place it in its slot."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401 - registers the env
from agents.errors import AgentError, CalibrationError
from agents.scripted.agent import ScriptedAgent
from agents.scripted.calibration import calibrate_env_camera
from envs.cell.accounting import TILE_STATES

FULL = (492, 656)


@pytest.fixture(scope="module")
def env():
    e = gym.make(
        "envs:MosaicAssembly-v0",
        action_mode="pick_place",
        image_size=FULL,
        execution="kinematic",
        max_slots=6,
    )
    yield e
    e.close()


def test_scripted_agent_fills_the_design(env):
    agent = ScriptedAgent.from_env(env)
    assert agent.calibration is not None and agent.calibration.reprojection_px < 0.5
    # The pictures were the env's own camera's, at the observation size.
    true, spec_cam = agent.calibration.true_camera, agent.spec.camera("input_camera")
    np.testing.assert_allclose(true.K, spec_cam.K)
    np.testing.assert_allclose(true.world_to_camera, spec_cam.world_to_camera, atol=1e-12)
    with pytest.raises(CalibrationError, match="allowed"):
        calibrate_env_camera(env, "top_camera")
    obs, _ = env.reset(seed=0)
    info = {}
    for step in range(20):
        action, _ = agent.predict(obs, episode_start=np.array([step == 0]))
        assert action.shape == (6,) and action.dtype == np.float32
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    ev = info["evaluation"]
    assert ev["success"] and ev["correct"] == ev["slots"] == 6
    assert ev["misplaced"] == 0 and ev["distractors_placed"] == 0


def test_evaluate_policy_accepts_it(env):
    from stable_baselines3.common.evaluation import evaluate_policy  # noqa: PLC0415

    agent = ScriptedAgent.from_env(env, calibrate=False)
    mean, _ = evaluate_policy(agent, env, n_eval_episodes=1, warn=False)
    assert mean > 0


def test_wrong_action_mode():
    e = gym.make("envs:MosaicAssembly-v0", action_mode="joint", max_slots=2)
    try:
        with pytest.raises(AgentError, match="pick_place"):
            ScriptedAgent.from_env(e, calibrate=False)
    finally:
        e.close()


def test_a_tile_still_on_the_belt_reopens_its_slot(env):
    """Same picture twice (as after a failed pick): the same slot is commanded again."""
    agent = ScriptedAgent.from_env(env, calibrate=False, replan_every_step=True)
    obs, _ = env.reset(seed=1)
    first, _ = agent.predict(obs, episode_start=np.array([True]))
    slot = agent.order[-1]
    again, _ = agent.predict(obs)
    assert agent.order[-1] == slot
    np.testing.assert_allclose(again, first, atol=1e-6)


def test_a_camera_that_sees_nothing_gives_a_harmless_rest_action(env):
    agent = ScriptedAgent.from_env(env, calibrate=False)
    obs, _ = env.reset(seed=3)
    cell = env.unwrapped.cell
    before = cell.tile_poses().pos.copy()
    dark = {**obs, "input_camera": np.zeros_like(obs["input_camera"])}
    action, _ = agent.predict(dark)
    assert agent.last_command is None and not agent.last_plan.commands
    _, _, _, _, info = env.step(action)
    assert info["action_failed"] and "no tile" in info["action_error"]
    moved = np.linalg.norm(cell.tile_poses().pos - before, axis=1)
    assert moved.max() < 1e-3  # the rest pick found empty belt: nothing moved
    assert info["evaluation"]["misplaced"] == info["evaluation"]["correct"] == 0


def test_rest_action_picks_away_from_every_tile_seen(env):
    agent = ScriptedAgent.from_env(env, calibrate=False)
    obs, _ = env.reset(seed=4)
    agent.plan(obs["input_camera"])
    pick, place = agent._idle_points()
    seen = np.array([t.centre for t in agent.last_perception.tiles])
    assert len(seen) == 6
    assert np.min(np.linalg.norm(seen - pick, axis=1)) > 0.03  # 3 cm from any tile centre
    slots = np.array([s.pose[:2] for s in agent.slots])
    assert np.min(np.linalg.norm(slots - place, axis=1)) > 0.02


def test_white_balance_history_is_the_episode_s(env):
    agent = ScriptedAgent.from_env(env, calibrate=False)
    obs, _ = env.reset(seed=1)
    agent.plan(obs["input_camera"])
    seen = len(agent.last_perception.tiles)
    assert seen > 0 and len(agent.colors) == seen  # every tile of the picture measured
    agent.plan(obs["input_camera"])  # a second picture adds to the history
    assert len(agent.colors) == min(2 * seen, agent.cfg.perception.color_history)
    agent.reset()
    assert len(agent.colors) == 0


FAULT_FORCE = 0.01
"""Holding force during the fault [N]: far less than a tile's weight (~0.19 N)."""


def _accounted(ev: dict) -> None:
    assert sum(ev[s] for s in TILE_STATES) == ev["fed"], ev


def test_a_tile_dropped_over_the_input_belt_is_picked_again_and_placed():
    env = gym.make(
        "envs:MosaicAssembly-v0",
        action_mode="pick_place",
        obs_mode="rgb",
        execution="dynamic",
        max_slots=2,
        image_size=(492, 656),
    )
    try:
        obs, info = env.reset(seed=0)
        cell = env.unwrapped.cell
        slots = info["evaluation"]["slots"]
        agent = ScriptedAgent.from_env(env)

        # The fault: the agent's first cycle seals on a tile, then the pad drops it.
        strong = cell.suction.holding_force
        cell.suction.holding_force = FAULT_FORCE
        action, _ = agent.predict(obs, episode_start=np.array([True]))
        obs, _, terminated, _, info = env.step(action)
        cell.suction.holding_force = strong
        assert [e.kind for e in cell.events] == ["grasp", "drop"]
        tile = cell.events[0].tile
        assert info["action_failed"]
        assert cell.input_side()[tile] and not cell.tile_held  # it lies on the input belt
        pick = env.unwrapped.pick_area
        rest_z = (pick.surface_z + pick.tile_top_z) / 2
        assert abs(cell.tile_poses().pos[tile][2] - rest_z) < 1e-3  # flat, at rest on it
        ev = info["evaluation"]
        assert (ev["on_input"], ev["dropped_tiles"], ev["dropped"]) == (slots, 0, 1)
        assert ev["placeable"] == slots and not terminated
        _accounted(ev)

        for _ in range(2 * slots):
            action, _ = agent.predict(obs)
            obs, _, terminated, truncated, info = env.step(action)
            _accounted(info["evaluation"])
            if terminated or truncated:
                break
        final = info["evaluation"]
        assert final["success"] and final["correct"] == final["slots"] == slots
        assert final["misplaced"] == 0 and final["dropped_tiles"] == 0
        # The dropped tile was sealed on again and released in its slot.
        assert [e.kind for e in cell.events if e.tile == tile] == [
            "grasp",
            "drop",
            "grasp",
            "release",
        ]
        assert not cell.was_dropped[tile]
    finally:
        env.close()


def test_the_scripted_agent_places_tiles_on_v1_unchanged():
    """``MosaicAssembly-v1``'s Box(5) pick_place layout: the agent encodes through the codec."""
    e = gym.make("envs:MosaicAssembly-v1", image_size=FULL, execution="kinematic", max_slots=2)
    try:
        assert e.action_space.shape == (5,)
        agent = ScriptedAgent.from_env(e, calibrate=False)
        obs, _ = e.reset(seed=0)
        info = {}
        for step in range(6):
            action, _ = agent.predict(obs, episode_start=np.array([step == 0]))
            assert action.shape == (5,)
            obs, _, terminated, truncated, info = e.step(action)
            if terminated or truncated:
                break
        assert info["evaluation"]["correct"] == 2
    finally:
        e.close()
