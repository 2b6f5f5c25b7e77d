"""EnvConfig: bundled YAML, flat overrides, clear errors for unknown keys and modes."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import pytest

import envs
from envs.cell.config import load_cell_config
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
    with pytest.raises(EnvConfigError, match=f"({key}|{value}).*allowed"):
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


def test_the_cell_is_nested_not_copied() -> None:
    cfg = load_env_config("env")
    assert cfg.cell.tiles.variants == 8 and cfg.cell.tiles.stream_period == 2.5  # env.yaml's
    assert cfg.cell.tiles.thickness == load_cell_config().tiles.thickness  # the rest: cell.yaml
    flat = load_env_config("env", belt_speed=0.1, feed="stream", tile_color_jitter=0.05)
    assert flat.cell.input_belt.speed == flat.belt_speed == 0.1
    assert flat.cell.tiles.feed == flat.feed == "stream"
    assert flat.cell.tiles.color_jitter == 0.05 and flat.cell.tiles.variants == 8
    nested = load_env_config("env", cell={"config": "cell", "input_belt": {"speed": 0.2}})
    assert nested.belt_speed == 0.2 and nested.cell.tiles.variants == 1  # cell.yaml's own
    with pytest.raises(EnvConfigError, match="unknown cell section 'belts'.*allowed"):
        load_env_config(cell={"belts": {"speed": 0.2}})
    with pytest.raises(EnvConfigError, match="varients.*allowed"):
        load_env_config(cell={"tiles": {"varients": 2}})


def test_a_cell_mapping_changes_the_env_cell_key_by_key() -> None:
    # Passing one cell section keeps the env's own tile settings (stream period, variants);
    # naming the cell file (config: cell) starts from that file alone (see the test above).
    for source in ("env", None):
        cfg = load_env_config(source, cell={"input_belt": {"speed": 0.1}})
        assert cfg.cell.input_belt.speed == 0.1
        assert cfg.cell.tiles.stream_period == 2.5
        assert cfg.cell.tiles.variants == 8
    cfg = load_env_config("env", cell={"tiles": {"stream_period": 3.0}})
    assert cfg.cell.tiles.stream_period == 3.0 and cfg.cell.tiles.variants == 8
