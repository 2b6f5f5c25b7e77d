"""One training loop for the behaviour clones: cross-entropy over shuffled minibatches.

The decision-level clones (`agents.bc`'s flat MLP, `agents.pair_bc`'s pair scorer on ``state``,
`agents.pair_objects_bc`'s pair scorer and flat MLP on ``objects`` rows) differ in their network
and inputs, not in how they are fitted: every epoch draws a permutation of the samples from a
generator seeded with the run's seed, and each batch takes one Adam step on the cross-entropy of
the network's logits against the expert's flat action index.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import torch

Logits = Callable[[torch.Tensor | None], torch.Tensor]
"""``logits(idx)``: the network's logits of the samples ``idx`` (None: of every sample)."""


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
    opt: torch.optim.Optimizer,
    y: torch.Tensor,
    *,
    epochs: int,
    batch_size: int,
    seed: int,
    accuracy: bool = False,
) -> FitResult:
    """Fit by cross-entropy over ``epochs`` passes of shuffled batches of ``batch_size``.

    Args:
        logits: The network's logits of a batch of sample indices (see `Logits`).
        opt: Optimiser over the network's parameters.
        y: Target class of each sample, shape (N,) int64.
        epochs: Passes over the samples.
        batch_size: Samples per optimiser step (the last batch of an epoch may be smaller).
        seed: Seed of the batch order.
        accuracy: Also measure the training accuracy after every epoch (one full forward pass).
    """
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
