"""Sleeping tiles: MuJoCo's sleep for tiles at rest, started and ended where it is known.

A tile at rest is most of an episode's physics cost through its contacts; asleep it costs
nothing until something touches or moves it. Both functions act on the kinematic trees of the
tiles (``model.body_treeid`` of their bodies).
"""

from __future__ import annotations

import mujoco
import numpy as np


def start_asleep(model: mujoco.MjModel, data: mujoco.MjData, trees: np.ndarray) -> None:
    """Start the trees ``trees`` asleep in their current pose (reset at the current state).

    A tile laid at its contact height is at rest, but MuJoCo keeps every tree awake for its
    first sleep countdown. MuJoCo's supported way to start trees asleep is the ``init`` sleep
    policy, applied by `mj_resetData` at the model's ``qpos0``: both are set for this call
    only (the current ``qpos`` becomes ``qpos0``), then restored; the controls are kept. A
    sleeping tile whose pose is written later (picked, fed, parked) is woken by MuJoCo's own
    check of its positions.
    """
    m, d = model, data
    qpos0, policy, ctrl = m.qpos0.copy(), m.tree_sleep_policy.copy(), d.ctrl.copy()
    m.qpos0[:] = d.qpos
    m.tree_sleep_policy[trees] = mujoco.mjtSleepPolicy.mjSLEEP_INIT
    try:
        mujoco.mj_resetData(m, d)
    finally:
        m.qpos0[:] = qpos0
        m.tree_sleep_policy[:] = policy
    d.ctrl[:] = ctrl  # the suction weld is off in qpos0's reset too (built inactive)


def end_countdowns(
    model: mujoco.MjModel, data: mujoco.MjData, trees: np.ndarray, dof_index: np.ndarray
) -> None:
    """Let the tiles now under the sleep tolerance fall asleep at the next physics step.

    MuJoCo puts a tree to sleep once it has stayed under ``opt.sleep_tolerance`` for a
    countdown of physics steps; this ends the countdown of the tiles still now. MuJoCo checks
    the tolerance again, over each tile's whole contact island, at that step.

    Args:
        model: The compiled cell.
        data: Its state.
        trees: Kinematic tree of each tile, shape (n,).
        dof_index: Dof indices of each tile's free joint, shape (n, 6).
    """
    counting = np.flatnonzero(data.tree_asleep[trees] < -1)
    if not len(counting):
        return
    dof = dof_index[counting]
    speed = np.abs(data.qvel[dof]) * model.dof_length[dof]
    still = counting[speed.max(axis=1) < model.opt.sleep_tolerance]
    data.tree_asleep[trees[still]] = -1


__all__ = ["end_countdowns", "start_asleep"]
