"""Gymnasium wrappers the learned policies train and evaluate with (adapters, no env changes).

`FlatDiscreteActions` turns ``pick_place_discrete``'s MultiDiscrete([tiles, slots, rotations])
into one Discrete(tiles x slots x rotations): a single categorical over (tile, slot, rotation)
triples. Factored heads sample the tile and the slot independently, so once the slot head
settles on one slot, only that slot's tile is ever rewarded (PPO on 6 slots stalled at 3 correct
tiles); a joint categorical has no such coordination problem, and DQN can use it.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces


class FlatDiscreteActions(gym.ActionWrapper):
    """MultiDiscrete(nvec) -> Discrete(prod(nvec)), row-major (last index fastest).

    Args:
        env: An env with a MultiDiscrete action space.

    Raises:
        TypeError: The action space is not MultiDiscrete.
    """

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        if not isinstance(env.action_space, spaces.MultiDiscrete):
            raise TypeError(
                f"FlatDiscreteActions needs a MultiDiscrete action space, got {env.action_space}"
            )
        self.nvec = np.asarray(env.action_space.nvec, dtype=np.int64).ravel()
        self.action_space = spaces.Discrete(int(np.prod(self.nvec)))

    def action(self, action: Any) -> np.ndarray:
        """Flat index -> the (tile, slot, rotation) MultiDiscrete action."""
        return np.array(np.unravel_index(int(np.asarray(action).item()), self.nvec), np.int64)

    def flat(self, action: np.ndarray) -> int:
        """The flat index of a MultiDiscrete action (inverse of `action`)."""
        return int(np.ravel_multi_index(tuple(int(a) for a in action), self.nvec))


__all__ = ["FlatDiscreteActions"]
