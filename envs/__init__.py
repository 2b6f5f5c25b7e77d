"""Simulated mosaic cell and the Gymnasium environment ``MosaicAssembly-v0``.

``import envs`` registers the environment (the simulator is imported only when one is made)::

    import gymnasium as gym
    env = gym.make("envs:MosaicAssembly-v0", action_mode="joint", obs_mode="state")
    env = gym.make("envs:MosaicDecision6-v0")  # a rung of the task ladder (`envs.tasks`)

Rendering is headless by default (``MUJOCO_GL=egl`` unless already set).
"""

from __future__ import annotations

import os

import gymnasium as gym

os.environ.setdefault("MUJOCO_GL", "egl")

ENV_ID = "MosaicAssembly-v0"
"""Registered id of the environment."""
MAX_EPISODE_STEPS = 1000
"""Steps before `TimeLimit` truncates an episode."""

if ENV_ID not in gym.registry:
    gym.register(
        id=ENV_ID,
        entry_point="envs.mosaic_env:MosaicAssemblyEnv",
        max_episode_steps=MAX_EPISODE_STEPS,
    )

from envs.tasks import register_tasks  # noqa: E402 - after MUJOCO_GL is set

TASK_IDS = tuple(register_tasks())
"""Registered ids of the task ladder (`envs.tasks`), easiest first."""

__all__ = ["ENV_ID", "MAX_EPISODE_STEPS", "TASK_IDS"]
