"""The task ladder: registered, versioned Gymnasium ids, each a frozen bundled configuration.

Every rung is a YAML file in ``configs/tasks/`` (`BenchmarkTask` documents the keys): the env
overrides of `MosaicAssembly-v0`, the episode limit, the held-out evaluation seeds (and designs)
and the horizon of the throughput metric. ``import envs`` registers them all::

    env = gym.make("MosaicDecision6-v0")                  # the bundled preset
    env = gym.make("MosaicDecision6-v0", obs_mode="rgb")  # keyword overrides still apply

From easy to the full cell: `MosaicOneTile-v0` (and ``...Joint-v0``), `MosaicDecision6-v0`,
`MosaicDecision16-v0`, `MosaicStream-v0`, `MosaicDistractors-v0`, `MosaicHeldOutDesigns-v0`.
`MosaicAssembly-v0` stays the fully configurable id.

Versions: a task file is the rung's ``-v0``; its ``versions`` map names each later version and
the env keys it changes (``v1``: ``invalid_actions: refuse``, ``pick_yaw_entry: false``, see
``CHANGELOG.md``). Every version is registered (``MosaicDecision6-v1`` beside
``MosaicDecision6-v0``); `bundled_tasks` gives the ``-v0`` ladder, ``bundled_tasks(True)``
every version, `get_task` any of them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import gymnasium as gym

from configs import CONFIG_DIR, ConfigError, from_dict, load_yaml
from configs.checks import check_fields, checked
from envs.errors import EnvError

TASKS_DIR = CONFIG_DIR / "tasks"
"""Folder of the bundled task configurations."""
ENTRY_POINT = "envs.mosaic_env:MosaicAssemblyEnv"
"""Every rung is the one environment class with its preset."""
SPLITS = ("train", "eval")
BASE_VERSION = "v0"
"""The version a task file describes (its ``id`` ends in ``-v0``)."""
"""Allowed ``split`` values of `BenchmarkTask.env_kwargs`."""
PROCEDURAL = "procedural"
"""Training design name meaning the procedural design source (`envs.design_source`)."""
DESIGN_KEYS = ("design", "design_source", "exclude_designs")
"""`EnvConfig` keys `BenchmarkTask.design_kwargs` sets for one design of a split."""


class TaskError(ConfigError, EnvError):
    """An unknown task id, split or design index, or a malformed task file."""


@dataclass(frozen=True)
class BenchmarkTask:
    """One rung of the ladder.

    Attributes:
        id: Registered Gymnasium id (``Name-v0``).
        description: One line saying what the rung tests.
        max_episode_steps: `TimeLimit` of the registered id [steps].
        horizon_s: Simulated time over which a failed episode's throughput is measured [s]
            (a successful one is measured to its completion).
        eval_seeds: Held-out reset seeds, inclusive range (lo, hi); training never resets
            with an explicit seed in it.
        env: `EnvConfig` overrides (flat keys of ``configs/env.yaml``).
        train_designs: Designs to train on (env i of a vector uses design i mod len); empty:
            ``env["design"]``. The name ``procedural`` (`envs.design_source.PROCEDURAL`)
            gives that env a new procedural design at every reset, never holding a tile
            class of the evaluation designs (``design_source: procedural`` with
            ``exclude_designs`` = the evaluation designs; `design_kwargs`).
        eval_designs: Held-out designs to evaluate on; empty: the training designs
            (``procedural`` excluded: evaluation designs are fixed).
        versions: Later versions of the rung (``v1``, ...) -> the `EnvConfig` keys each one
            changes on top of ``env`` (`at_version`).
    """

    id: str
    description: str
    max_episode_steps: int = checked(ge=1)
    horizon_s: float = checked(gt=0)
    eval_seeds: tuple[int, int] = checked(ge=0)
    env: Mapping[str, Any] = field(default_factory=dict)
    train_designs: tuple[str, ...] = ()
    eval_designs: tuple[str, ...] = ()
    versions: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        check_fields(self, TaskError, prefix=f"{self.id}: ")
        lo, hi = self.eval_seeds
        if not lo <= hi:
            raise TaskError(f"{self.id}: eval_seeds must be a range lo <= hi of seeds >= 0")
        if PROCEDURAL in self.eval_designs or PROCEDURAL == self.env.get("design"):
            raise TaskError(
                f"{self.id}: {PROCEDURAL!r} is allowed in train_designs only (evaluation "
                "designs and env.design are fixed designs)"
            )
        from envs.env_config import load_env_config  # noqa: PLC0415 - validates the keys

        load_env_config(**dict(self.env))
        version = self.id.rpartition("-")[2]
        for later, changes in self.versions.items():
            if version != BASE_VERSION or not later[1:].isdigit() or not later.startswith("v"):
                raise TaskError(
                    f"{self.id}: versions need a -{BASE_VERSION} id and names v1, v2, ...; got "
                    f"{later!r}"
                )
            load_env_config(**{**dict(self.env), **dict(changes)})

    @property
    def version(self) -> str:
        """The id's version (``v0``, ``v1``, ...)."""
        return self.id.rpartition("-")[2]

    def at_version(self, version: str) -> BenchmarkTask:
        """This rung at ``version``: the id renamed, ``env`` with that version's changes.

        Raises:
            TaskError: The task file names no such version (lists the ones it has).
        """
        if version == self.version:
            return self
        if version not in self.versions:
            raise TaskError(
                f"{self.id} has no version {version!r}; allowed: {[self.version, *self.versions]}"
            )
        env = {**dict(self.env), **dict(self.versions[version])}
        name = self.id.rpartition("-")[0]
        return replace(self, id=f"{name}-{version}", env=env, versions={})

    @property
    def seeds(self) -> list[int]:
        """The held-out evaluation seeds."""
        return list(range(self.eval_seeds[0], self.eval_seeds[1] + 1))

    def designs(self, split: str = "train") -> tuple[str, ...]:
        """Designs of a split (``train`` or ``eval``).

        Raises:
            TaskError: Unknown split.
        """
        if split not in SPLITS:
            raise TaskError(f"unknown split {split!r}; allowed: {list(SPLITS)}")
        train = self.train_designs or (str(self.env.get("design", "paper_mixed")),)
        fixed = tuple(d for d in train if d != PROCEDURAL) or (
            str(self.env.get("design", "paper_mixed")),
        )
        return train if split == "train" else (self.eval_designs or fixed)

    def design_kwargs(self, split: str = "train", design_index: int = 0) -> dict[str, Any]:
        """The `DESIGN_KEYS` overrides of one design of a split.

        A fixed design gives ``{"design": name}``; the training name ``procedural`` gives
        ``{"design_source": "procedural", "exclude_designs": <the eval designs>}``.
        """
        designs = self.designs(split)
        name = designs[design_index % len(designs)]
        if name != PROCEDURAL:
            return {"design": name}
        return {"design_source": PROCEDURAL, "exclude_designs": list(self.designs("eval"))}

    def env_kwargs(self, split: str = "train", design_index: int = 0) -> dict[str, Any]:
        """`MosaicAssembly-v0` overrides of this rung for one design of a split."""
        return {**dict(self.env), **self.design_kwargs(split, design_index)}


def load_task(name_or_path: str | Path) -> BenchmarkTask:
    """A task from a file in ``configs/tasks/`` (by stem) or a path, loaded strictly.

    Raises:
        ConfigError: Unknown key or bad value (names the file).
    """
    data = load_yaml(name_or_path, "tasks")
    for key in ("eval_seeds", "train_designs", "eval_designs"):
        if key in data:
            data[key] = tuple(data[key])
    return from_dict(BenchmarkTask, data, source=str(name_or_path))


def bundled_tasks(all_versions: bool = False) -> dict[str, BenchmarkTask]:
    """Every bundled rung by id, easiest first (file order of the ladder).

    Args:
        all_versions: Also every later version of each rung (after the ``-v0`` ladder,
            version by version, each easiest first); default the ``-v0`` ids only.
    """
    out: dict[str, BenchmarkTask] = {}
    for path in sorted(TASKS_DIR.glob("*.yaml"), key=lambda p: LADDER.index(p.stem)):
        task = load_task(path)
        out[task.id] = task
    if all_versions:
        later = sorted({v for t in out.values() for v in t.versions}, key=lambda v: int(v[1:]))
        for version in later:
            for task in list(out.values()):
                if version in task.versions:
                    moved = task.at_version(version)
                    out[moved.id] = moved
    return out


LADDER = (
    "one_tile",
    "one_tile_joint",
    "decision6",
    "decision16",
    "stream",
    "distractors",
    "held_out_designs",
)
"""File stems of the bundled rungs, easiest first."""


def get_task(task_id: str) -> BenchmarkTask:
    """The bundled rung with id ``task_id`` (``envs:`` prefix allowed).

    Raises:
        TaskError: No such rung (lists the ids).
    """
    tasks = bundled_tasks(all_versions=True)
    key = task_id.removeprefix("envs:")
    if key not in tasks:
        raise TaskError(f"unknown task {task_id!r}; bundled: {list(tasks)}")
    return tasks[key]


def register_tasks() -> list[str]:
    """Register every bundled rung with Gymnasium (idempotent); returns the ids."""
    ids = []
    for task in bundled_tasks(all_versions=True).values():
        if task.id not in gym.registry:
            gym.register(
                id=task.id,
                entry_point=ENTRY_POINT,
                max_episode_steps=task.max_episode_steps,
                kwargs=task.env_kwargs("train"),
            )
        ids.append(task.id)
    return ids


__all__ = [
    "DESIGN_KEYS",
    "LADDER",
    "PROCEDURAL",
    "BenchmarkTask",
    "TaskError",
    "bundled_tasks",
    "get_task",
    "load_task",
    "register_tasks",
]
