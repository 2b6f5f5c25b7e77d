"""A pair scorer: one network applied with shared weights to every (tile row, slot row) pair.

A flat network over the concatenated observation has to learn "this tile goes with that slot"
separately for every pair of row positions. The pair scorer learns one function of one pair,
so it scores ``n x k`` pairs with the weights of one: it reads a tile row (``tile_dim``
features), a slot row (``slot_dim``) and features of the pair (``pair_dim``, computed by an
adapter from both rows, e.g. whether their classes are equal and the tile's yaw relative to
the slot), and gives one logit per rotation bin. The logits of all pairs, flattened as
``(tile, slot, rotation)`` row-major, are one categorical over the ``pick_place_discrete``
actions (the order `agents.learning.wrappers.FlatDiscreteActions` uses).

The network knows nothing of the observation's encoding: `PairRows` carries the rows, and an
adapter (`agents.pair.state_rows` for ``obs_mode="state"``) makes them. A value estimate for
actor-critic training comes from the pair embeddings pooled over the allowed pairs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import torch
from torch import nn

from envs.env_config import DEFAULT_ROTATION_BINS

MASKED_LOGIT = -1e9
"""Logit of a forbidden (tile, slot) pair (finite, so a softmax over all-forbidden rows is
defined; exp of it is 0 in float32)."""


@dataclass(frozen=True)
class PairScorerConfig:
    """Shape of a pair scorer.

    Attributes:
        tile_dim: Features per tile row.
        slot_dim: Features per slot row.
        pair_dim: Features per (tile, slot) pair from the adapter.
        rotation_bins: Logits per pair (the action space's rotation bins).
        hidden: Width of each hidden layer of the pair network [units].
        layers: Hidden layers of the pair network (>= 1).
    """

    tile_dim: int
    slot_dim: int
    pair_dim: int
    rotation_bins: int = DEFAULT_ROTATION_BINS
    hidden: int = 64
    layers: int = 2


@dataclass(frozen=True)
class PairRows:
    """Entity rows of a batch of observations (torch tensors, float32 unless said).

    Attributes:
        tiles: Tile rows, shape (B, n, tile_dim).
        slots: Slot rows, shape (B, k, slot_dim).
        pairs: Pair features, shape (B, n, k, pair_dim).
        tile_mask: Tile may be picked now, shape (B, n) bool.
        slot_mask: Slot may be filled now, shape (B, k) bool.
    """

    tiles: torch.Tensor
    slots: torch.Tensor
    pairs: torch.Tensor
    tile_mask: torch.Tensor
    slot_mask: torch.Tensor

    def pair_mask(self) -> torch.Tensor:
        """Allowed (tile, slot) pairs, shape (B, n, k) bool."""
        return self.tile_mask[:, :, None] & self.slot_mask[:, None, :]

    def take(self, idx: torch.Tensor) -> PairRows:
        """The rows of the batch entries ``idx`` (every field indexed along its first axis)."""
        return PairRows(
            self.tiles[idx],
            self.slots[idx],
            self.pairs[idx],
            self.tile_mask[idx],
            self.slot_mask[idx],
        )


class PairScorer(nn.Module):
    """Shared-weight network over (tile, slot) pairs (see the module docstring).

    Args:
        cfg: Its shape.
    """

    def __init__(self, cfg: PairScorerConfig) -> None:
        super().__init__()
        self.cfg = cfg
        layers: list[nn.Module] = []
        width = cfg.tile_dim + cfg.slot_dim + cfg.pair_dim
        for _ in range(cfg.layers):
            layers += [nn.Linear(width, cfg.hidden), nn.ReLU()]
            width = cfg.hidden
        self.body = nn.Sequential(*layers)
        self.head = nn.Linear(cfg.hidden, cfg.rotation_bins)

    def embed(self, rows: PairRows) -> torch.Tensor:
        """Hidden features of every pair, shape (B, n, k, hidden)."""
        b, n, _ = rows.tiles.shape
        k = rows.slots.shape[1]
        x = torch.cat(
            [
                rows.tiles[:, :, None, :].expand(b, n, k, -1),
                rows.slots[:, None, :, :].expand(b, n, k, -1),
                rows.pairs,
            ],
            dim=-1,
        )
        return self.body(x)

    def logits(self, rows: PairRows, emb: torch.Tensor | None = None, mask: bool = True) -> Any:
        """Flat logits over (tile, slot, rotation), shape (B, n * k * rotation_bins).

        Args:
            rows: The batch's rows.
            emb: Their `embed` (computed when None).
            mask: Set the logits of forbidden pairs to `MASKED_LOGIT` (from the rows' masks).
        """
        out = self.head(self.embed(rows) if emb is None else emb)
        if mask:
            allowed = rows.pair_mask()[..., None]
            out = torch.where(allowed, out, torch.full_like(out, MASKED_LOGIT))
        return out.flatten(1)

    def pooled(self, rows: PairRows, emb: torch.Tensor) -> torch.Tensor:
        """Mean embedding over the allowed pairs (all pairs if none is), shape (B, hidden)."""
        w = rows.pair_mask().to(emb.dtype)
        w = torch.where(w.sum((1, 2), keepdim=True) > 0, w, torch.ones_like(w))
        return (emb * w[..., None]).sum((1, 2)) / w.sum((1, 2))[:, None]

    def forward(self, rows: PairRows) -> torch.Tensor:
        """Masked flat logits (see `logits`)."""
        return self.logits(rows)


__all__ = ["MASKED_LOGIT", "PairRows", "PairScorer", "PairScorerConfig"]
