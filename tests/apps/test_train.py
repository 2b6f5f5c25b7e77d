"""apps.train: a few hundred PPO steps on the tiny preset; artefacts; reload and predict."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from stable_baselines3 import PPO

from agents.learning.algorithms import AlgorithmError, algorithm_class
from agents.learning.wrappers import FlatDiscreteActions
from apps.train import (
    TrainError,
    load_train_config,
    main,
    pick_policy,
)
from configs import ConfigError

TINY = "configs/train/tiny.yaml"


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> tuple[Path, object]:
    out = tmp_path_factory.mktemp("run")
    result = main(["--config", TINY, "--out", str(out), "--no-progress"])
    return out, result


def test_artefacts(run):
    out, result = run
    assert (out / "model.zip").is_file()
    assert sorted((out / "checkpoints").glob("model_*_steps.zip"))
    assert list((out / "tb").rglob("events.out.tfevents.*"))
    assert list((out / "monitor").glob("*.monitor.csv"))
    assert (out / "train_config.yaml").is_file() and (out / "summary.json").is_file()
    assert result.timesteps >= 256 and result.steps_per_s > 0
    # One row of reward-term sums per finished training episode, summed like the return.
    lines = (out / "reward_terms.csv").read_text().splitlines()
    head = lines[0].split(",")
    assert head[0] == "step" and "correct" in head and "failed_action" in head
    assert len(lines) - 1 == result.episodes >= 2
    assert set(result.last_terms) == set(head[1:])


def test_model_reloads_and_predicts(run):
    out, _ = run
    model = PPO.load(str(out / "model.zip"), device="cpu")
    cfg = load_train_config(out / "train_config.yaml")
    env = gym.make("envs:MosaicAssembly-v0", **dict(cfg.env))
    try:
        obs, _ = env.reset(seed=3)
        action, _ = model.predict(obs, deterministic=True)
        assert env.action_space.contains(np.asarray(action))
        again, _ = model.predict(obs, deterministic=True)
        assert np.array_equal(action, again)
    finally:
        env.close()


def test_config_is_strict(yaml_file):
    bad = yaml_file("algo: PPO\nlearning_rate: 0.1\n")
    with pytest.raises(ConfigError, match="unknown key"):
        load_train_config(bad)
    bad = yaml_file("env: {action_mod: joint}\n")
    with pytest.raises(ConfigError, match="action_mod"):
        load_train_config(bad)
    with pytest.raises(AlgorithmError, match="known"):
        algorithm_class("NOPE")
    assert algorithm_class("sac").__name__ == "SAC"
    with pytest.raises(TrainError, match="reach_shaping must be >= 0"):
        load_train_config(TINY, reach_shaping=-1.0)
    shaped = load_train_config("bench_sac_one_tile_joint_reach")
    assert shaped.reach_shaping > 0 and shaped.task == "MosaicOneTileJoint-v0"
    with pytest.raises(TrainError, match="actor_bc_weight must be >= 0"):
        load_train_config(TINY, actor_bc_weight=-1.0)
    rlpd = load_train_config("rlpd_one_tile")
    assert rlpd.actor_bc_weight > 0 and rlpd.actor_bc_decay_steps == 0
    with pytest.raises(TrainError, match=r"bc_std_fit must be one of \['mean', 'clipped'\]"):
        load_train_config(TINY, bc_std_fit="median")
    assert load_train_config(TINY, bc_std_fit="clipped").bc_std_fit == "clipped"


def test_policy_choice():
    d = spaces.Dict({"a": spaces.Box(-1, 1, (3,))})
    assert pick_policy("auto", d) == "MultiInputPolicy"
    assert pick_policy("auto", spaces.Box(0, 255, (64, 64, 3), np.uint8)) == "CnnPolicy"
    assert pick_policy("auto", spaces.Box(-1, 1, (3,))) == "MlpPolicy"


def test_flat_discrete_actions_round_trip():
    env = FlatDiscreteActions(
        gym.make(
            "envs:MosaicAssembly-v0",
            max_slots=2,
            action_mode="pick_place_discrete",
            obs_mode="state",
            execution="kinematic",
        )
    )
    try:
        assert env.action_space == spaces.Discrete(2 * 2 * 4)
        for k in range(env.action_space.n):
            assert env.flat(env.action(k)) == k
        assert env.action(5).tolist() == [0, 1, 1]
        env.reset(seed=0)
        env.step(env.flat(np.array([0, 0, 0])))
    finally:
        env.close()
    with pytest.raises(TypeError, match="MultiDiscrete"):
        FlatDiscreteActions(gym.make("CartPole-v1"))
