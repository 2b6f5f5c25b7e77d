"""Behaviour cloning of the pair scorer on ``objects`` rows (learned matching without class ids).

The demonstrations are arrays (tile rows, slot rows, the expert's flat action index) recorded on
the training designs of a task, procedural ones included (``apps.bc.objects`` records them with
the privileged expert; a procedural design's task_spec changes at every reset, so they are not
a fixed-spec Minari dataset). The outlines are compared once per step by the adapter
(`agents.pair.objects_rows.objects_rows`), then the scorer is trained with cross-entropy over its
masked flat logits. The ``.pt`` file has the layout of `agents.pair.state_bc` (``arch: pair``,
``adapter: objects``), so `agents.pair.state_bc.PairBCPolicy` plays it and ``apps.evaluate
--policies <file>.pt@obs_mode=objects`` evaluates it.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from agents.learning.classifier_fit import fit_classifier
from agents.pair.objects_rows import objects_rows
from agents.pair.state_bc import ARCH, fit_scorer
from configs.files import atomic_path, write_json

ADAPTER = "objects"
"""Adapter name stored in the clone file."""


@dataclass(frozen=True)
class ObjectDemos:
    """Recorded expert steps on ``objects`` observations.

    Attributes:
        tiles: Tile rows, shape (N, n, D) float32.
        slots: Slot rows, shape (N, k, D) float32.
        actions: Flat (tile, slot, rotation) index of each step, shape (N,) int64.
        nvec: The MultiDiscrete sizes (tiles, slots, rotation bins), shape (3,).
        episodes: Episodes recorded.
        robot: The ``robot`` observation of each step, shape (N, 19) (the flat MLP reads it).
    """

    tiles: np.ndarray
    slots: np.ndarray
    actions: np.ndarray
    nvec: np.ndarray
    episodes: int
    robot: np.ndarray | None = None


def train_objects_bc(demos: ObjectDemos, out: Path, seed: int, cfg: Any) -> dict[str, Any]:
    """Clone the demonstrations into a pair scorer; writes ``out/bc.pt`` and ``bc_summary.json``.

    Args:
        demos: The expert's steps.
        out: Run folder.
        seed: Seed of the initial weights and the minibatch order.
        cfg: `agents.learning.decision_bc.BCConfig` (hidden, layers, epochs, batch_size, learning
            rate, decay).

    Returns:
        The summary (samples, gradient steps, CPU seconds, per-epoch loss and accuracy).
    """
    cpu0 = time.process_time()
    rows = objects_rows(torch.as_tensor(demos.tiles), torch.as_tensor(demos.slots))
    y = torch.as_tensor(demos.actions)
    net, fit, path = fit_scorer(
        rows, y, demos.nvec, cfg, adapter=ADAPTER, seed=seed, out=out, accuracy=True
    )
    steps, curve = fit.gradient_steps, list(fit.curve)
    summary = {
        "model_path": str(path),
        "arch": ARCH,
        "adapter": ADAPTER,
        "episodes": demos.episodes,
        "samples": len(y),
        "parameters": sum(p.numel() for p in net.parameters()),
        "gradient_steps": steps,
        "train_accuracy": curve[-1]["train_accuracy"] if curve else 0.0,
        "train_cpu_s": time.process_time() - cpu0,
        "seed": seed,
        "curve": curve,
    }
    write_json(out / "bc_summary.json", summary)
    return summary


def train_objects_mlp(demos: ObjectDemos, out: Path, seed: int, cfg: Any) -> dict[str, Any]:
    """The ablation: the flat MLP of `agents.learning.decision_bc` over robot + tile + slot rows.

    Writes ``out/bc.pt`` in `agents.learning.decision_bc.BCPolicy`'s layout (``arch: mlp``,
    ``obs_mode: objects``) and ``bc_summary.json``.
    """
    from agents.learning.decision_bc import _network  # noqa: PLC0415 - the same network as agents.learning.decision_bc's MLP

    cpu0 = time.process_time()
    assert demos.robot is not None, "the flat MLP needs the recorded robot observations"
    x = torch.as_tensor(
        np.concatenate(
            [
                demos.robot,
                demos.tiles.reshape(len(demos.tiles), -1),
                demos.slots.reshape(len(demos.slots), -1),
            ],
            axis=1,
        ),
        dtype=torch.float32,
    )
    y = torch.as_tensor(demos.actions)
    torch.manual_seed(seed)
    net = _network(x.shape[1], int(np.prod(demos.nvec)), cfg)
    fit = fit_classifier(
        lambda idx: net(x if idx is None else x[idx]),
        net.parameters(),
        y,
        cfg,
        seed,
    )
    steps, curve = fit.gradient_steps, list(fit.curve)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "bc.pt"
    blob = {
        "arch": "mlp",
        "obs_mode": "objects",
        "nvec": demos.nvec.tolist(),
        "n_in": int(x.shape[1]),
        "config": asdict(cfg),
    }
    with atomic_path(path) as tmp:
        torch.save({**blob, "state_dict": net.state_dict()}, tmp)
    summary = {
        "model_path": str(path),
        "arch": "mlp",
        "adapter": "flat",
        "episodes": demos.episodes,
        "samples": len(y),
        "parameters": sum(p.numel() for p in net.parameters()),
        "gradient_steps": steps,
        "train_cpu_s": time.process_time() - cpu0,
        "seed": seed,
        "curve": curve,
    }
    write_json(out / "bc_summary.json", summary)
    return summary


__all__ = ["ADAPTER", "ObjectDemos", "train_objects_bc", "train_objects_mlp"]
