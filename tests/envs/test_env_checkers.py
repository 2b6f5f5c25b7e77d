"""Gymnasium's and stable-baselines3's env checkers for every action and observation mode."""

from __future__ import annotations

import warnings

import gymnasium as gym
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import envs
from envs.env_config import ACTION_MODES, OBS_MODES

SMALL = {"max_slots": 3, "image_size": 48}
"""A small design and images (SB3's CNN check wants >= 36 px)."""


def _make(action_mode: str, obs_mode: str, **kw: object) -> gym.Env:
    execution = "kinematic" if action_mode.startswith("pick_place") else "dynamic"
    return gym.make(
        envs.ENV_ID,
        action_mode=action_mode,
        obs_mode=obs_mode,
        execution=execution,
        **{**SMALL, **kw},
    )


@pytest.mark.parametrize("obs_mode", OBS_MODES)
@pytest.mark.parametrize("action_mode", ACTION_MODES)
def test_checkers_pass_without_warnings(action_mode: str, obs_mode: str) -> None:
    env = _make(action_mode, obs_mode)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            if obs_mode == "objects":  # 2-D entity rows by design (MultiInputPolicy flattens)
                warnings.filterwarnings("ignore", ".*unconventional shape", UserWarning)
            gym_check_env(env.unwrapped, skip_render_check=True)
            sb3_check_env(env.unwrapped, warn=True)
    finally:
        env.close()


def test_checkers_dynamic_pick_place_with_render() -> None:
    env = gym.make(envs.ENV_ID, obs_mode="rgb+state", render_mode="rgb_array", **SMALL)
    assert env.unwrapped.config.execution == "dynamic"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            gym_check_env(env.unwrapped, skip_render_check=True)
            sb3_check_env(env.unwrapped, warn=True)
        env.reset(seed=0)
        frame = env.render()
        assert frame.dtype == "uint8" and frame.ndim == 3 and frame.std() > 0
    finally:
        env.close()


def test_gymnasium_checker_with_depth() -> None:
    """Depth is float32 (H, W, 1) [m]: Gymnasium's checker passes; SB3's would warn that an
    image-shaped observation is not uint8 (use a custom feature extractor for depth)."""
    env = _make("joint", "rgb", depth=True)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            gym_check_env(env.unwrapped, skip_render_check=True)
    finally:
        env.close()
