"""Bad settings refused at load with the key named; every `envs` error derives from `EnvError`;
generated bad actions give `ActionError`, never a builtin error."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import envs
from configs import ConfigError
from envs.errors import EnvError
from envs.task_spec import ActionError
from planners.errors import PlannerError

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


_ENV: dict[str, Any] = {}


def _state_env() -> Any:
    if "env" not in _ENV:
        env = gym.make(ENV_ID, action_mode="pick_place", obs_mode="state", execution="kinematic")
        env.reset(seed=0)
        _ENV["env"] = env
    return _ENV["env"]


def test_complex_actions_are_refused():
    env = _state_env()
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
def test_generated_actions_are_refused_with_action_error_or_executed(action):
    env = _state_env()
    try:
        _, _, terminated, truncated, _ = env.step(action)
    except ActionError:
        return
    if terminated or truncated:
        env.reset(seed=0)
