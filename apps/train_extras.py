"""Pieces of ``apps.train`` for learning from demonstrations and CPU budgets.

- `resolve_named`: a ``module:attr`` string in a training YAML (``policy``, an
  ``algo_kwargs`` key ending in ``_class``) becomes the object it names, so a config can use a
  policy or replay buffer class of the project (`agents.learning.rlpd`) without code.
- `clone_before_learning`: behaviour cloning of a SAC actor on a demonstration dataset before
  (or instead of) reinforcement learning.
- `demo_normalized_kwargs`: ``policy_kwargs`` whose features extractor standardises the
  observations with the demonstrations' statistics (`agents.learning.obs_norm`).
"""

from __future__ import annotations

import importlib
import math
from pathlib import Path
from typing import Any

from configs import ConfigError

BC_BATCH = 256
"""Transitions per behaviour-cloning gradient step."""
CLASS_SUFFIX = "_class"
"""``algo_kwargs`` keys whose ``module:attr`` string values are resolved."""


def resolve_named(value: Any) -> Any:
    """The object a ``module:attr`` string names; any other value unchanged.

    Raises:
        ConfigError: The module or the attribute does not exist.
    """
    if not isinstance(value, str) or ":" not in value:
        return value
    module, _, attr = value.partition(":")
    try:
        return getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError) as exc:
        raise ConfigError(f"cannot resolve {value!r} (module:attr): {exc}") from exc


def resolve_algo_kwargs(kwargs: dict[str, Any]) -> dict[str, Any]:
    """``algo_kwargs`` with every ``*_class`` string resolved (`resolve_named`)."""
    return {k: resolve_named(v) if k.endswith(CLASS_SUFFIX) else v for k, v in kwargs.items()}


def clone_before_learning(
    model: Any, dataset_id: str, root: str | Path, epochs: int, seed: int, *, std_fit: str = "mean"
) -> int:
    """Fit ``model``'s actor to the dataset's demonstrations (`agents.learning.rlpd.clone_actor`).

    ``std_fit``: where the actor's standard deviation is fitted around (`clone_actor`).

    Returns:
        The gradient steps taken.

    Raises:
        ConfigError: The model has no SAC-style actor.
        DemoSpaceError: The dataset's spaces differ from the model's.
    """
    from agents.learning.demos import load_demos  # noqa: PLC0415
    from agents.learning.rlpd import clone_actor  # noqa: PLC0415

    if not hasattr(model, "actor"):
        raise ConfigError(f"bc_epochs needs an actor-critic with an actor (SAC), got {model}")
    demos = load_demos(dataset_id, model.observation_space, model.action_space, Path(root))
    clone_actor(model, demos, epochs=epochs, batch_size=BC_BATCH, seed=seed, std_fit=std_fit)
    return epochs * math.ceil(len(demos) / BC_BATCH)


def demo_normalized_kwargs(
    policy_kwargs: dict[str, Any], dataset_id: str, root: str | Path, venv: Any
) -> dict[str, Any]:
    """``policy_kwargs`` with the demos' `agents.learning.obs_norm.NormalizedStateExtractor`.

    Raises:
        DemoSpaceError: The dataset's spaces differ from the envs'.
    """
    from agents.learning.demos import load_demos  # noqa: PLC0415
    from agents.learning.obs_norm import normalized_policy_kwargs  # noqa: PLC0415

    demos = load_demos(dataset_id, venv.observation_space, venv.action_space, Path(root))
    return normalized_policy_kwargs(policy_kwargs, demos.observations, venv.observation_space)


def policy_kwargs_for(cfg: Any, venv: Any, root: str | Path) -> dict[str, Any]:
    """A `TrainConfig`'s ``policy_kwargs``, standardised on its ``demos`` if ``normalize_obs``."""
    kwargs = dict(cfg.policy_kwargs)
    if cfg.normalize_obs:
        return demo_normalized_kwargs(kwargs, cfg.demos, root, venv)
    return kwargs


def demo_callbacks(cfg: Any) -> list[Any]:
    """Callbacks of learning from demonstrations of a `TrainConfig`.

    `agents.learning.rlpd.hold_actor` if ``hold_actor_steps`` > 0,
    `agents.learning.actor_bc.actor_bc` (a behaviour-cloning term in the actor's loss) if
    ``actor_bc_weight`` > 0.
    """
    callbacks: list[Any] = []
    if cfg.hold_actor_steps:
        from agents.learning.rlpd import hold_actor  # noqa: PLC0415

        callbacks.append(hold_actor(cfg.hold_actor_steps))
    if cfg.actor_bc_weight:
        from agents.learning.actor_bc import actor_bc  # noqa: PLC0415

        callbacks.append(actor_bc(cfg.actor_bc_weight, cfg.actor_bc_decay_steps))
    return callbacks


__all__ = [
    "BC_BATCH",
    "CLASS_SUFFIX",
    "clone_before_learning",
    "demo_callbacks",
    "demo_normalized_kwargs",
    "policy_kwargs_for",
    "resolve_algo_kwargs",
    "resolve_named",
]
