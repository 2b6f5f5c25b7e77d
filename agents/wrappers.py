"""Gymnasium wrappers the learned policies train and evaluate with (adapters, no env changes).

`RecordCycleVideo` is Gymnasium's `RecordVideo` with the frames from inside each step: a
decision-level step spans a whole pick-and-place cycle, and `RecordVideo` alone gets one frame
per step (a 6-step episode: 0.24 s of video).

`FlatDiscreteActions` turns ``pick_place_discrete``'s MultiDiscrete([tiles, slots, rotations])
into one Discrete(tiles x slots x rotations): a single categorical over (tile, slot, rotation)
triples. Factored heads sample the tile and the slot independently, so once the slot head
settles on one slot, only that slot's tile is ever rewarded (PPO on 6 slots stalled at 3 correct
tiles); a joint categorical has no such coordination problem, and DQN can use it.

`EpisodeRewardTerms` sums the env's named reward terms (``info["reward_<term>"]``) over each
episode and hands the sums over in the last step's ``info``: training logs them per episode, so
one can see which stage of a shaped reward a learner reaches (`agents.train` writes them to
``reward_terms.csv``).
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


REWARD_TERM_PREFIX = "reward_"
"""Prefix of the env's per-term reward entries in ``info``."""
EPISODE_TERMS_KEY = "episode_reward_terms"
"""``info`` key of the per-episode term sums (last step of an episode only)."""


class EpisodeRewardTerms(gym.Wrapper):
    """Per-episode sums of the named reward terms of ``info``.

    Every numeric ``info["reward_<term>"]`` is summed over the episode; the step that ends it
    (terminated or truncated) gets ``info["episode_reward_terms"] = {term: sum}``. Spaces,
    rewards and observations are unchanged.

    Args:
        env: Any env whose ``info`` names its reward terms ``reward_<term>``.
    """

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self._sums: dict[str, float] = {}

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        """Reset the env and the sums."""
        self._sums = {}
        return self.env.reset(**kwargs)

    def step(self, action: Any) -> tuple[Any, Any, bool, bool, dict[str, Any]]:
        """Step the env, add this step's terms, hand the sums over at the episode's end."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        n = len(REWARD_TERM_PREFIX)
        for key, value in info.items():
            if key.startswith(REWARD_TERM_PREFIX) and isinstance(value, int | float | np.number):
                self._sums[key[n:]] = self._sums.get(key[n:], 0.0) + float(value)
        if terminated or truncated:
            info = {**info, EPISODE_TERMS_KEY: dict(self._sums)}
        return obs, reward, terminated, truncated, info


class RecordCycleVideo(gym.wrappers.RecordVideo):
    """`RecordVideo` that also records the frames rendered inside each step.

    A frame listener of the env (``env.unwrapped.add_frame_listener``) renders every
    ``1 / fps`` s of simulated time while a recording is on, also inside a dynamic
    pick-and-place cycle; each step hands those frames to the video before its own.
    Arguments: as `RecordVideo` (the env needs ``render_mode="rgb_array"``).
    """

    def __init__(self, env: gym.Env, *args: Any, **kwargs: Any) -> None:
        super().__init__(env, *args, **kwargs)
        self._inside: list[np.ndarray] = []
        fps = float(env.metadata.get("render_fps", 25))
        env.unwrapped.add_frame_listener(self._grab, fps)  # type: ignore[attr-defined]

    def _grab(self) -> None:
        if self.recording:
            frame = self.env.render()
            if isinstance(frame, np.ndarray):
                self._inside.append(frame)

    def _capture_frame(self) -> None:
        if self.recording:
            self.recorded_frames.extend(self._inside)
        self._inside.clear()
        super()._capture_frame()


__all__ = [
    "EPISODE_TERMS_KEY",
    "REWARD_TERM_PREFIX",
    "EpisodeRewardTerms",
    "FlatDiscreteActions",
    "RecordCycleVideo",
]
