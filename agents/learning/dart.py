"""Noise injected into executed actions while the recorder keeps the expert's (DART style).

Behaviour cloning from clean demonstrations only sees the states the expert visits; a clone's
small errors lead it into states the data never covered, where it errs more (compounding
error). DART (Laskey et al. 2017, "DART: Noise Injection for Robust Imitation Learning")
records with noise added to the *executed* action while the *label* stays the expert's clean
action: the data then covers the neighbourhood of the expert's path, each state labelled with
the correction the expert would make there.

`NoisyExecution` wraps the env *inside* the recorder (``DataCollector(NoisyExecution(env))``):
the recorder stores the action the expert chose, the simulator executes it plus Gaussian noise
on the chosen dimensions, clipped to the action space. The noise's standard deviation is
``sigma`` plus ``relative`` times the size of the action on that dimension: large while the
expert moves at full speed through free space (where a clone's lag takes it off the path),
small where it servos to millimetres (where the same noise would stop the expert itself).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from agents.errors import AgentError


class NoisyExecution(gym.Wrapper):
    """Execute ``action + N(0, sigma^2)`` on the ``dims`` of a Box action, clipped to the box.

    Args:
        env: An env with a Box action space.
        sigma: Standard deviation of the noise, in action units (a full action is 1.0).
        dims: Action dimensions that get noise (the others are executed as given).
        seed: Seed of the noise generator (re-seeded on ``reset(seed=...)`` with seed + that).
        relative: Extra standard deviation per unit of the action's size on that dimension.

    Raises:
        AgentError: A non-Box action space, a negative sigma or a dimension out of range.
    """

    def __init__(
        self,
        env: gym.Env,
        sigma: float,
        dims: Sequence[int] = (0, 1, 2, 3),
        seed: int = 0,
        relative: float = 0.0,
    ) -> None:
        super().__init__(env)
        space = env.action_space
        if not isinstance(space, gym.spaces.Box):
            raise AgentError(f"NoisyExecution needs a Box action space, got {space}")
        if sigma < 0 or relative < 0:
            raise AgentError(f"sigma and relative must be >= 0, got {sigma} and {relative}")
        size = int(np.prod(space.shape))
        if any(not 0 <= d < size for d in dims):
            raise AgentError(f"noise dims {list(dims)} out of range for {size} action dims")
        self.sigma = float(sigma)
        self.relative = float(relative)
        self.mask = np.zeros(space.shape, bool)
        self.mask.flat[list(dims)] = True
        self.base_seed = int(seed)
        self.rng = np.random.default_rng(seed)

    def reset(self, *, seed: int | None = None, options: Any = None) -> Any:
        """Reset the env; a reset seed also re-seeds the noise (reproducible episodes)."""
        if seed is not None:
            self.rng = np.random.default_rng(self.base_seed + seed)
        return self.env.reset(seed=seed, options=options)

    def step(self, action: Any) -> Any:
        """Step with the noisy action (the caller, e.g. a recorder, keeps the clean one)."""
        space = self.action_space
        assert isinstance(space, gym.spaces.Box)
        noisy = np.asarray(action, np.float64).copy()
        std = self.sigma + self.relative * np.abs(noisy[self.mask])
        noisy[self.mask] += self.rng.normal(0.0, 1.0, int(self.mask.sum())) * std
        return self.env.step(np.clip(noisy, space.low, space.high).astype(space.dtype))


__all__ = ["NoisyExecution"]
