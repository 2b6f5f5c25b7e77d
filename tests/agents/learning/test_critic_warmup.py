"""Critic warm-up: the actor does not move while the critic fits, then it trains."""

from __future__ import annotations

import gymnasium as gym
import pytest
import torch
from stable_baselines3 import PPO

from agents.errors import AgentError
from agents.learning.critic_warmup import actor_parameters, critic_parameters, critic_warmup

ROLLOUT = 32
"""Env steps per PPO update."""


def _copy(params: list[torch.nn.Parameter]) -> list[torch.Tensor]:
    return [p.detach().clone() for p in params]


def _same(a: list[torch.Tensor], b: list[torch.nn.Parameter]) -> bool:
    return all(torch.equal(x, y) for x, y in zip(a, b, strict=True))


@pytest.fixture
def model() -> PPO:
    """PPO on CartPole with separate actor and critic feature extractors (seeded)."""
    env = gym.make("CartPole-v1")
    return PPO(
        "MlpPolicy",
        env,
        n_steps=ROLLOUT,
        batch_size=ROLLOUT,
        n_epochs=2,
        learning_rate=1e-3,
        seed=0,
        policy_kwargs={"share_features_extractor": False},
    )


def test_the_actor_is_frozen_for_the_warmup_and_trains_after_it(model: PPO) -> None:
    actor, critic = actor_parameters(model.policy), critic_parameters(model.policy)
    assert actor and critic
    assert not {id(p) for p in actor} & {id(p) for p in critic}
    actor0, critic0 = _copy(actor), _copy(critic)
    model.learn(2 * ROLLOUT, callback=critic_warmup(2 * ROLLOUT, learning_rate=3e-3))
    assert _same(actor0, actor), "an actor parameter moved during the warm-up"
    assert not _same(critic0, critic), "the critic did not fit"
    assert all(p.requires_grad for p in model.policy.parameters())  # learn() ended: thawed
    model.learn(ROLLOUT, callback=critic_warmup(2 * ROLLOUT), reset_num_timesteps=False)
    assert not _same(actor0, actor), "the actor did not train after the warm-up"


def test_the_warmup_learning_rate_applies_to_its_updates_only(model: PPO) -> None:
    """During the warm-up the updates use its rate; after it, the algorithm's again."""
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415

    seen: list[float] = []

    class UpdateRates(BaseCallback):  # the optimiser's rate after each update
        def _rate(self) -> None:
            seen.append(self.model.policy.optimizer.param_groups[0]["lr"])

        def _on_rollout_start(self) -> None:
            if self.model.num_timesteps:
                self._rate()

        def _on_training_end(self) -> None:
            self._rate()

        def _on_step(self) -> bool:
            return True

    model.learn(3 * ROLLOUT, callback=[critic_warmup(ROLLOUT, learning_rate=3e-3), UpdateRates()])
    assert seen == pytest.approx([3e-3, 1e-3, 1e-3])


def test_bad_warmup_settings_are_refused() -> None:
    with pytest.raises(AgentError, match="steps"):
        critic_warmup(0)
    with pytest.raises(AgentError, match="learning rate"):
        critic_warmup(10, learning_rate=-1.0)
    with pytest.raises(AgentError, match="value_net"):
        critic_parameters(torch.nn.Linear(2, 2))
