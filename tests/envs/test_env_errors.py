"""Bad input gets clear errors: settings refused at load with the key named, generated bad actions
give `ActionError` (never a builtin error), every `envs` error derives from `EnvError`; noisy
controls raise no MuJoCo warning; close is idempotent."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import envs
from configs import ConfigError
from envs.env_config import EnvConfigError
from envs.errors import EnvError
from envs.mosaic_env import MosaicAssemblyEnv, MosaicEnvError
from envs.task_spec import ActionError
from planners.errors import PlannerError

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


ENV_ID = "envs:MosaicAssembly-v0"


@pytest.mark.parametrize(
    ("overrides", "error", "key"),
    [
        ({"cell": {"robot": {"home": [0, 0, 0, 0, float("nan"), 0]}}}, ConfigError, "home"),
        ({"cell": {"robot": {"home": [0, 0, 0, 0, 9.0, 0]}}}, EnvError, "robot.home[4]"),
        ({"control_dt": float("inf")}, ConfigError, "control_dt"),
        ({"tool_z_range": (0.3, 0.004)}, ConfigError, "tool_z_range"),
        ({"tool_z_range": (-0.1, 0.3)}, ConfigError, "tool_z_range"),
        ({"image_size": (4000, 5000)}, ConfigError, "image_size"),
        ({"position_tolerance": float("nan")}, ConfigError, "position_tolerance"),
    ],
)
def test_bad_settings_are_refused_at_make_with_the_key_named(overrides, error, key):
    with pytest.raises(error, match=key.replace("[", r"\[").replace("]", r"\]")):
        gym.make(ENV_ID, obs_mode="rgb", **overrides)


def test_an_ik_solver_that_is_not_installed_is_refused(tmp_path):
    bad = tmp_path / "planner.yaml"
    bad.write_text("ik:\n  solver: no_such_solver\n")
    with pytest.raises(PlannerError, match=r"ik\.solver 'no_such_solver'.*allowed"):
        gym.make(ENV_ID, obs_mode="state", planner=str(bad))


def test_every_error_class_of_envs_derives_from_env_error():
    found = []
    for mod in pkgutil.iter_modules(envs.__path__):
        module = importlib.import_module(f"envs.{mod.name}")
        for _, cls in inspect.getmembers(module, inspect.isclass):
            if issubclass(cls, BaseException) and cls.__module__.startswith("envs."):
                found.append(cls)
                assert issubclass(cls, EnvError), cls
    names = {c.__name__ for c in found}
    assert {"ActionError", "MosaicEnvError", "EnvConfigError", "TaskError", "CellError"} <= names


def test_complex_actions_are_refused(kinematic_env):
    env = kinematic_env
    with pytest.raises(ActionError, match="not complex"):
        env.step(np.zeros(6, complex) + 0.5j)


_DTYPES = st.sampled_from(
    [np.float16, np.float32, np.float64, np.int8, np.int64, np.uint8, np.complex64, np.bool_]
)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    action=hnp.arrays(
        _DTYPES,
        st.sampled_from([(6,), (5,), (7,), (1, 6), (), (6, 1)]),
        elements={"allow_nan": True, "allow_infinity": True},
    )
    | st.one_of(st.none(), st.text(max_size=6), st.lists(st.floats(), max_size=7))
)
def test_generated_actions_are_refused_with_action_error_or_executed(kinematic_env, action):
    env = kinematic_env
    try:
        _, _, terminated, truncated, _ = env.step(action)
    except ActionError:
        return
    if terminated or truncated:
        env.reset(seed=0)
