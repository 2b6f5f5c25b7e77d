"""Behaviour cloning of the equivariant policy from `StepRecords`.

The loss is a cross-entropy over every (tile, slot, fine turn) a step allows (tiles seen and
open slots, as the action mask has them): the right answers are the demonstrated tile and slot
at every fine turn within ``turn_tolerance_deg`` of the demonstrated turn modulo the slot
figure's symmetry. Two augmentations cost nothing and change no answer's meaning: all crops of
a step turned by one quarter turn (the answer stays), and the step's tile crops alone turned by
another (the right turn moves back by as much).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from agents.equivariant.config import EquivariantConfig
from agents.equivariant.network import build_network
from agents.equivariant.records import StepRecords, from_bytes
from agents.equivariant.turns import right_turns
from agents.learning.step_fit import fit_steps


def targets(
    rec: StepRecords, idx: np.ndarray, turns: int, tolerance: float, shift: np.ndarray
) -> np.ndarray:
    """Right answers of steps ``idx``, (B, n, k, turns) bool.

    ``shift``: quarter turns each step's tile crops were turned by (the right turn moves back).
    """
    n, k = rec.tile_ok.shape[1], rec.slot_ok.shape[1]
    out = np.zeros((len(idx), n, k, turns), bool)
    for b, s in enumerate(idx):
        j = int(rec.slot[s])
        turn = float(rec.turn[s]) - shift[b] * math.pi / 2
        out[b, int(rec.tile[s]), j] = right_turns(turn, int(rec.symmetry[s, j]), turns, tolerance)
    return out


def batch_loss(
    net: Any,
    rec: StepRecords,
    idx: np.ndarray,
    cfg: EquivariantConfig,
    rng: np.random.Generator | None,
) -> tuple[Any, Any]:
    """Mean cross-entropy of steps ``idx`` and whether each step's best answer is right.

    With ``rng`` the crops are augmented (module docstring); without, read as recorded.
    """
    import torch  # noqa: PLC0415

    tiles = torch.as_tensor(from_bytes(rec.tiles[idx]))
    slots = torch.as_tensor(from_bytes(rec.slots[idx]))
    shift = np.zeros(len(idx), int)
    if rng is not None and cfg.augment:
        both = int(rng.integers(4))
        shift = rng.integers(4, size=len(idx))
        tiles = torch.stack(
            [torch.rot90(t, int(q), dims=(-2, -1)) for t, q in zip(tiles, shift, strict=True)]
        )
        tiles = torch.rot90(tiles, both, dims=(-2, -1))
        slots = torch.rot90(slots, both, dims=(-2, -1))
    logits = net(tiles, slots)
    ok = rec.tile_ok[idx][:, :, None, None] & rec.slot_ok[idx][:, None, :, None]
    valid = torch.as_tensor(np.broadcast_to(ok, logits.shape).copy())
    flat = logits.masked_fill(~valid, -1e9).reshape(len(idx), -1)
    logp = torch.log_softmax(flat, dim=1)
    right = torch.as_tensor(
        targets(rec, idx, cfg.turns, math.radians(cfg.turn_tolerance_deg), shift)
    ).reshape(len(idx), -1)
    loss = -torch.logsumexp(logp.masked_fill(~right, -1e9), dim=1).mean()
    hit = right.gather(1, flat.argmax(1, keepdim=True))[:, 0]
    return loss, hit


def train(
    rec: StepRecords,
    cfg: EquivariantConfig,
    seed: int = 0,
    on_point: Callable[[int, Any], dict[str, float]] | None = None,
    every: int = 0,
) -> tuple[Any, list[dict[str, float]]]:
    """Fit the network to the demonstrated steps.

    Args:
        rec: The demonstrations.
        cfg: Network and training settings.
        seed: Seed of the weights, the batches and the augmentation.
        on_point: Called every ``every`` steps and at the end with (step, network); its values
            join that point of the curve.
        every: Gradient steps between points of the curve (0: only the end).

    Returns:
        (the network in eval mode, the curve: per point ``step``, ``loss``, ``train_hit``,
        ``cpu_s`` and ``on_point``'s values).
    """
    import torch  # noqa: PLC0415

    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    net = build_network(cfg)
    n = len(rec.tile)

    def batch() -> tuple[Any, Any]:
        idx = rng.choice(n, size=min(cfg.batch_size, n), replace=False)
        return batch_loss(net, rec, idx, cfg, rng)

    curve = fit_steps(
        net,
        batch,
        steps=cfg.steps,
        learning_rate=cfg.learning_rate,
        weight_decay=cfg.weight_decay,
        every=every,
        on_point=on_point,
    )
    return net, curve


__all__ = ["batch_loss", "targets", "train"]
