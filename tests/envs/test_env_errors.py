"""Bad input gets clear errors; noisy controls raise no MuJoCo warning; close is idempotent."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import envs
from envs.env_config import EnvConfigError
from envs.mosaic_env import MosaicAssemblyEnv, MosaicEnvError
from envs.task_spec import ActionError

SMALL = {"max_slots": 3, "image_size": 48}


@pytest.fixture(scope="module")
def joint_env() -> MosaicAssemblyEnv:
    env = MosaicAssemblyEnv(action_mode="joint", obs_mode="state", **SMALL)
    env.reset(seed=0)
    yield env
    env.close()


@pytest.mark.parametrize(
    ("action", "match"),
    [
        (np.full(7, np.nan, np.float32), "finite"),
        (np.array([np.inf, 0, 0, 0, 0, 0, 0], np.float32), "finite"),
        (np.zeros(6, np.float32), r"shape \(6,\).*expects \(7,\)"),
        (np.zeros((1, 7), np.float32), "shape"),
        (np.full(7, 1.5, np.float32), r"outside \[-1, 1\]"),
        (np.array(["a"] * 7), "numeric"),
    ],
)
def test_bad_actions_are_rejected(
    joint_env: MosaicAssemblyEnv, action: np.ndarray, match: str
) -> None:
    t = joint_env.cell.time
    with pytest.raises(ActionError, match=match):
        joint_env.step(action)
    assert joint_env.cell.time == t  # nothing simulated


def test_discrete_out_of_range() -> None:
    env = MosaicAssemblyEnv(action_mode="pick_place_discrete", obs_mode="state", **SMALL)
    try:
        env.reset(seed=0)
        with pytest.raises(ActionError, match="integers in"):
            env.step(np.array([99, 0, 0]))
        with pytest.raises(ActionError, match="integers in"):
            env.step(np.array([0.5, 0, 0]))
    finally:
        env.close()


def test_step_before_reset_and_after_close() -> None:
    env = MosaicAssemblyEnv(action_mode="joint", obs_mode="state", **SMALL)
    with pytest.raises(MosaicEnvError, match="before reset"):
        env.step(np.zeros(7, np.float32))
    env.reset(seed=0)
    env.close()
    env.close()  # twice is fine
    with pytest.raises(MosaicEnvError, match="closed"):
        env.step(np.zeros(7, np.float32))
    with pytest.raises(MosaicEnvError, match="closed"):
        env.reset()


def test_unknown_modes_via_make() -> None:
    with pytest.raises(EnvConfigError, match="allowed"):
        gym.make(envs.ENV_ID, action_mode="fly")
    with pytest.raises(EnvConfigError, match="allowed"):
        gym.make(envs.ENV_ID, obs_mode="lidar")


def test_human_render_without_display_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    env = MosaicAssemblyEnv(render_mode="human", action_mode="joint", obs_mode="state", **SMALL)
    try:
        with pytest.raises(MosaicEnvError, match="display"):
            env.reset(seed=0)
            env.render()
    finally:
        env.close()


@pytest.mark.parametrize("mode", ["joint", "cartesian"])
def test_noisy_controls_raise_no_mujoco_warning(mode: str) -> None:
    env = MosaicAssemblyEnv(action_mode=mode, obs_mode="state", action_noise=0.3, **SMALL)
    try:
        env.reset(seed=0)
        rng = np.random.default_rng(0)
        for _ in range(150):
            a = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
            env.step(a)
        assert env.cell.warnings() == 0
        assert np.all(np.isfinite(env.cell.data.qpos))
    finally:
        env.close()


def test_pick_place_action_outside_area() -> None:
    env = MosaicAssemblyEnv(obs_mode="state", **SMALL)
    try:
        with pytest.raises(ActionError, match="outside the areas"):
            env.pick_place_action(np.array([5.0, 5.0]), 0.0, np.zeros(2), 0.0)
    finally:
        env.close()
