"""Low-level demonstrations as transitions, their space check, RLPD's batches and learning."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
import torch

pytest.importorskip("minari")
pytest.importorskip("jax")

import envs  # noqa: E402,F401 - registers the ids
from agents.learning.demos import DemoSpaceError, load_demos  # noqa: E402
from agents.learning.rlpd import (  # noqa: E402
    DemoMixReplayBuffer,
    LayerNormSACPolicy,
    clone_actor,
    hold_actor,
    portable_checkpoint,
)
from apps.record_demos import record  # noqa: E402

DATASET = "test/one-tile-lowlevel-v0"
TASK = "MosaicOneTile-v0"


@pytest.fixture(scope="module")
def demo_root(tmp_path_factory):
    """Two low-level expert episodes (seeds 0, 1) recorded as a Minari dataset."""
    torch.set_num_threads(1)  # the machine's cores are shared; results do not depend on it
    root = tmp_path_factory.mktemp("minari")
    rec = record(2, seed=0, root=root, dataset_id=DATASET, lowlevel=True)
    assert rec.success_rate == 1.0
    return root


def test_demos_load_as_transitions(demo_root):
    env = gym.make(TASK)
    demos = load_demos(DATASET, env.observation_space, env.action_space, demo_root)
    assert demos.episodes == 2
    assert len(demos) == len(demos.rewards) == len(demos.next_observations["robot"])
    assert demos.terminations.sum() == 2  # each episode ends by success (terminated)
    # the next observation of step t is the observation of step t + 1 within an episode
    assert np.array_equal(demos.next_observations["robot"][0], demos.observations["robot"][1])
    env.close()


def test_demos_with_other_spaces_are_refused_naming_both(demo_root):
    joint = gym.make("MosaicOneTileJoint-v0")
    with pytest.raises(DemoSpaceError) as err:
        load_demos(DATASET, joint.observation_space, joint.action_space, demo_root)
    text = str(err.value)
    assert "action space" in text and "(5,)" in text and "(7,)" in text
    joint.close()


def _model(env, demo_root, **kwargs):
    from stable_baselines3 import SAC  # noqa: PLC0415

    settings = {"batch_size": 64, "learning_starts": 50, "gradient_steps": 2, **kwargs}
    return SAC(
        LayerNormSACPolicy,
        env,
        seed=0,
        device="cpu",
        policy_kwargs={"net_arch": [64, 64]},
        replay_buffer_class=DemoMixReplayBuffer,
        replay_buffer_kwargs={"dataset_id": DATASET, "root": demo_root, "demo_fraction": 0.5},
        **settings,
    )


def test_batches_are_half_demonstrations(demo_root, tmp_path):
    env = gym.make(TASK)
    model = _model(env, demo_root)
    model.learn(60)
    buf = model.replay_buffer
    assert isinstance(buf, DemoMixReplayBuffer)
    batch = buf.sample(64)
    demo_actions = {tuple(a) for a in buf.demos.actions.round(5)}
    from_demos = sum(tuple(a) in demo_actions for a in batch.actions.numpy().round(5))
    assert from_demos == 32
    assert any("LayerNorm" in type(m).__name__ for m in model.critic.modules())
    # the shipped copy loads without the dataset and acts as the trained model does
    from stable_baselines3 import SAC  # noqa: PLC0415

    model.save(tmp_path / "trained.zip")
    portable_checkpoint(tmp_path / "trained.zip", tmp_path / "portable.zip")
    loaded = SAC.load(tmp_path / "portable.zip", device="cpu")
    assert not isinstance(loaded.replay_buffer, DemoMixReplayBuffer)
    obs = {k: v[:8] for k, v in buf.demos.observations.items()}
    assert np.allclose(
        loaded.predict(obs, deterministic=True)[0], model.predict(obs, deterministic=True)[0]
    )
    env.close()


def _value_error(model, demos) -> float:
    """Mean absolute difference of the critic's Q and the demonstrations' discounted returns."""
    returns = np.zeros(len(demos), np.float32)
    future = 0.0
    for t in range(len(demos) - 1, -1, -1):  # episodes end where terminated
        future = demos.rewards[t] + model.gamma * future * (1 - demos.terminations[t])
        returns[t] = future
    obs, _ = model.policy.obs_to_tensor(demos.observations)
    act = torch.as_tensor(demos.actions, dtype=torch.float32)
    with torch.no_grad():
        q = torch.min(*model.critic(obs, act)).squeeze(1).numpy()
    return float(np.abs(q - returns).mean())


def test_rlpd_critic_learns_the_value_of_the_demonstrations(demo_root):
    torch.manual_seed(0)
    env = gym.make(TASK)
    model = _model(env, demo_root)
    demos = model.replay_buffer.demos
    before = _value_error(model, demos)
    model.learn(300)  # 250 env steps after learning_starts, 500 gradient steps
    after = _value_error(model, demos)
    assert after < 0.7 * before, (before, after)
    env.close()


def test_behaviour_cloning_moves_the_actor_towards_the_expert(demo_root):
    env = gym.make(TASK)
    model = _model(env, demo_root)
    demos = model.replay_buffer.demos

    def action_error() -> float:
        pred, _ = model.predict(demos.observations, deterministic=True)
        return float(np.abs(pred - demos.actions).mean())

    before = action_error()
    losses = clone_actor(model, demos, epochs=150, batch_size=64)
    assert losses[-1] < losses[0]
    assert action_error() < 0.5 * before
    env.close()


def _vacuum_flip_odds(model, demos) -> np.ndarray:
    """Per demonstrated state: the chance a sampled vacuum entry has the other sign."""
    obs, _ = model.policy.obs_to_tensor(demos.observations)
    with torch.no_grad():
        mean, log_std, _ = model.actor.get_action_dist_params(obs)
    z = -np.sign(demos.actions[:, -1]) * mean[:, -1].numpy() / log_std[:, -1].exp().numpy()
    return np.array([0.5 * (1 + math.erf(v / math.sqrt(2))) for v in z])


@pytest.mark.slow
def test_clipped_std_fit_keeps_a_sampled_vacuum_on_its_label(demo_root):
    env = gym.make(TASK)
    odds = {}
    for fit in ("mean", "clipped"):
        torch.manual_seed(0)
        model = _model(env, demo_root)
        demos = model.replay_buffer.demos
        clone_actor(model, demos, epochs=800, batch_size=64, std_fit=fit)
        odds[fit] = float(np.median(_vacuum_flip_odds(model, demos)))
    # the vacuum's labels are all +-1: fitted around the mean its spread reads as large and a
    # sampled vacuum switches the wrong way in a few per cent of the states; clipped, never
    assert odds["clipped"] < 1e-3, odds
    assert odds["mean"] > 0.01, odds
    env.close()


def test_clone_actor_refuses_an_unknown_std_fit(demo_root):
    env = gym.make(TASK)
    model = _model(env, demo_root)
    with pytest.raises(ValueError, match=r"std_fit must be one of \['mean', 'clipped'\]"):
        clone_actor(model, model.replay_buffer.demos, epochs=1, std_fit="median")
    env.close()


def test_held_actor_is_the_clone_at_every_action(demo_root):
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415

    class Acting(BaseCallback):
        """The actor's largest parameter change from the start, seen before each action."""

        def _on_training_start(self) -> None:
            self.start = [p.detach().clone() for p in self.model.actor.parameters()]
            self.drift: list[float] = []

        def _on_rollout_start(self) -> None:
            now = list(self.model.actor.parameters())
            self.drift.append(
                max(
                    float((a.detach() - b).abs().max())
                    for a, b in zip(now, self.start, strict=True)
                )
            )

        def _on_step(self) -> bool:
            return True

    torch.manual_seed(0)
    env = gym.make(TASK)
    model = _model(env, demo_root, learning_starts=0, gradient_steps=1)
    acting = Acting()
    model.learn(40, callback=[hold_actor(40), acting])
    # SAC updates the actor after every step; the held actor still takes every action
    assert len(acting.drift) == 40 and max(acting.drift) == 0.0, acting.drift
    env.close()


def _cloned_model(env, demo_root, weight: float):
    """A cloned actor, then 250 env steps (400 gradient steps) of RLPD with the BC term."""
    from agents.learning.actor_bc import actor_bc  # noqa: PLC0415

    torch.manual_seed(0)
    model = _model(env, demo_root)
    demos = model.replay_buffer.demos
    clone_actor(model, demos, epochs=150, batch_size=64)
    cloned, _ = model.predict(demos.observations, deterministic=True)
    model.learn(300, callback=[actor_bc(weight)] if weight else None)
    after, _ = model.predict(demos.observations, deterministic=True)
    return float(np.abs(after - cloned).mean()), float(np.abs(after - demos.actions).mean())


def test_actor_bc_term_keeps_the_actor_at_the_demonstrations(demo_root):
    env = gym.make(TASK)
    drift_free, error_free = _cloned_model(env, demo_root, 0.0)
    drift_bc, error_bc = _cloned_model(env, demo_root, 5.0)
    # without the term SAC's updates drag the clone off; with it the actor stays near the demos
    assert drift_bc < 0.5 * drift_free, (drift_bc, drift_free)
    assert error_bc < error_free, (error_bc, error_free)
    env.close()


def test_actor_bc_term_refuses_a_buffer_without_demonstrations(demo_root):
    from stable_baselines3 import SAC  # noqa: PLC0415

    from agents.learning.actor_bc import ActorBCError, actor_bc  # noqa: PLC0415

    with pytest.raises(ActorBCError, match="weight and decay must be >= 0"):
        actor_bc(-1.0)
    env = gym.make(TASK)
    model = SAC("MultiInputPolicy", env, seed=0, device="cpu", learning_starts=10)
    with pytest.raises(ActorBCError, match="DemoMixReplayBuffer"):
        model.learn(20, callback=actor_bc(1.0))
    env.close()
