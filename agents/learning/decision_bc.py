"""Behaviour cloning of the decision-level tasks: the network, its training and the policy.

Trained from Minari demonstrations by ``python -m apps.bc.decision``; see that program for the run.
"""

from __future__ import annotations

import pickle
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agents.errors import AgentError
from configs import load_config
from configs.checks import check_fields, checked
from configs.files import atomic_path, write_json

STATE_KEYS = ("robot", "tiles", "slots")
"""Observation keys the clone reads, in order."""
BC_CONFIG = "bc"
"""Bundled config name (``configs/bc.yaml``)."""
ARCHS = ("mlp", "pair")
"""Allowed ``BCConfig.arch`` values."""


@dataclass(frozen=True)
class BCConfig:
    """Behaviour-cloning settings.

    Attributes:
        hidden: Width of each hidden layer [units].
        layers: Hidden layers.
        epochs: Passes over the demonstrations.
        batch_size: Steps per gradient step.
        learning_rate: Adam step size.
        weight_decay: Adam L2 penalty.
        arch: ``mlp`` (one network over the concatenated observation) or ``pair`` (the pair
            scorer of `agents.pair.scorer`, shared weights per (tile, slot) pair).
    """

    hidden: int = 256
    layers: int = 2
    epochs: int = 300
    batch_size: int = 64
    learning_rate: float = 1e-3
    weight_decay: float = 1e-4
    arch: str = checked("mlp", choices=ARCHS)

    def __post_init__(self) -> None:
        check_fields(self, AgentError, prefix="behaviour cloning: ")


def load_bc_config(name_or_path: str | Path = BC_CONFIG, **overrides: Any) -> BCConfig:
    """Load a `BCConfig` strictly from ``configs/`` (by name) or a path."""
    return load_config(BCConfig, name_or_path, **overrides)


def _features(obs: dict[str, Any]) -> np.ndarray:
    """State observation(s) -> feature rows (one per step), float32."""
    parts = [np.asarray(obs[k], np.float32) for k in STATE_KEYS]
    if parts[0].ndim == 1:
        parts = [p[None] for p in parts]
    return np.concatenate([p.reshape(len(p), -1) for p in parts], axis=1)  # objects rows: flat


def _network(n_in: int, n_out: int, cfg: BCConfig) -> Any:
    import torch  # noqa: PLC0415

    layers: list[Any] = []
    width = n_in
    for _ in range(cfg.layers):
        layers += [torch.nn.Linear(width, cfg.hidden), torch.nn.ReLU()]
        width = cfg.hidden
    layers.append(torch.nn.Linear(width, n_out))
    return torch.nn.Sequential(*layers)


def train_bc(dataset: Any, out: Path, seed: int = 0, cfg: BCConfig | None = None) -> dict[str, Any]:
    """Train a clone on every step of a Minari dataset; writes ``out/bc.pt`` and a summary.

    Raises:
        AgentError: The dataset is not a decision-level (MultiDiscrete) dataset with state.
    """
    import torch  # noqa: PLC0415

    from agents.learning.classifier_fit import fit_classifier  # noqa: PLC0415 - torch on demand

    cfg = cfg or load_bc_config()
    if cfg.arch == "pair":
        from agents.pair.state_bc import train_pair_bc  # noqa: PLC0415

        return train_pair_bc(dataset, out, seed, cfg)
    cpu0 = time.process_time()
    xs, ys = [], []
    nvec: np.ndarray | None = None
    for ep in dataset.iterate_episodes():
        obs = ep.observations
        if not all(k in obs for k in STATE_KEYS) or np.asarray(ep.actions).ndim != 2:
            raise AgentError("behaviour cloning needs rgb+state/state obs and discrete actions")
        xs.append(_features({k: obs[k][:-1] for k in STATE_KEYS}))
        ys.append(np.asarray(ep.actions, np.int64))
    space = dataset.spec.action_space
    nvec = np.asarray(getattr(space, "nvec", []), np.int64)
    if nvec.size == 0:
        raise AgentError(f"behaviour cloning needs a MultiDiscrete action space, got {space}")
    x = torch.as_tensor(np.concatenate(xs))
    y = torch.as_tensor(np.ravel_multi_index(np.concatenate(ys).T, nvec))
    torch.manual_seed(seed)
    net = _network(x.shape[1], int(np.prod(nvec)), cfg)
    t0 = time.perf_counter()
    fit = fit_classifier(
        lambda idx: net(x if idx is None else x[idx]),
        net.parameters(),
        y,
        cfg,
        seed,
    )
    with torch.no_grad():
        acc = float((net(x).argmax(1) == y).float().mean())
    out.mkdir(parents=True, exist_ok=True)
    path = out / "bc.pt"
    with atomic_path(path) as tmp:
        torch.save(
            {
                "state_dict": net.state_dict(),
                "nvec": nvec.tolist(),
                "n_in": int(x.shape[1]),
                "config": asdict(cfg),
                "arch": "mlp",
            },
            tmp,
        )
    summary = {
        "model_path": str(path),
        "arch": "mlp",
        "samples": len(x),
        "parameters": sum(p.numel() for p in net.parameters()),
        "gradient_steps": fit.gradient_steps,
        "train_accuracy": acc,
        "final_loss": fit.last_batch_loss,
        "wall_s": time.perf_counter() - t0,
        "cpu_s": time.process_time() - cpu0,
        "seed": seed,
    }
    write_json(out / "bc_summary.json", summary)
    return summary


class BCPolicy:
    """A trained clone as a policy (``predict(obs) -> (action, None)``).

    A pair-scorer clone (``arch: pair`` in the file) is played by
    `agents.pair.state_bc.PairBCPolicy`.

    Args:
        path: A ``bc.pt`` file from `train_bc`.
    """

    def __init__(self, path: str | Path) -> None:
        import torch  # noqa: PLC0415
        from gymnasium import spaces  # noqa: PLC0415

        try:
            blob = torch.load(str(path), map_location="cpu", weights_only=True)
            if blob.get("arch") == "pair":
                from agents.pair.state_bc import PairBCPolicy  # noqa: PLC0415

                self._pair: Any = PairBCPolicy(blob)
                self.action_space = self._pair.action_space
                return
            self._pair = None
            self._obs_mode = str(blob.get("obs_mode", "state"))
            self.nvec = np.asarray(blob["nvec"], np.int64)
            cfg = BCConfig(**blob["config"])
            self.net = _network(int(blob["n_in"]), int(np.prod(self.nvec)), cfg)
            self.net.load_state_dict(blob["state_dict"])
        except (
            OSError,
            RuntimeError,
            KeyError,
            TypeError,
            ValueError,
            EOFError,
            AttributeError,
            pickle.UnpicklingError,
        ) as exc:
            what = "no such file" if isinstance(exc, FileNotFoundError) else "unreadable"
            if isinstance(exc, KeyError | TypeError):
                what = f"missing or wrong entry {exc}"
            raise AgentError(
                f"{path} is not a behaviour clone saved by agents.learning.decision_bc "
                f"({what}: {type(exc).__name__})"
            ) from exc
        self.net.eval()
        self.action_space = spaces.MultiDiscrete(self.nvec)
        self.n_in = int(blob["n_in"])

    @property
    def env_overrides(self) -> dict[str, Any]:
        """Env keys the clone's observation needs: ``obs_mode="objects"`` for an objects clone."""
        if self._pair is not None:
            mode = self._pair.adapter_name
        else:
            mode = self._obs_mode
        return {"obs_mode": mode} if mode == "objects" else {}

    def predict(self, obs: dict[str, Any]) -> tuple[np.ndarray, None]:
        """The most likely (tile, slot, rotation) for a state observation."""
        import torch  # noqa: PLC0415

        if self._pair is not None:
            return self._pair.predict(obs)
        x = _features(obs)
        if x.shape[1] != self.n_in:
            raise AgentError(f"clone expects {self.n_in} state features, got {x.shape[1]}")
        with torch.no_grad():
            k = int(self.net(torch.as_tensor(x)).argmax(1)[0])
        return np.array(np.unravel_index(k, self.nvec), np.int64), None


__all__ = ["ARCHS", "BCConfig", "BCPolicy", "load_bc_config", "train_bc"]
