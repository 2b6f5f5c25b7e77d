"""The scripted low-level controller seals, carries and places the one-tile task's tile."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401 - registers the ids
from agents.errors import AgentError
from agents.experts.cartesian import HELD, LowLevelExpert

SEED = 1000
"""A held-out seed of MosaicOneTile-v0 (its tile must turn by about 4 degrees)."""


def test_expert_seals_carries_and_places_the_tile():
    env = gym.make("MosaicOneTile-v0")
    expert = LowLevelExpert(env)
    obs, _ = env.reset(seed=SEED)
    start = obs["tiles"][:2].copy()
    held_steps, done, info = 0, False, {}
    while not done:
        obs, _, terminated, truncated, info = env.step(expert.act(obs))
        held_steps += int(obs["robot"][HELD] > 0.5)
        done = terminated or truncated
    env.close()
    ev = info["evaluation"]
    assert terminated and info["is_success"]
    assert held_steps > 20  # sealed, then carried about a metre at 0.5 m/s
    assert np.linalg.norm(obs["tiles"][:2] - start) > 0.5  # the tile crossed the cell
    assert ev["position_error_mm"] < 1.5 and ev["yaw_error_deg"] < 2.0
    assert ev["dropped"] == 0 and ev["misplaced"] == 0


def test_expert_refuses_other_action_modes():
    env = gym.make("MosaicOneTileJoint-v0")
    with pytest.raises(AgentError, match="cartesian"):
        LowLevelExpert(env)
    env.close()
