"""The scripted joint-mode controller places the one-tile task's tile through the arm's joints."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401 - registers the ids
from agents.errors import AgentError
from agents.experts.cartesian import HELD
from agents.experts.joint import LowLevelJointExpert, load_joint_expert_config
from configs import ConfigError

TASK = "MosaicOneTileJoint-v0"
SEED = 1010
"""A held-out seed of MosaicOneTileJoint-v0 (85 steps)."""


def test_joint_expert_seals_carries_and_places_the_tile():
    env = gym.make(TASK)
    expert = LowLevelJointExpert(env)
    obs, _ = env.reset(seed=SEED)
    start = obs["tiles"][:2].copy()
    held_steps, done, info = 0, False, {}
    while not done:
        action = expert.act(obs)
        assert action.shape == (7,) and np.all(np.abs(action) <= 1.0)
        obs, _, terminated, truncated, info = env.step(action)
        held_steps += int(obs["robot"][HELD] > 0.5)
        done = terminated or truncated
    env.close()
    ev = info["evaluation"]
    assert terminated and info["is_success"]
    assert held_steps > 20  # sealed, then carried round the front of the robot
    assert np.linalg.norm(obs["tiles"][:2] - start) > 0.5  # the tile crossed the cell
    assert ev["position_error_mm"] < 1.5 and ev["yaw_error_deg"] < 2.0
    assert ev["dropped"] == 0 and ev["misplaced"] == 0


@pytest.mark.parametrize(
    "override", [{"damping": -0.01}, {"tool_step": 0.0}, {"iterations": 0}, {"phases": ""}]
)
def test_bad_settings_raise_an_agent_error(override):
    with pytest.raises(AgentError, match="LowLevelJointExpertConfig"):
        load_joint_expert_config(**override)


def test_unknown_or_mistyped_keys_are_config_errors():
    with pytest.raises(ConfigError, match="gain"):
        load_joint_expert_config(gain=1.0)
    with pytest.raises(ConfigError, match="damping"):
        load_joint_expert_config(damping="small")


def test_joint_expert_refuses_other_action_modes():
    env = gym.make("MosaicOneTile-v0")
    with pytest.raises(AgentError, match="'joint'"):
        LowLevelJointExpert(env)
    env.close()


@pytest.mark.slow  # about 5 s: one episode recorded, written and replayed
def test_joint_demonstrations_record_and_replay_exactly(tmp_path):
    pytest.importorskip("minari")
    from apps.record_demos import load, record, replay  # noqa: PLC0415

    rec = record(1, seed=0, root=tmp_path, dataset_id="test/joint-v0", task=TASK, lowlevel=True)
    assert rec.episodes == 1 and rec.success_rate == 1.0
    dataset = load("test/joint-v0", tmp_path)
    assert dataset.action_space.shape == (7,)
    rep = replay(dataset)
    assert rep.matching_episodes == 1 and rep.replayed_success == 1
