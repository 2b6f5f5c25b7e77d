"""A behaviour-cloning term in SAC's actor loss, on the demonstration part of each batch.

RLPD (`agents.learning.rlpd`) with a cloned actor loses the clone once SAC updates the actor: the
young critics overrate actions the demonstrations never took and drag the actor there. TD3+BC
(Fujimoto & Gu 2021) and AWAC-like methods keep the actor near the data with a regression term;
here SAC's actor loss becomes, per gradient step,

    ent_coef * log pi(a|s) - Q(s, a_pi)  +  weight * mean|Q| * ||a_pi(s_demo) - a_demo||^2

where ``a_pi(s)`` is the deterministic action (tanh of the Gaussian's mean), the squared
distance is summed over the action's dimensions and averaged over the demonstration part of the
batch that `DemoMixReplayBuffer` just drew, and ``mean|Q|`` (the mean magnitude of the smaller
critic's value of the actor's deterministic action on those states, no gradient) puts the term
on the critic's scale as TD3+BC's normalisation does: dividing the whole loss by ``mean|Q|``
gives TD3+BC's form with ``weight`` = 1 / its alpha (TD3+BC's 2.5 is ``weight`` 0.4).

`actor_bc` is an SB3 callback: at the start of ``learn`` it registers a step pre-hook on the
actor's optimizer (`torch.optim.Optimizer.register_step_pre_hook`) that adds the term's
gradient to the one SAC's own actor loss left, so SAC's update itself is unchanged. The weight
may fall linearly to zero over ``decay_steps`` env steps. Nothing is saved with the model.
"""

from __future__ import annotations

from typing import Any

import torch
from stable_baselines3.common.type_aliases import DictReplayBufferSamples

from agents.errors import AgentError


class ActorBCError(AgentError):
    """An actor BC term that cannot be applied (a negative weight, no demonstration buffer)."""


def bc_weight_at(weight: float, decay_steps: int, step: int) -> float:
    """The term's weight after ``step`` env steps.

    ``weight`` falls linearly to 0 over ``decay_steps`` env steps (0: constant).
    """
    if decay_steps <= 0:
        return weight
    return weight * max(0.0, 1.0 - step / decay_steps)


def actor_bc_loss(model: Any, demo: DictReplayBufferSamples) -> torch.Tensor:
    """``mean|Q| * ||a_pi(s) - a||^2`` on demonstration transitions (see the module docstring).

    Args:
        model: An SB3 SAC model (``actor``, ``critic``).
        demo: Demonstration transitions (observations as the actor takes them, actions in
            [-1, 1]).

    Returns:
        The scalar term, differentiable in the actor's parameters.
    """
    action = model.actor(demo.observations, deterministic=True)
    with torch.no_grad():
        q_values = torch.cat(model.critic(demo.observations, action.detach()), dim=1)
        scale = q_values.min(dim=1).values.abs().mean()
    return scale * ((action - demo.actions) ** 2).sum(dim=1).mean()


def actor_bc(weight: float, decay_steps: int = 0) -> Any:
    """An SB3 callback adding the behaviour-cloning term to every SAC actor update.

    Args:
        weight: The term's weight relative to the critic's value (see the module docstring).
        decay_steps: Env steps over which the weight falls linearly to zero; 0: constant.

    Raises:
        ActorBCError: A negative weight or decay (here), or a model whose replay buffer has no
            demonstrations (``last_demo``, `agents.learning.rlpd.DemoMixReplayBuffer`) when
            ``learn``
            starts.
    """
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415

    if weight < 0 or decay_steps < 0:
        raise ActorBCError(f"actor BC weight and decay must be >= 0, got {weight}, {decay_steps}")

    class ActorBC(BaseCallback):
        def _on_training_start(self) -> None:
            model = self.model
            if not hasattr(getattr(model, "replay_buffer", None), "last_demo"):
                raise ActorBCError(
                    "the actor BC term needs a SAC model whose replay buffer mixes in "
                    "demonstrations (replay_buffer_class: agents.learning.rlpd:DemoMixReplayBuffer)"
                )
            optimizer = getattr(model, "actor").optimizer  # noqa: B009 - SAC-style models
            self.handle = optimizer.register_step_pre_hook(self._add_bc_gradient)

        def _add_bc_gradient(self, *_: Any) -> None:
            current = bc_weight_at(weight, decay_steps, int(self.model.num_timesteps))
            demo = getattr(self.model, "replay_buffer").last_demo  # noqa: B009
            if current <= 0 or demo is None:
                return
            with torch.enable_grad():
                (current * actor_bc_loss(self.model, demo)).backward()

        def _on_step(self) -> bool:
            return True

        def _on_training_end(self) -> None:
            self.handle.remove()

    return ActorBC()


__all__ = ["ActorBCError", "actor_bc", "actor_bc_loss", "bc_weight_at"]
