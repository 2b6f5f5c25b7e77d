"""EnvConfig: bundled YAML, flat overrides, clear errors for unknown keys and modes."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import pytest

import envs
from envs.env_config import EnvConfig, EnvConfigError, allowed_keys, load_env_config


def test_yaml_matches_dataclass_defaults() -> None:
    assert load_env_config("env") == EnvConfig()


def test_flat_overrides_and_square_image_size() -> None:
    cfg = load_env_config(action_mode="joint", image_size=64, belt_speed=0.1)
    assert cfg.image_size == (64, 64) and cfg.action_mode == "joint" and cfg.belt_speed == 0.1
    again = load_env_config(cfg, obs_mode="state")
    assert again.obs_mode == "state" and again.image_size == (64, 64)
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.design = "hexagon"  # type: ignore[misc]


def test_unknown_key_lists_allowed() -> None:
    with pytest.raises(EnvConfigError, match="allowed") as exc:
        load_env_config(colour="red")
    assert "action_mode" in str(exc.value) and "colour" in str(exc.value)
    with pytest.raises(EnvConfigError, match="allowed"):
        load_env_config(EnvConfig(), colour="red")


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("action_mode", "teleport"),
        ("obs_mode", "lidar"),
        ("reward_mode", "shaped"),
        ("execution", "magic"),
        ("feed", "trickle"),
        ("render_mode", "ansi"),
    ],
)
def test_unknown_modes_name_the_allowed_ones(key: str, value: str) -> None:
    with pytest.raises(EnvConfigError, match=f"unknown {key}.*allowed"):
        load_env_config(**{key: value})


def test_bad_values() -> None:
    with pytest.raises(EnvConfigError, match="control_dt"):
        load_env_config(control_dt=0.0)
    with pytest.raises(EnvConfigError, match="belt_speed"):
        load_env_config(belt_speed=-1.0)
    with pytest.raises(EnvConfigError, match="batch_size"):
        load_env_config(feed="batch", batch_size=0)
    with pytest.raises(EnvConfigError, match="batch_index_time"):
        load_env_config(feed="batch", batch_index_time=0.0)


def test_registration() -> None:
    spec = gym.spec(envs.ENV_ID)
    assert spec.max_episode_steps == envs.MAX_EPISODE_STEPS
    assert "action_mode" in allowed_keys()


def test_make_rejects_unknown_key() -> None:
    with pytest.raises(EnvConfigError, match="allowed"):
        gym.make("envs:MosaicAssembly-v0", not_a_key=1)
