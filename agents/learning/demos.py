"""Demonstration datasets (Minari) as transitions for learning: loading, space checks.

A dataset recorded by ``apps.record_demos`` is read from a local folder (never downloaded) and
turned into flat transitions (observation, action, reward, next observation, termination) for a
replay buffer (`agents.learning.rlpd.DemoMixReplayBuffer`) or behaviour cloning. A dataset whose
observation or action space differs from the env's is refused with `DemoSpaceError`, which
names both spaces: transitions of another action mode or observation layout would train on
garbage without any other error.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from agents.errors import AgentError

DEFAULT_ROOT = Path("out/minari")
"""Default dataset root (``MINARI_DATASETS_PATH``)."""


class DemoDatasetError(AgentError):
    """A demonstration dataset that is missing or cannot be read."""


class DemoSpaceError(DemoDatasetError):
    """A demonstration dataset whose observation or action space differs from the env's."""


@contextlib.contextmanager
def datasets_root(root: Path) -> Iterator[None]:
    """Point ``MINARI_DATASETS_PATH`` at ``root`` for the block (restored afterwards)."""
    old = os.environ.get("MINARI_DATASETS_PATH")
    root.mkdir(parents=True, exist_ok=True)
    os.environ["MINARI_DATASETS_PATH"] = str(root.resolve())
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("MINARI_DATASETS_PATH", None)
        else:
            os.environ["MINARI_DATASETS_PATH"] = old


def load_dataset(dataset_id: str, root: Path = DEFAULT_ROOT) -> Any:
    """Load a local Minari dataset (never downloads).

    Raises:
        DemoDatasetError: No complete dataset ``dataset_id`` under ``root``.
    """
    import minari  # noqa: PLC0415 - optional heavy import

    with datasets_root(Path(root)):
        path = Path(os.environ["MINARI_DATASETS_PATH"]) / dataset_id
        if not path.is_dir():
            raise DemoDatasetError(f"no dataset {dataset_id!r} under {root} (record it first)")
        try:
            return minari.load_dataset(dataset_id, download=False)
        except (OSError, ValueError, KeyError) as exc:
            raise DemoDatasetError(
                f"dataset {dataset_id!r} under {root} cannot be read: {exc}"
            ) from exc


def check_spaces(
    dataset: Any, observation_space: spaces.Space, action_space: spaces.Space, name: str = ""
) -> None:
    """Refuse a dataset whose spaces differ from the env's.

    Raises:
        DemoSpaceError: The observation or the action space differs (both spaces named).
    """
    label = name or getattr(getattr(dataset, "spec", None), "dataset_id", "dataset")
    for what, theirs, mine in (
        ("observation", dataset.observation_space, observation_space),
        ("action", dataset.action_space, action_space),
    ):
        if theirs != mine:
            raise DemoSpaceError(
                f"demonstrations {label!r}: their {what} space {theirs} differs from the env's "
                f"{mine}; record demonstrations on the env (task and keys) that learns from them"
            )


@dataclass(frozen=True)
class Transitions:
    """Flat transitions of a dataset's episodes.

    Attributes:
        observations: Per observation key, shape (n, ...) (n, then the key's shape).
        actions: Shape (n, ...) (n, then the action shape).
        rewards: Shape (n,).
        next_observations: Per key, the observation after each action, shape (n, ...).
        terminations: 1.0 where the episode terminated (not truncated) at that step, shape (n,).
        episodes: Episodes read.
    """

    observations: dict[str, np.ndarray]
    actions: np.ndarray
    rewards: np.ndarray
    next_observations: dict[str, np.ndarray]
    terminations: np.ndarray
    episodes: int

    def __len__(self) -> int:
        return len(self.actions)


def transitions(dataset: Any) -> Transitions:
    """The dataset's episodes as flat transitions (Dict or Box observations).

    Raises:
        DemoDatasetError: The dataset holds no steps.
    """
    obs: dict[str, list[np.ndarray]] = {}
    nxt: dict[str, list[np.ndarray]] = {}
    actions, rewards, terms = [], [], []
    episodes = 0
    for ep in dataset.iterate_episodes():
        episodes += 1
        o = ep.observations if isinstance(ep.observations, dict) else {"obs": ep.observations}
        for key, value in o.items():
            arr = np.asarray(value)
            obs.setdefault(key, []).append(arr[:-1])
            nxt.setdefault(key, []).append(arr[1:])
        actions.append(np.asarray(ep.actions))
        rewards.append(np.asarray(ep.rewards, np.float32))
        terms.append(np.asarray(ep.terminations, np.float32))
    if not actions:
        raise DemoDatasetError("the dataset holds no episodes")
    return Transitions(
        {k: np.concatenate(v) for k, v in obs.items()},
        np.concatenate(actions),
        np.concatenate(rewards),
        {k: np.concatenate(v) for k, v in nxt.items()},
        np.concatenate(terms),
        episodes,
    )


def load_demos(
    dataset_id: str,
    observation_space: spaces.Space,
    action_space: spaces.Space,
    root: Path = DEFAULT_ROOT,
) -> Transitions:
    """Load a dataset's transitions after checking its spaces against the env's.

    Raises:
        DemoDatasetError: Missing or unreadable dataset.
        DemoSpaceError: Its spaces differ from ``observation_space``/``action_space``.
    """
    dataset = load_dataset(dataset_id, root)
    check_spaces(dataset, observation_space, action_space, dataset_id)
    return transitions(dataset)


__all__ = [
    "DEFAULT_ROOT",
    "DemoDatasetError",
    "DemoSpaceError",
    "Transitions",
    "check_spaces",
    "datasets_root",
    "load_dataset",
    "load_demos",
    "transitions",
]
