"""Simulated mosaic cell and the Gymnasium environment ``MosaicAssembly-v0``.

``import envs`` registers the environment (the simulator is imported only when one is made)::

    import gymnasium as gym
    env = gym.make("envs:MosaicAssembly-v0", action_mode="joint", obs_mode="state")
    env = gym.make("envs:MosaicDecision6-v0")  # a rung of the task ladder (`envs.tasks`)

Rendering is headless by default (``MUJOCO_GL=egl`` unless already set).
"""

from __future__ import annotations

import gymnasium as gym

from envs.cell.rendering import use_headless_rendering

use_headless_rendering()

ENV_ID = "MosaicAssembly-v0"
"""Registered id of the environment."""
ENV_ID_V1 = "MosaicAssembly-v1"
"""The environment at ``-v1``: `V1_CHANGES` on top of ``configs/env.yaml`` (``CHANGELOG.md``)."""
V1_CHANGES = {"invalid_actions": "refuse", "pick_yaw_entry": False}
"""What ``-v1`` changes: a ``pick_place_discrete`` action its mask forbids raises `ActionError`;
``pick_place`` is Box(5), without the pick-yaw entry that did nothing (as every rung's ``v1``)."""
MAX_EPISODE_STEPS = 1000
"""Steps before `TimeLimit` truncates an episode."""

for _id, _kwargs in ((ENV_ID, {}), (ENV_ID_V1, V1_CHANGES)):
    if _id not in gym.registry:
        gym.register(
            id=_id,
            entry_point="envs.mosaic_env:MosaicAssemblyEnv",
            max_episode_steps=MAX_EPISODE_STEPS,
            kwargs=dict(_kwargs),
        )

from envs.tasks import register_tasks  # noqa: E402 - after MUJOCO_GL is set

ALL_TASK_IDS = tuple(register_tasks())
"""Registered ids of every version of the task ladder (`envs.tasks`): the -v0s, then the -v1s."""
TASK_IDS = tuple(task_id for task_id in ALL_TASK_IDS if task_id.endswith("-v0"))
"""Registered ids of the task ladder at -v0 (`envs.tasks`), easiest first."""

__all__ = ["ALL_TASK_IDS", "ENV_ID", "ENV_ID_V1", "MAX_EPISODE_STEPS", "TASK_IDS", "V1_CHANGES"]
