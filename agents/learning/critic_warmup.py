"""Critic warm-up of an on-policy actor-critic: the actor frozen while the value fits its rollouts.

A policy started from a good clone (`agents.pair.from_clone`) has a good actor and a critic
that knows nothing: PPO's first updates would push the actor along advantages measured by a
random value function and can undo the clone in a few updates. `critic_warmup` is an SB3
callback for PPO / MaskablePPO that, for the first ``steps`` env steps, keeps every actor
parameter out of the gradient (``requires_grad`` off), so each update fits only the critic on
the rollouts the unchanged actor collects, at its own learning rate; the update of the first
rollout that ends past ``steps`` env steps trains the actor too, at the algorithm's own (small)
learning rate.

Which parameters are the critic's: an unshared value features extractor
(``vf_features_extractor`` when ``share_features_extractor=False``), the value branch of the
MLP extractor (``value_net`` there, SB3's name) and the value head (``value_net``); everything
else is the actor's. With a shared features extractor the warm-up fits the value head alone.
"""

from __future__ import annotations

from typing import Any

from torch import nn

from agents.errors import AgentError


def critic_parameters(policy: nn.Module) -> list[nn.Parameter]:
    """The parameters of an SB3 actor-critic policy that only its value estimate uses.

    Raises:
        AgentError: The policy has no ``value_net`` (not an actor-critic).
    """
    head = getattr(policy, "value_net", None)
    if not isinstance(head, nn.Module):
        raise AgentError(
            f"a critic warm-up needs an actor-critic policy with a value_net, got "
            f"{type(policy).__name__}"
        )
    modules: list[nn.Module] = [head]
    shared = getattr(policy, "share_features_extractor", True)
    vf_feats = getattr(policy, "vf_features_extractor", None)
    if not shared and isinstance(vf_feats, nn.Module):
        modules.append(vf_feats)
    branch = getattr(getattr(policy, "mlp_extractor", None), "value_net", None)
    if isinstance(branch, nn.Module):
        modules.append(branch)
    return [p for m in modules for p in m.parameters()]


def actor_parameters(policy: nn.Module) -> list[nn.Parameter]:
    """Every parameter of the policy that is not one of `critic_parameters`."""
    critic = {id(p) for p in critic_parameters(policy)}
    return [p for p in policy.parameters() if id(p) not in critic]


def critic_warmup(steps: int, learning_rate: float = 0.0) -> Any:
    """An SB3 callback freezing the actor for the first ``steps`` env steps (module docstring).

    Args:
        steps: Env steps (over all envs) whose updates fit the critic only (> 0).
        learning_rate: Learning rate of those updates; 0 keeps the algorithm's.

    Raises:
        AgentError: ``steps`` < 1 or a negative learning rate.
    """
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415
    from stable_baselines3.common.utils import FloatSchedule  # noqa: PLC0415

    if steps < 1 or learning_rate < 0:
        raise AgentError(
            f"critic warm-up: steps must be >= 1 env step (got {steps}) and the learning rate "
            f">= 0 (got {learning_rate}; 0 keeps the algorithm's)"
        )

    class CriticWarmup(BaseCallback):
        def _on_training_start(self) -> None:
            self.frozen = False
            self.schedule = self.model.lr_schedule
            if self.model.num_timesteps < steps:
                self._freeze(True)

        def _freeze(self, on: bool) -> None:
            for p in actor_parameters(self.model.policy):
                p.requires_grad_(not on)
            self.model.lr_schedule = (
                FloatSchedule(learning_rate) if on and learning_rate else self.schedule
            )
            self.frozen = on

        def _on_rollout_end(self) -> None:  # before the update of the rollout just collected
            if self.frozen and self.model.num_timesteps > steps:
                self._freeze(False)

        def _on_step(self) -> bool:
            return True

        def _on_training_end(self) -> None:
            if self.frozen:  # a learn() stopped inside the warm-up leaves a trainable model
                self._freeze(False)

    return CriticWarmup()


__all__ = ["actor_parameters", "critic_parameters", "critic_warmup"]
