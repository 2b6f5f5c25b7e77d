"""One timed step of the env's expert, for the benchmarks that time observation sources."""

from __future__ import annotations

import time
from typing import cast

import gymnasium as gym
import numpy as np

from envs.mosaic_env import MosaicAssemblyEnv


def timed_expert_step(env: gym.Env) -> tuple[float, bool] | None:
    """Step ``env`` with its expert's action for the first tile on the input side.

    The tile goes to the slot of the same index (`MosaicAssemblyEnv.expert_action`).

    Returns:
        CPU seconds of the step and whether the episode ended (terminated or truncated);
        None when no tile is left on the input side (nothing was stepped).
    """
    u = cast(MosaicAssemblyEnv, env.unwrapped)
    on_input = np.flatnonzero(u.cell.input_half())
    if not len(on_input):
        return None
    tile = int(on_input[0])
    action = u.expert_action(tile, tile)
    t0 = time.process_time()
    _, _, term, trunc, _ = env.step(action)
    return time.process_time() - t0, bool(term or trunc)


__all__ = ["timed_expert_step"]
