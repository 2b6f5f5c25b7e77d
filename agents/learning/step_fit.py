"""One training loop for the camera policies: a fixed number of gradient steps with a curve.

The crop scorer (`agents.camera.crop_bc`) and the equivariant policy
(`agents.equivariant.train`) differ in their network, batches and loss, not in how they are
fitted: Adam with the run's learning rate and weight decay, ``steps`` gradient steps each on one
batch's loss, and a training curve whose points average the loss and the share of steps answered
right since the last point.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

BatchLoss = Callable[[], tuple[Any, Any]]
"""``batch()``: the next batch's mean loss (a scalar tensor) and per-step hits (bool tensor)."""
OnPoint = Callable[[int, Any], dict[str, float]]
"""``on_point(step, network)``: further values of a curve point (e.g. a validation level)."""


def fit_steps(
    net: Any,
    batch: BatchLoss,
    *,
    steps: int,
    learning_rate: float,
    weight_decay: float,
    every: int = 0,
    on_point: OnPoint | None = None,
) -> list[dict[str, float]]:
    """Fit ``net`` by ``steps`` Adam steps on ``batch()``; the network ends in eval mode.

    Args:
        net: The torch module (in train mode while a batch is scored).
        batch: Draws the next batch and scores it (module attribute `BatchLoss`).
        steps: Gradient steps.
        learning_rate: Adam step size.
        weight_decay: Adam L2 penalty.
        every: Gradient steps between points of the curve (0: only the end).
        on_point: Called at each point with (step, network in eval mode).

    Returns:
        The curve: per point ``step``, ``loss``, ``train_hit``, ``cpu_s`` (CPU seconds since the
        fit began) and ``on_point``'s values.
    """
    import torch  # noqa: PLC0415

    opt = torch.optim.Adam(net.parameters(), lr=learning_rate, weight_decay=weight_decay)
    curve: list[dict[str, float]] = []
    cpu0 = time.process_time()
    losses: list[float] = []
    hits: list[float] = []
    for step in range(1, steps + 1):
        net.train()
        loss, hit = batch()
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(float(loss.detach()))
        hits.append(float(hit.float().mean()))
        if step == steps or (every and step % every == 0):
            net.eval()
            point = {
                "step": float(step),
                "loss": float(np.mean(losses)),
                "train_hit": float(np.mean(hits)),
                "cpu_s": time.process_time() - cpu0,
            }
            if on_point is not None:
                point.update(on_point(step, net))
            curve.append(point)
            losses, hits = [], []
    net.eval()
    return curve


__all__ = ["BatchLoss", "OnPoint", "fit_steps"]
