"""One training loop for the behaviour clones: cross-entropy over shuffled minibatches.

The decision-level clones (`agents.learning.decision_bc`'s flat MLP, `agents.pair.state_bc`'s pair
scorer on ``state``, `agents.pair.objects_bc`'s pair scorer and flat MLP on ``objects`` rows)
differ in their network and inputs, not in how they are fitted: Adam with the clone's learning rate
and weight decay, and every epoch a permutation of the samples drawn from a generator seeded with
the run's seed, each batch one step on the cross-entropy of the network's logits against the
expert's flat action index.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Protocol

import torch

Logits = Callable[[torch.Tensor | None], torch.Tensor]
"""``logits(idx)``: the network's logits of the samples ``idx`` (None: of every sample)."""


class FitSettings(Protocol):
    """What a fit reads of a clone's configuration (`agents.learning.decision_bc.BCConfig`)."""

    @property
    def epochs(self) -> int:
        """Passes over the samples."""
        ...

    @property
    def batch_size(self) -> int:
        """Samples per optimiser step (the last batch of an epoch may be smaller)."""
        ...

    @property
    def learning_rate(self) -> float:
        """Adam's step size."""
        ...

    @property
    def weight_decay(self) -> float:
        """Adam's L2 penalty."""
        ...


@dataclass(frozen=True)
class FitResult:
    """What a fit did.

    Attributes:
        gradient_steps: Optimiser steps taken (batches over all epochs).
        last_batch_loss: Cross-entropy of the last batch [nats].
        curve: One point per epoch: ``gradient_steps``, ``loss`` (mean over the epoch's samples
            [nats]) and, if asked, ``train_accuracy`` (share of samples whose arg-max is right).
    """

    gradient_steps: int
    last_batch_loss: float
    curve: tuple[dict[str, float], ...]


def fit_classifier(
    logits: Logits,
    params: Iterable[torch.nn.Parameter],
    y: torch.Tensor,
    settings: FitSettings,
    seed: int,
    *,
    accuracy: bool = False,
) -> FitResult:
    """Fit by Adam on the cross-entropy, ``settings.epochs`` passes of shuffled batches.

    Args:
        logits: The network's logits of a batch of sample indices (see `Logits`).
        params: The network's parameters (Adam with ``settings``' rate and decay).
        y: Target class of each sample, shape (N,) int64.
        settings: Epochs, batch size, learning rate and weight decay (an
            `agents.learning.decision_bc.BCConfig`).
        seed: Seed of the batch order.
        accuracy: Also measure the training accuracy after every epoch (one full forward pass).
    """
    opt = torch.optim.Adam(params, lr=settings.learning_rate, weight_decay=settings.weight_decay)
    epochs, batch_size = settings.epochs, settings.batch_size
    gen = torch.Generator().manual_seed(seed)
    steps, last, curve = 0, 0.0, []
    for _ in range(epochs):
        perm = torch.randperm(len(y), generator=gen)
        total = 0.0
        for i in range(0, len(y), batch_size):
            idx = perm[i : i + batch_size]
            loss = torch.nn.functional.cross_entropy(logits(idx), y[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
            steps += 1
            last = float(loss.detach())
            total += last * len(idx)
        point: dict[str, float] = {"gradient_steps": steps, "loss": total / max(len(y), 1)}
        if accuracy:
            with torch.no_grad():
                point["train_accuracy"] = float((logits(None).argmax(1) == y).float().mean())
        curve.append(point)
    return FitResult(steps, last, tuple(curve))
