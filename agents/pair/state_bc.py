"""Behaviour cloning of the pair scorer (`agents.pair.scorer`) and the clone as a policy.

Every recorded step gives the observation's rows (an adapter of `agents.pair.state_rows`) and the
expert's (tile, slot, rotation) as one index of the flat categorical; the scorer is trained
with cross-entropy over its masked logits. ``python -m apps.bc.decision --arch pair`` runs it; the
``.pt`` file holds the weights, the scorer's shape, the adapter's name and the action sizes,
and `PairBCPolicy` plays it (`agents.learning.decision_bc.BCPolicy` hands such a file over to it).
"""

from __future__ import annotations

import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import torch

from agents.errors import AgentError
from agents.learning.classifier_fit import FitResult, fit_classifier
from agents.pair.adapters import FEATURE_DIMS, row_adapter
from agents.pair.scorer import PairScorer, PairScorerConfig
from configs.files import atomic_path, write_json
from envs.observations.fields import SLOT_DIM, TILE_DIM

ARCH = "pair"
"""Value of the ``arch`` entry of a pair-scorer clone file."""


def demo_arrays(dataset: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(tiles (N, n*7), slots (N, k*6), flat action index (N,), nvec (3,)) of every step.

    Raises:
        AgentError: Not a dataset of ``tiles``/``slots`` observations and MultiDiscrete actions.
    """
    tiles, slots, acts = [], [], []
    for ep in dataset.iterate_episodes():
        obs = ep.observations
        if "tiles" not in obs or "slots" not in obs or np.asarray(ep.actions).ndim != 2:
            raise AgentError("pair-scorer cloning needs state observations and discrete actions")
        tiles.append(np.asarray(obs["tiles"][:-1], np.float32))
        slots.append(np.asarray(obs["slots"][:-1], np.float32))
        acts.append(np.asarray(ep.actions, np.int64))
    nvec = np.asarray(getattr(dataset.spec.action_space, "nvec", []), np.int64)
    if nvec.size != 3:
        raise AgentError(
            f"pair-scorer cloning needs MultiDiscrete([tiles, slots, rotations]), "
            f"got {dataset.spec.action_space}"
        )
    flat = np.asarray(np.ravel_multi_index(np.concatenate(acts).T, nvec), np.int64)
    return np.concatenate(tiles), np.concatenate(slots), flat, nvec


def fit_scorer(
    rows: Any,
    y: torch.Tensor,
    nvec: np.ndarray,
    cfg: Any,
    *,
    adapter: str,
    seed: int,
    out: Path,
    accuracy: bool = False,
    adapter_args: dict[str, Any] | None = None,
) -> tuple[PairScorer, FitResult, Path]:
    """Fit a pair scorer to the demonstrated flat actions and write it to ``out/bc.pt``.

    Args:
        rows: The adapter's feature rows of every demonstrated step (`PairRows`).
        y: Flat action index per step.
        nvec: The ``pick_place_discrete`` action space's sizes (tile, slot, rotation).
        cfg: `agents.learning.decision_bc.BCConfig`.
        adapter: Name of the row adapter (`agents.pair.adapters.ADAPTERS`).
        seed: Seed of the initial weights and the minibatch order.
        out: Run folder (made).
        accuracy: Record the training accuracy after each epoch (`fit_classifier`).
        adapter_args: The adapter's settings, saved in the file (a ``stream`` adapter's belt
            timing).

    Returns:
        The fitted scorer, the fit's record and the path of the written clone.
    """
    torch.manual_seed(seed)
    shape = PairScorerConfig(*FEATURE_DIMS[adapter], int(nvec[2]), cfg.hidden, cfg.layers)
    net = PairScorer(shape)
    fit = fit_classifier(
        lambda idx: net(rows if idx is None else rows.take(idx)),
        net.parameters(),
        y,
        cfg,
        seed,
        accuracy=accuracy,
    )
    out.mkdir(parents=True, exist_ok=True)
    path = out / "bc.pt"
    blob = {"arch": ARCH, "adapter": adapter, "scorer": asdict(shape), "nvec": nvec.tolist()}
    if adapter_args:
        blob["adapter_args"] = adapter_args
    with atomic_path(path) as tmp:
        torch.save({**blob, "state_dict": net.state_dict(), "config": asdict(cfg)}, tmp)
    return net, fit, path


def train_pair_bc(
    dataset: Any, out: Path, seed: int, cfg: Any, adapter: str = "state"
) -> dict[str, Any]:
    """Clone the demonstrations into a pair scorer; writes ``out/bc.pt`` and a summary.

    Args:
        dataset: A Minari dataset of ``pick_place_discrete`` steps.
        out: Run folder.
        seed: Seed of the initial weights and the minibatch order.
        cfg: `agents.learning.decision_bc.BCConfig` (hidden, layers, epochs, batch_size, learning
            rate, decay).
        adapter: Name of the row adapter (`agents.pair.adapters.ADAPTERS`).
    """
    cpu0 = time.process_time()
    tiles, slots, flat, nvec = demo_arrays(dataset)
    rows = row_adapter(adapter)(torch.as_tensor(tiles), torch.as_tensor(slots))
    y = torch.as_tensor(flat)
    net, fit, path = fit_scorer(rows, y, nvec, cfg, adapter=adapter, seed=seed, out=out)
    with torch.no_grad():
        acc = float((net(rows).argmax(1) == y).float().mean())
    summary = {
        "model_path": str(path),
        "arch": ARCH,
        "samples": len(y),
        "parameters": sum(p.numel() for p in net.parameters()),
        "gradient_steps": fit.gradient_steps,
        "train_accuracy": acc,
        "final_loss": fit.last_batch_loss,
        "cpu_s": time.process_time() - cpu0,
        "seed": seed,
    }
    write_json(out / "bc_summary.json", summary)
    return summary


class PairBCPolicy:
    """A pair-scorer clone as a policy (``predict(obs) -> (action, None)``).

    Args:
        blob: The loaded contents of a clone file written by `train_pair_bc`.

    Raises:
        KeyError, TypeError, RuntimeError: The blob is not a pair-scorer clone.
    """

    def __init__(self, blob: dict[str, Any]) -> None:
        from gymnasium import spaces  # noqa: PLC0415

        self.adapter_name = str(blob["adapter"])
        self.adapter = row_adapter(self.adapter_name, blob.get("adapter_args"))
        self.nvec = np.asarray(blob["nvec"], np.int64)
        self.net = PairScorer(PairScorerConfig(**blob["scorer"]))
        self.net.load_state_dict(blob["state_dict"])
        self.net.eval()
        self.action_space = spaces.MultiDiscrete(self.nvec)

    def predict(self, obs: dict[str, Any]) -> tuple[np.ndarray, None]:
        """The most likely allowed (tile, slot, rotation) for one observation."""
        tiles = np.asarray(obs["tiles"], np.float32)
        slots = np.asarray(obs["slots"], np.float32)
        if tiles.ndim == 2:  # noqa: PLR2004 - objects entity rows (rows, D)
            n, k = len(tiles), len(slots)
        else:
            n, k = len(tiles) // TILE_DIM, len(slots) // SLOT_DIM
        if (n, k) != (int(self.nvec[0]), int(self.nvec[1])):
            raise AgentError(
                f"clone expects {self.nvec[0]} tiles and {self.nvec[1]} slots, got {n} and {k}"
            )
        with torch.no_grad():
            rows = self.adapter(torch.as_tensor(tiles)[None], torch.as_tensor(slots)[None])
            k_best = int(self.net(rows).argmax(1)[0])
        return np.array(np.unravel_index(k_best, self.nvec), np.int64), None


__all__ = ["ARCH", "PairBCPolicy", "demo_arrays", "train_pair_bc"]
