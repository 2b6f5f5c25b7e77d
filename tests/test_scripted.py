"""The scripted agent driving MosaicAssembly-v0 through its public API (pick_place actions)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from agents.errors import AgentError
from agents.scripted import ScriptedAgent

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
    agent = ScriptedAgent(env)
    assert agent.calibration is not None and agent.calibration.reprojection_px < 0.5
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

    agent = ScriptedAgent(env, calibrate=False)
    mean, _ = evaluate_policy(agent, env, n_eval_episodes=1, warn=False)
    assert mean > 0


def test_wrong_action_mode():
    e = gym.make("envs:MosaicAssembly-v0", action_mode="joint", max_slots=2)
    try:
        with pytest.raises(AgentError, match="pick_place"):
            ScriptedAgent(e, calibrate=False)
    finally:
        e.close()


def test_a_tile_still_on_the_belt_reopens_its_slot(env):
    """Same picture twice (as after a failed pick): the same slot is commanded again."""
    agent = ScriptedAgent(env, calibrate=False, replan_every_step=True)
    obs, _ = env.reset(seed=1)
    first, _ = agent.predict(obs, episode_start=np.array([True]))
    slot = agent.order[-1]
    again, _ = agent.predict(obs)
    assert agent.order[-1] == slot
    np.testing.assert_allclose(again, first, atol=1e-6)
