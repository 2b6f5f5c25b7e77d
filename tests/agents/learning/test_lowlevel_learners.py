"""The low-level learned rows: DART recording, normalised observations, BC clone, residual RL.

Each learner trains for seconds on a fixed seed and must beat the random policy there (through
``agents.policies``, the path ``apps.evaluate`` plays checkpoints by).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

pytest.importorskip("minari")

import envs  # noqa: E402,F401 - registers the ids
from agents.errors import AgentError  # noqa: E402
from agents.learning.dart import NoisyExecution  # noqa: E402
from agents.learning.demos import load_demos  # noqa: E402
from agents.learning.obs_norm import NormalizedStateExtractor, feature_stats  # noqa: E402
from agents.policies import make_policy  # noqa: E402
from apps.evaluate import evaluate_policy_set  # noqa: E402
from apps.record_demos import record  # noqa: E402
from apps.train import TrainConfig, train  # noqa: E402

TASK = "MosaicOneTile-v0"
DATASET = "test/one-tile-dart-v0"
SEED = 1000
"""The fixed held-out seed the learners are played on."""
EPISODES = 12
"""Demonstrations recorded for the tests (about 2000 steps)."""


@pytest.fixture(scope="module")
def dart_root(tmp_path_factory):
    """DART episodes of the continuous-descent controller (noise 0.02 + 0.5 |a|), seeds 0..."""
    torch.set_num_threads(1)
    root = tmp_path_factory.mktemp("minari")
    rec = record(
        EPISODES,
        seed=0,
        root=root,
        dataset_id=DATASET,
        lowlevel=True,
        action_noise=0.02,
        noise_relative=0.5,
        expert_config="lowlevel_expert_smooth",
    )
    assert rec.episodes == EPISODES
    return root


def _play(model_path, seed: int = SEED) -> tuple[float, float]:
    """(success, return) of a checkpoint on one seed, as apps.evaluate plays it."""
    from envs.tasks import get_task  # noqa: PLC0415

    task = get_task(TASK)
    pol = make_policy(str(model_path), task.env_kwargs("eval"))
    _, per = evaluate_policy_set([pol], [seed], max_steps=task.max_episode_steps)
    ep = per[pol.label][0]
    return float(ep.success), float(ep.episode_return)


def _random_return(seed: int = SEED) -> float:
    from envs.tasks import get_task  # noqa: PLC0415

    pol = make_policy("random", get_task(TASK).env_kwargs("eval"))
    _, per = evaluate_policy_set([pol], [seed], max_steps=200)
    return float(per["random"][0].episode_return)


def test_noisy_execution_moves_the_tool_off_the_clean_path():
    clean, noisy = gym.make(TASK), NoisyExecution(gym.make(TASK), 0.5, seed=3)
    a, _ = clean.reset(seed=0)
    b, _ = noisy.reset(seed=0)
    assert np.array_equal(a["robot"], b["robot"])
    action = np.array([0.5, 0.0, 0.0, 0.0, -1.0], np.float32)
    a = clean.step(action)[0]
    b = noisy.step(action)[0]
    assert not np.allclose(a["robot"][12:15], b["robot"][12:15], atol=1e-4)
    with pytest.raises(AgentError, match="sigma"):
        NoisyExecution(gym.make(TASK), -0.1)
    clean.close()
    noisy.close()


def test_extractor_standardises_the_demonstrations(dart_root):
    env = gym.make(TASK)
    demos = load_demos(DATASET, env.observation_space, env.action_space, dart_root)
    stats = feature_stats(demos.observations, env.observation_space, relative=True)
    ext = NormalizedStateExtractor(env.observation_space, relative=True, **stats)
    obs = {k: torch.as_tensor(v) for k, v in demos.observations.items()}
    x = ext(obs).numpy()
    varying = np.asarray(stats["std"]) > 1e-3
    assert np.allclose(x[:, varying].mean(0), 0.0, atol=1e-3)
    assert np.allclose(x[:, varying].std(0), 1.0, atol=1e-2)
    with pytest.raises(AgentError, match="features are"):
        NormalizedStateExtractor(env.observation_space, mean=[0.0, 1.0])
    env.close()


def test_behaviour_clone_beats_random_on_a_fixed_seed(dart_root, tmp_path, monkeypatch):
    monkeypatch.setattr("apps.train.DEMO_ROOT", dart_root)
    cfg = TrainConfig(
        task=TASK,
        algo="SAC",
        total_timesteps=1,
        demos=DATASET,
        normalize_obs=True,
        bc_epochs=200,
        algo_kwargs={"buffer_size": 100, "learning_starts": 100},
        policy_kwargs={"net_arch": [64, 64], "features_extractor_kwargs": {"relative": True}},
        checkpoint_freq=0,
        tensorboard=False,
        progress_bar=False,
        log_every_s=0,
    )
    result = train(cfg, tmp_path / "bc")
    _, clone_return = _play(result.model_path)
    assert clone_return > _random_return() + 0.3  # the clone reaches the tile at least


def test_residual_policy_trains_and_plays_at_the_controllers_level(tmp_path):
    cfg = TrainConfig(
        task=TASK,
        algo="SAC",
        policy="agents.learning.residual:ResidualSACPolicy",
        total_timesteps=300,
        residual_scale=0.05,
        hold_actor_steps=300,
        algo_kwargs={"learning_starts": 100, "batch_size": 64, "buffer_size": 1000},
        policy_kwargs={"net_arch": [64, 64]},
        checkpoint_freq=0,
        tensorboard=False,
        progress_bar=False,
        log_every_s=0,
    )
    result = train(cfg, tmp_path / "residual")
    assert result.gradient_steps > 0
    success, ret = _play(result.model_path)
    assert success == 1.0 and ret > _random_return() + 10.0
