"""RL with demonstrations for stable-baselines3's SAC (RLPD style); behaviour cloning of its actor.

RLPD (Ball et al. 2023, "Efficient Online Reinforcement Learning with Offline Data") is SAC
with three changes, each a setting here:

- `DemoMixReplayBuffer`: every batch is ``demo_fraction`` (one half in RLPD) transitions of a
  demonstration dataset (`agents.learning.demos`) and the rest of the agent's own replay;
- `LayerNormSACPolicy`: LayerNorm after every hidden layer of the critics (keeps the Q values
  of actions the data does not cover from blowing up);
- several gradient updates per env step: SAC's own ``gradient_steps`` (``train_freq: 1``).

In ``configs/train/`` (``apps.train`` resolves ``module:attr`` names)::

    algo: SAC
    policy: agents.learning.rlpd:LayerNormSACPolicy
    algo_kwargs:
      gradient_steps: 4
      replay_buffer_class: agents.learning.rlpd:DemoMixReplayBuffer
      replay_buffer_kwargs: {dataset_id: mosaic/one-tile-lowlevel-v0, demo_fraction: 0.5}

`clone_actor` fits a SAC model's actor to demonstrations by maximum likelihood (behaviour
cloning); the model then plays (and saves) like any SAC model.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from stable_baselines3.common.buffers import DictReplayBuffer
from stable_baselines3.common.policies import ContinuousCritic
from stable_baselines3.common.type_aliases import DictReplayBufferSamples
from stable_baselines3.sac.policies import MultiInputPolicy
from torch import nn

from agents.learning.demos import DEFAULT_ROOT, DemoDatasetError, Transitions, load_demos

DEMO_FRACTION = 0.5
"""RLPD's share of demonstrations in each batch."""
LABEL_CLIP = 1e-3
"""Demonstrated actions are cloned clipped this far inside [-1, 1] (where tanh is invertible)."""
STD_FITS = ("mean", "clipped")
"""Allowed ``std_fit`` values of `clone_actor`."""
STD_WEIGHT = 1e-2
"""Weight of the standard deviation's likelihood term in `clone_actor`'s ``mse`` loss."""
STD_FLOOR = 1e-3
"""``std_fit: clipped``: the likelihood sees the standard deviation (before the tanh) floored
here, so that on exactly matched labels (the vacuum) it stops there instead of falling without
end while its gradient drags the layers the mean shares."""


class DemoMixReplayBuffer(DictReplayBuffer):
    """A Dict replay buffer whose batches mix in demonstrations.

    Args:
        buffer_size: Online transitions kept.
        observation_space: The env's observation space (the dataset's must equal it).
        action_space: The env's action space (likewise).
        dataset_id: Minari dataset of demonstrations (`agents.learning.demos.load_demos`).
        root: Folder of the datasets.
        demo_fraction: Share of each batch drawn from the demonstrations, in [0, 1].
        demos: Transitions to use instead of loading ``dataset_id`` (tests, notebooks).
        **kwargs: `DictReplayBuffer` arguments (device, n_envs, ...).

    Raises:
        DemoDatasetError: A fraction outside [0, 1], or neither a dataset nor transitions.
        DemoSpaceError: The dataset's spaces differ from the env's.
    """

    def __init__(
        self,
        buffer_size: int,
        observation_space: spaces.Dict,
        action_space: spaces.Space,
        *,
        dataset_id: str = "",
        root: str | Path = DEFAULT_ROOT,
        demo_fraction: float = DEMO_FRACTION,
        demos: Transitions | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init__(buffer_size, observation_space, action_space, **kwargs)
        if not 0.0 <= demo_fraction <= 1.0:
            raise DemoDatasetError(f"demo_fraction must be in [0, 1], got {demo_fraction}")
        if demos is None:
            if not dataset_id:
                raise DemoDatasetError("DemoMixReplayBuffer needs a dataset_id (or demos)")
            demos = load_demos(dataset_id, observation_space, action_space, Path(root))
        self.demos = demos
        self.demo_fraction = float(demo_fraction)
        self.last_demo: DictReplayBufferSamples | None = None
        """The demonstration part of the last batch `sample` returned (None before one)."""

    def sample(self, batch_size: int, env: Any = None) -> DictReplayBufferSamples:  # type: ignore[override]
        """``batch_size`` transitions: ``demo_fraction`` of them demonstrations."""
        n_demo = round(batch_size * self.demo_fraction)
        if self.size() == 0:
            n_demo = batch_size
        online = super().sample(batch_size - n_demo, env) if n_demo < batch_size else None
        if n_demo == 0 and online is not None:
            self.last_demo = None
            return online
        demo = self._demo_samples(np.random.randint(0, len(self.demos), size=n_demo), env)
        self.last_demo = demo
        if online is None:
            return demo
        return DictReplayBufferSamples(
            observations={
                k: torch.cat([online.observations[k], demo.observations[k]])
                for k in demo.observations
            },
            actions=torch.cat([online.actions, demo.actions]),
            next_observations={
                k: torch.cat([online.next_observations[k], demo.next_observations[k]])
                for k in demo.next_observations
            },
            dones=torch.cat([online.dones, demo.dones]),
            rewards=torch.cat([online.rewards, demo.rewards]),
        )

    def _demo_samples(self, idx: np.ndarray, env: Any) -> DictReplayBufferSamples:
        d = self.demos
        obs = self._normalize_obs({k: v[idx] for k, v in d.observations.items()}, env)
        nxt = self._normalize_obs({k: v[idx] for k, v in d.next_observations.items()}, env)
        assert isinstance(obs, dict) and isinstance(nxt, dict)
        return DictReplayBufferSamples(
            observations={k: self.to_torch(v.astype(np.float32)) for k, v in obs.items()},
            actions=self.to_torch(d.actions[idx].astype(np.float32)),
            next_observations={k: self.to_torch(v.astype(np.float32)) for k, v in nxt.items()},
            dones=self.to_torch(d.terminations[idx].reshape(-1, 1)),
            rewards=self.to_torch(
                self._normalize_reward(d.rewards[idx].reshape(-1, 1), env).astype(np.float32)
            ),
        )


def layer_norm_mlp(
    in_dim: int, out_dim: int, net_arch: list[int], activation_fn: type[nn.Module]
) -> nn.Sequential:
    """An MLP with LayerNorm after every hidden Linear layer (before the activation)."""
    layers: list[nn.Module] = []
    last = in_dim
    for width in net_arch:
        layers += [nn.Linear(last, width), nn.LayerNorm(width), activation_fn()]
        last = width
    layers.append(nn.Linear(last, out_dim))
    return nn.Sequential(*layers)


class LayerNormCritic(ContinuousCritic):
    """SB3's continuous critic with LayerNorm in each Q network's hidden layers."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        action_dim = int(np.prod(self.action_space.shape or (1,)))
        net_arch = list(kwargs["net_arch"])
        activation = kwargs.get("activation_fn", nn.ReLU)
        in_dim = int(kwargs["features_dim"]) + action_dim
        for idx in range(self.n_critics):
            q_net = layer_norm_mlp(in_dim, 1, net_arch, activation)
            self.add_module(f"qf{idx}", q_net)
            self.q_networks[idx] = q_net


class LayerNormSACPolicy(MultiInputPolicy):
    """SAC's Dict-observation policy with `LayerNormCritic` critics (RLPD)."""

    def make_critic(self, features_extractor: Any = None) -> ContinuousCritic:
        """The critic with LayerNorm (called by SAC for the critic and its target)."""
        critic_kwargs = self._update_features_extractor(self.critic_kwargs, features_extractor)
        return LayerNormCritic(**critic_kwargs).to(self.device)


def clone_actor(
    model: Any,
    demos: Transitions,
    *,
    epochs: int,
    batch_size: int = 256,
    learning_rate: float = 1e-3,
    seed: int = 0,
    loss: str = "mse",
    std_fit: str = "mean",
) -> list[float]:
    """Behaviour cloning: fit a SAC model's actor to the demonstrations.

    ``loss``:

    - ``mse``: the deterministic action (tanh of the Gaussian's mean) regressed onto the
      demonstrated action (squared error), and the log standard deviation fitted by maximum
      likelihood around that mean (the mean's gradient stopped). The mean stays where tanh is
      steep, so the clone's action can change sign within millimetres as the controller's does.
    - ``nll``: maximum likelihood of the squashed Gaussian (demonstrated actions clipped just
      inside [-1, 1], where tanh is invertible). Saturated labels (a full move, +-1) drive the
      mean far into tanh's flat tails, and the clone turns round late (it overshoots its
      targets by centimetres on `MosaicOneTile-v0`).

    ``std_fit`` (``mse`` only): where the log standard deviation is fitted around:

    - ``mean``: the Gaussian's mean. On a saturated label (+-1: the vacuum, a full move) the
      squared error leaves the mean anywhere past the label's pre-image (tanh is flat there),
      and the fit reads that distance as spread: on `MosaicOneTileJoint-v1` the vacuum's
      standard deviation ends at SB3's upper clip (e^2) and a sampled vacuum switches off
      mid-carry (``scripts/joint_clone_diagnosis.py``).
    - ``clipped``: the mean clipped to the labels' pre-image range (``atanh(1 -``
      `LABEL_CLIP` ``)``): a mean past a saturated label acts as the label and counts as no
      error, so the standard deviation measures the demonstrations' real spread (floored at
      `STD_FLOOR` in the likelihood).

    Args:
        model: An SB3 SAC model (its ``actor`` and ``policy.obs_to_tensor``).
        demos: The demonstrations.
        epochs: Passes over the demonstrations.
        batch_size: Transitions per gradient step.
        learning_rate: Adam step size.
        seed: Seed of the batch order.
        loss: ``mse`` or ``nll`` (above).
        std_fit: ``mean`` or ``clipped`` (above).

    Returns:
        The mean loss of each epoch.

    Raises:
        ValueError: An unknown ``loss`` or ``std_fit``.
    """
    if loss not in ("mse", "nll"):
        raise ValueError(f"clone_actor loss must be 'mse' or 'nll', got {loss!r}")
    if std_fit not in STD_FITS:
        raise ValueError(f"clone_actor std_fit must be one of {list(STD_FITS)}, got {std_fit!r}")
    actor = model.actor
    optim = torch.optim.Adam(actor.parameters(), lr=learning_rate)
    rng = np.random.default_rng(seed)
    edge = 1 - LABEL_CLIP
    actions = np.clip(demos.actions, -edge, edge).astype(np.float32)
    reach, floor = float(np.arctanh(edge)), float(np.log(STD_FLOOR))
    losses = []
    for _ in range(epochs):
        order = rng.permutation(len(demos))
        total = 0.0
        for start in range(0, len(order), batch_size):
            idx = order[start : start + batch_size]
            obs, _ = model.policy.obs_to_tensor({k: v[idx] for k, v in demos.observations.items()})
            target = torch.as_tensor(actions[idx], device=model.device)
            mean, log_std, kwargs = actor.get_action_dist_params(obs)
            if loss == "mse":
                value = ((torch.tanh(mean) - target) ** 2).sum(1).mean()
                if std_fit == "clipped":
                    centre = mean.detach().clamp(-reach, reach)
                    log_sd = log_std.clamp(min=floor)
                    nll = 0.5 * ((torch.atanh(target) - centre) / log_sd.exp()) ** 2 + log_sd
                    value = value + STD_WEIGHT * nll.sum(1).mean()
                else:
                    dist = actor.action_dist.proba_distribution(mean.detach(), log_std, **kwargs)
                    value = value - STD_WEIGHT * dist.log_prob(target).mean()
            else:
                dist = actor.action_dist.proba_distribution(mean, log_std, **kwargs)
                value = -dist.log_prob(target).mean()
            optim.zero_grad()
            value.backward()
            optim.step()
            total += float(value.detach()) * len(idx)
        losses.append(total / len(order))
    return losses


def hold_actor(steps: int) -> Any:
    """An SB3 callback keeping a SAC model's actor as it was at the start of ``learn``.

    For ``steps`` env steps the actor's weights are put back before every action (SB3 trains
    between an env step and the next action, so putting them back after the step alone would
    let every action come from the clone plus one update) and after every step, so a cloned
    actor (`clone_actor`) acts as the clone while the critics learn from its episodes and the
    demonstrations; a random critic would otherwise drag it off at once.
    """
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415

    class HoldActor(BaseCallback):
        def _on_training_start(self) -> None:
            actor: nn.Module = getattr(self.model, "actor")  # noqa: B009 - SAC-style models
            self.saved = {k: v.clone() for k, v in actor.state_dict().items()}

        def _on_rollout_start(self) -> None:  # before the next action, after SAC's update
            if self.model.num_timesteps < steps:
                getattr(self.model, "actor").load_state_dict(self.saved)  # noqa: B009

        def _on_step(self) -> bool:
            if self.model.num_timesteps <= steps:
                getattr(self.model, "actor").load_state_dict(self.saved)  # noqa: B009
            return True

    return HoldActor()


def portable_checkpoint(src: str | Path, dst: str | Path) -> None:
    """Save a SAC model trained with `DemoMixReplayBuffer` so that it loads without its dataset.

    A model file records its replay buffer class and arguments, and loading rebuilds the
    buffer: a `DemoMixReplayBuffer` would read its dataset again. The copy at ``dst`` records
    SB3's plain `DictReplayBuffer` of one transition instead (policy, critics and optimisers
    unchanged): it plays, and trains on, without the demonstrations.
    """
    load_without_demos(src).save(str(dst))


def load_without_demos(path: str | Path) -> Any:
    """A SAC model file loaded on the CPU without the replay buffer it records.

    SB3's plain `DictReplayBuffer` of one transition takes its place: a `DemoMixReplayBuffer`
    would read its dataset again.
    """
    from stable_baselines3 import SAC  # noqa: PLC0415

    plain = {"replay_buffer_class": DictReplayBuffer, "replay_buffer_kwargs": {}, "buffer_size": 1}
    return SAC.load(str(path), device="cpu", custom_objects=plain)


__all__ = [
    "DEMO_FRACTION",
    "LABEL_CLIP",
    "STD_FITS",
    "STD_FLOOR",
    "STD_WEIGHT",
    "DemoMixReplayBuffer",
    "LayerNormCritic",
    "LayerNormSACPolicy",
    "clone_actor",
    "hold_actor",
    "load_without_demos",
    "layer_norm_mlp",
    "portable_checkpoint",
]
