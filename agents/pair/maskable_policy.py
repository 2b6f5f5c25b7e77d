"""The pair scorer (`agents.pair.scorer`) as an actor-critic policy of sb3-contrib's MaskablePPO.

The actor's logits over the flat (tile, slot, rotation) actions are the pair scorer's, one per
pair and rotation bin; the critic reads the pair embeddings pooled over the pairs the
observation allows. Forbidden actions are masked by MaskablePPO from the env's
``action_masks()`` (the flat joint mask of `agents.learning.wrappers.FlatDiscreteActions`), so the
network itself masks nothing here.

Train with ``policy: agents.pair.maskable_policy:PairScorerPolicy`` and ``flatten_actions: true``
in a
``configs/train`` preset (``configs/train/maskable_ppo_pair_d6.yaml``); the scorer's shape is
set by ``policy_kwargs.features_extractor_kwargs`` (``hidden``, ``layers``, ``adapter``).
"""

from __future__ import annotations

from typing import Any

import torch
from gymnasium import spaces
from sb3_contrib.common.maskable.policies import MaskableActorCriticPolicy
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

from agents.errors import AgentError
from agents.pair.adapters import ADAPTERS, FEATURE_DIMS, row_adapter
from agents.pair.scorer import PairScorer, PairScorerConfig
from envs.env_config import DEFAULT_ROTATION_BINS
from envs.observations.fields import SLOT_DIM, TILE_DIM


class PairFeatures(BaseFeaturesExtractor):
    """Features = [flat pair logits (n * k * bins), pooled pair embedding (hidden)].

    Args:
        observation_space: A Dict space with flat ``tiles`` and ``slots`` Boxes.
        hidden: Width of the pair network's hidden layers [units].
        layers: Its hidden layers.
        rotation_bins: Logits per pair (the action space's rotation bins).
        adapter: Row adapter (`agents.pair.adapters.ADAPTERS`).
        adapter_args: The adapter's settings (a ``stream`` adapter's belt timing,
            `agents.pair.stream_rows.BeltTiming` as a dict).

    Raises:
        AgentError: No ``tiles``/``slots`` observations, or an unknown adapter.
    """

    def __init__(
        self,
        observation_space: spaces.Dict,
        hidden: int = 64,
        layers: int = 2,
        rotation_bins: int = DEFAULT_ROTATION_BINS,
        adapter: str = "state",
        *,
        adapter_args: dict[str, Any] | None = None,
    ) -> None:
        keys = getattr(observation_space, "spaces", {})
        if "tiles" not in keys or "slots" not in keys or adapter not in ADAPTERS:
            raise AgentError(
                f"the pair-scorer policy needs 'tiles' and 'slots' observations (got "
                f"{sorted(keys)}) and an adapter in {sorted(ADAPTERS)} (got {adapter!r})"
            )
        n = int(keys["tiles"].shape[0]) // TILE_DIM
        k = int(keys["slots"].shape[0]) // SLOT_DIM
        super().__init__(observation_space, n * k * rotation_bins + hidden)
        self.action_dim = n * k * rotation_bins
        self.hidden = hidden
        self.adapter = row_adapter(adapter, adapter_args)
        self.scorer = PairScorer(
            PairScorerConfig(*FEATURE_DIMS[adapter], rotation_bins, hidden, layers)
        )

    def forward(self, observations: dict[str, torch.Tensor]) -> torch.Tensor:
        """Flat logits and pooled embedding of a batch, shape (B, features_dim)."""
        rows = self.adapter(observations["tiles"], observations["slots"])
        emb = self.scorer.embed(rows)
        logits = self.scorer.logits(rows, emb, mask=False)
        return torch.cat([logits, self.scorer.pooled(rows, emb)], dim=1)


class _Split(nn.Module):
    """The MLP extractor's place: actor latent = the logits, critic latent = the embedding."""

    def __init__(self, action_dim: int, hidden: int) -> None:
        super().__init__()
        self.action_dim = action_dim
        self.latent_dim_pi = action_dim
        self.latent_dim_vf = hidden

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.forward_actor(features), self.forward_critic(features)

    def forward_actor(self, features: torch.Tensor) -> torch.Tensor:
        return features[:, : self.action_dim]

    def forward_critic(self, features: torch.Tensor) -> torch.Tensor:
        return features[:, self.action_dim :]


class PairScorerPolicy(MaskableActorCriticPolicy):
    """MaskablePPO policy whose action logits are the pair scorer's (see the module docstring).

    Arguments: as `MaskableActorCriticPolicy`; ``net_arch`` and ``ortho_init`` are fixed (no
    layers after the scorer, PyTorch's default initialisation) and the features extractor is
    `PairFeatures` (its keyword arguments via ``features_extractor_kwargs``).

    Raises:
        AgentError: The action space is not Discrete(tiles x slots x rotation bins).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs["features_extractor_class"] = PairFeatures
        kwargs["net_arch"] = []
        kwargs["ortho_init"] = False
        super().__init__(*args, **kwargs)

    def _build(self, lr_schedule: Any) -> None:
        feats = self.features_extractor
        if not isinstance(feats, PairFeatures):
            raise AgentError("PairScorerPolicy needs the PairFeatures extractor")
        n = getattr(self.action_space, "n", None)
        if n != feats.action_dim:
            raise AgentError(
                f"PairScorerPolicy needs Discrete({feats.action_dim}) actions (tiles x slots x "
                f"rotation bins; flatten_actions: true), got {self.action_space}"
            )
        self.mlp_extractor = _Split(feats.action_dim, feats.hidden)  # type: ignore[assignment]
        self.action_net = nn.Identity()
        self.value_net = nn.Linear(feats.hidden, 1)
        self.optimizer = self.optimizer_class(
            self.parameters(),
            lr=lr_schedule(1),  # type: ignore[call-arg]
            **self.optimizer_kwargs,
        )


__all__ = ["PairFeatures", "PairScorerPolicy"]
