"""Wrappers: RecordCycleVideo shows the motion inside each cycle; EpisodeRewardTerms sums terms."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401
from agents.errors import AgentError
from agents.learning.wrappers import (
    EPISODE_TERMS_KEY,
    EpisodeRewardTerms,
    ReachShaping,
    RecordCycleVideo,
)


def test_frames_from_inside_the_cycle_reach_the_video(tmp_path) -> None:
    env = gym.make(
        "MosaicAssembly-v0",
        max_slots=1,
        action_mode="pick_place_discrete",
        execution="dynamic",
        obs_mode="state",
        render_mode="rgb_array",
    )
    env = RecordCycleVideo(env, str(tmp_path / "video"), episode_trigger=lambda i: True)
    try:
        env.reset(seed=0)
        _, _, term, _, info = env.step(env.unwrapped.expert_action(0, 0))
        frames = len(env.recorded_frames)
        fps = env.metadata["render_fps"]
        assert info["is_success"] and term
        # One frame per 1/fps of the cycle's simulated time (plus reset's and the step's own).
        assert frames >= 0.9 * info["sim_time"] * fps > 20
    finally:
        env.close()
    assert list((tmp_path / "video").glob("*.mp4"))


def test_episode_reward_terms_sum_the_named_terms() -> None:
    env = EpisodeRewardTerms(gym.make("MosaicOneTile-v0", max_episode_steps=6))
    try:
        env.reset(seed=3)
        env.action_space.seed(3)
        total: dict[str, float] = {}
        rewards, done, info = 0.0, False, {}
        while not done:
            _, r, term, trunc, info = env.step(env.action_space.sample())
            rewards += float(r)
            done = term or trunc
            if not done:
                assert EPISODE_TERMS_KEY not in info
            for k, v in info.items():
                if k.startswith("reward_"):
                    total[k[7:]] = total.get(k[7:], 0.0) + float(v)
        sums = info[EPISODE_TERMS_KEY]
        assert set(sums) == set(total) and "stage_reach" in sums
        assert all(abs(sums[k] - total[k]) < 1e-9 for k in total)
        assert sums["stage_reach"] != 0.0  # random moves change the reach potential
        # A reset starts new sums.
        env.reset(seed=4)
        *_, info = env.step(env.action_space.sample())
        assert EPISODE_TERMS_KEY not in info
    finally:
        env.close()


def test_reach_shaping_pays_the_approach_and_telescopes() -> None:
    base = gym.make("MosaicOneTileJoint-v0", max_episode_steps=8)
    env = ReachShaping(base, weight=2.0)
    try:
        obs, _ = env.reset(seed=5)
        tool, tile = obs["robot"][12:15], obs["tiles"][:3]
        start = env.potential(obs)
        assert np.isclose(start, -2.0 * np.linalg.norm(tool - tile), atol=1e-6)
        assert start < -1.0  # the tile starts far (~0.9 m) from the tool at home
        # Joint 1 turns towards the tile (it lies at +y): the shaping pays for the approach.
        action = np.zeros(env.action_space.shape, np.float32)
        action[0] = 1.0
        extras, done = [], False
        while not done:
            obs, r, term, trunc, info = env.step(action)
            extras.append(info["reward_reach_shaping"])
            done = term or trunc
        assert sum(extras) > 0.1
        assert np.isclose(sum(extras), env.potential(obs) - start, atol=1e-9)
    finally:
        env.close()
    with pytest.raises(AgentError, match="weight > 0"):
        ReachShaping(gym.make("MosaicOneTileJoint-v0"), weight=0.0)


def test_flat_discrete_masks_are_the_outer_product_of_the_env_masks() -> None:
    from sb3_contrib.common.maskable.utils import get_action_masks  # noqa: PLC0415
    from stable_baselines3.common.vec_env import DummyVecEnv  # noqa: PLC0415

    from agents.learning.wrappers import FlatDiscreteActions  # noqa: PLC0415

    flat = FlatDiscreteActions(gym.make("MosaicDecision6-v0"))
    flat.reset(seed=1003)
    flat.step(flat.flat(flat.unwrapped.expert_action(3, 3)))  # type: ignore[attr-defined]
    vec = DummyVecEnv([lambda: flat])
    joint = get_action_masks(vec)[0]
    n, k, bins = (int(v) for v in flat.nvec)
    assert joint.shape == (n * k * bins,) and joint.dtype == bool
    per_dim = np.asarray(flat.env.get_wrapper_attr("action_masks")(), bool)
    tiles, slots = per_dim[:n], per_dim[n : n + k]
    for a in range(joint.size):
        t, s, _ = flat.action(a)
        assert joint[a] == (tiles[t] and slots[s])
    assert joint.sum() == (n - 1) * (k - 1) * bins
    vec.close()


def test_flat_discrete_masks_need_an_env_with_masks() -> None:
    from agents.learning.wrappers import FlatDiscreteActions  # noqa: PLC0415
    from envs.mosaic_env import MosaicEnvError  # noqa: PLC0415

    env = gym.make("MosaicAssembly-v0", max_slots=1, action_mode="joint", obs_mode="state")
    env.action_space = gym.spaces.MultiDiscrete([2, 2])  # a MultiDiscrete env without masks
    flat = FlatDiscreteActions(env)
    with pytest.raises(MosaicEnvError, match="needs pick_place_discrete"):
        flat.action_masks()
    env.close()
