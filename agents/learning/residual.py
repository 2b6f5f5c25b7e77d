"""Residual RL over the scripted low-level controller: the agent's action corrects the expert's.

`ResidualExpertActions` wraps a ``cartesian`` env so that the action an agent sends is a
*residual*: the env executes ``clip(expert(obs) + scale * residual, -1, 1)``, where
``expert`` is `agents.experts.cartesian.LowLevelExpert` acting on the last observation. The
wrapped env has the same spaces, so SB3's SAC trains on it unchanged, and the saved model
plays through ``apps.evaluate``: a run whose ``train_config.yaml`` has ``residual_scale``
gets the same wrapper at play time (`agents.policies`), the expert being part of the policy.

`ResidualSACPolicy` is SAC's Dict policy with the actor's mean layer zeroed (its
deterministic output, the residual, starts at exactly zero: the policy starts at the
controller's level) and its log-std layer's bias set to ``log_std_bias`` (exploration noise
small next to the controller's tolerances: noise of 0.05 action units on the executed moves
already makes it fail).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.sac.policies import MultiInputPolicy
from torch import nn

from agents.errors import AgentError
from agents.experts.cartesian import LowLevelExpert, LowLevelExpertConfig

LOG_STD_BIAS = -2.0
"""Initial log standard deviation of the residual's Gaussian (before tanh): std 0.14."""


class ResidualExpertActions(gym.Wrapper):
    """Execute ``clip(expert(obs) + scale * action, low, high)`` (the agent sends a residual).

    Args:
        env: A ``cartesian`` env with ``state`` observations (`LowLevelExpert`'s needs).
        scale: Residual scale (a residual of 1.0 moves the action by ``scale``); > 0.
        config: The expert's settings (default: ``configs/lowlevel_expert.yaml``).

    Raises:
        AgentError: A scale <= 0, or an env the expert cannot act in.
    """

    def __init__(
        self, env: gym.Env, scale: float, config: LowLevelExpertConfig | None = None
    ) -> None:
        super().__init__(env)
        if scale <= 0:
            raise AgentError(f"residual scale must be > 0 (action units), got {scale}")
        self.scale = float(scale)
        self.expert = LowLevelExpert(env, config)
        self.last_obs: dict[str, Any] | None = None

    def reset(self, *, seed: int | None = None, options: Any = None) -> Any:
        """Reset the env and keep the observation the expert acts on."""
        obs, info = self.env.reset(seed=seed, options=options)
        self.last_obs = obs
        return obs, info

    def step(self, action: Any) -> Any:
        """Step with the expert's action plus the scaled residual."""
        if self.last_obs is None:
            raise AgentError("ResidualExpertActions.step before reset")
        space = self.action_space
        assert isinstance(space, gym.spaces.Box)
        total = self.expert.act(self.last_obs) + self.scale * np.asarray(action, np.float64)
        obs, reward, terminated, truncated, info = self.env.step(
            np.clip(total, space.low, space.high).astype(space.dtype)
        )
        self.last_obs = obs
        return obs, reward, terminated, truncated, info


class ResidualSACPolicy(MultiInputPolicy):
    """SAC's Dict policy whose residual starts at zero with small exploration noise.

    ``log_std_bias`` (a ``policy_kwargs`` key, default `LOG_STD_BIAS`) sets the initial
    log standard deviation; the actor's mean layer starts at zero weights and bias.
    """

    def __init__(self, *args: Any, log_std_bias: float = LOG_STD_BIAS, **kwargs: Any) -> None:
        self.log_std_bias = float(log_std_bias)
        super().__init__(*args, **kwargs)

    def _build(self, lr_schedule: Any) -> None:
        super()._build(lr_schedule)
        mu: nn.Linear = self.actor.mu  # type: ignore[assignment]
        log_std: nn.Linear = self.actor.log_std  # type: ignore[assignment]
        with torch.no_grad():
            mu.weight.zero_()
            mu.bias.zero_()
            log_std.weight.zero_()
            log_std.bias.fill_(self.log_std_bias)

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data = super()._get_constructor_parameters()
        data["log_std_bias"] = self.log_std_bias
        return data


__all__ = ["LOG_STD_BIAS", "ResidualExpertActions", "ResidualSACPolicy"]
