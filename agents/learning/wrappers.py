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
one can see which stage of a shaped reward a learner reaches (`apps.train` writes them to
``reward_terms.csv``).

`ReachShaping` adds a training-only, potential-based reach term read from the documented state
observation: minus a weight times the distance from the tool to the nearest present tile. The
env's own reach potential (``1 - tanh(d / 0.3 m)``) is flat at the one-tile task's start
distance (~0.9 m: 0.04 per metre of approach against 3.3 per metre near the tile), so a learner
starting at home sees almost no gradient towards the tile.
"""

from __future__ import annotations

import resource
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from agents.errors import AgentError


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

    def action_masks(self) -> np.ndarray:
        """The joint mask over the flat actions, shape (prod(nvec),) bool.

        The outer product of the wrapped env's per-dimension masks (its ``action_masks()``,
        tiles + slots + rotations concatenated), flattened row-major as `action` reads an index:
        flat action ``a`` is allowed when its tile, its slot and its rotation all are.

        Raises:
            EnvError: The wrapped env offers no masks (e.g. a continuous action mode).
        """
        flat = np.asarray(self.env.get_wrapper_attr("action_masks")(), bool)
        joint = np.ones((), bool)
        for part in np.split(flat, np.cumsum(self.nvec)[:-1]):
            joint = np.multiply.outer(joint, part)
        return joint.reshape(-1)


def cpu_seconds() -> float:
    """CPU time of this process and its finished children so far [s] (user + system)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


class EpisodeProgress(gym.Wrapper):
    """Puts an episode's fill and the training process's CPU time into its last ``info``.

    The step that ends an episode gets ``info["filled"]`` (slots filled correctly / slots,
    from ``info["evaluation"]``) and ``info["cpu_s"]`` (`cpu_seconds` then), so a `Monitor`
    can log learning curves against CPU time as well as env steps.

    Args:
        env: A `MosaicAssembly-v0` env (any wrapper).
    """

    def step(self, action: Any) -> tuple[Any, Any, bool, bool, dict[str, Any]]:
        """Step the env; add the two entries at the episode's end."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        if terminated or truncated:
            ev = info.get("evaluation") or {}
            filled = float(ev.get("correct", 0)) / max(float(ev.get("slots", 0)), 1.0)
            info = {**info, "filled": filled, "cpu_s": cpu_seconds()}
        return obs, reward, terminated, truncated, info


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


TOOL_POS = slice(12, 15)
"""Tool position [m] in the state observation's ``robot`` vector."""
TILE_HELD = 18
"""Index of the tile-held flag in ``robot``."""
TILE_ROW = 7
"""Features per tile in ``tiles``: x, y, z [m], cos yaw, sin yaw, class, present."""
TILE_PRESENT = 6
"""Index of the present flag in a tile row."""
SHAPING_KEY = "reward_reach_shaping"
"""``info`` key of the added term (so `EpisodeRewardTerms` sums it too)."""


class ReachShaping(gym.Wrapper):
    """Training-only potential-based reach shaping from the state observation.

    Potential: ``-weight x d`` with d the distance from the tool to the nearest present tile
    [m], and 0 while a tile is held; each step adds ``potential(after) - potential(before)``
    to the reward (so the added terms of an episode telescope: approaching pays, leaving
    costs the same) and reports it as ``info["reward_reach_shaping"]``.

    Args:
        env: An env with the ``robot`` and ``tiles`` state observations.
        weight: Reward per metre of approach [1/m] (> 0).

    Raises:
        AgentError: A weight <= 0 or an env without ``robot``/``tiles`` observations.
    """

    def __init__(self, env: gym.Env, weight: float) -> None:
        super().__init__(env)
        keys = getattr(env.observation_space, "spaces", {})
        if not weight > 0 or "robot" not in keys or "tiles" not in keys:
            raise AgentError(
                f"ReachShaping needs weight > 0 (got {weight}) and 'robot' and 'tiles' "
                f"observations (got {sorted(keys)})"
            )
        self.weight = float(weight)
        self._last = 0.0

    def potential(self, obs: dict[str, Any]) -> float:
        """``-weight x`` tool-to-nearest-present-tile distance [m]; 0 while holding a tile."""
        robot = np.asarray(obs["robot"], np.float64)
        if robot[TILE_HELD] > 0.5:
            return 0.0
        tiles = np.asarray(obs["tiles"], np.float64).reshape(-1, TILE_ROW)
        present = tiles[tiles[:, TILE_PRESENT] > 0.5, :3]
        if not len(present):
            return 0.0
        d = np.linalg.norm(present - robot[TOOL_POS], axis=1).min()
        return -self.weight * float(d)

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        """Reset the env and the potential."""
        obs, info = self.env.reset(**kwargs)
        self._last = self.potential(obs)
        return obs, info

    def step(self, action: Any) -> tuple[Any, Any, bool, bool, dict[str, Any]]:
        """Step the env and add the change of the potential."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        now = self.potential(obs)
        extra, self._last = now - self._last, now
        return obs, float(reward) + extra, terminated, truncated, {**info, SHAPING_KEY: extra}


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
    "EpisodeProgress",
    "EpisodeRewardTerms",
    "FlatDiscreteActions",
    "ReachShaping",
    "RecordCycleVideo",
    "cpu_seconds",
]
