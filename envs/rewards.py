"""Staged dense reward of the one-tile low-level task: reach, seal, lift, transport, align, release.

Each stage has a progress potential in [0, 1] computed from the cell's state; the reward term of
a stage is its weight times the change of its potential since the previous step (potential-based
shaping: the terms of an episode telescope, so hovering or holding a tile forever earns
nothing, and undoing progress, e.g. dropping the tile, costs what reaching it earned).

Potentials, for the target tile (the held wanted tile, else the wanted tile nearest the pad) and
its target slot (the nearest open slot of its class):

- ``reach``: 1 - tanh(pad-to-grasp-point distance / ``reach_scale``); 1 while holding it.
- ``seal``: 1 while the pad holds a wanted tile.
- ``lift``: held tile's height above its resting height / ``lift_height``, clipped to 1 and
  kept at 1 once reached for as long as the tile stays held.
- ``transport``: lift x (1 - tanh(xy distance tile-to-slot / ``transport_scale``)).
- ``align``: within ``align_distance`` of the slot, (1 - distance / align_distance) x
  (1 - yaw error / half the tile's symmetry period).
- ``release``: fraction f of the slots filled correctly. Every other stage's potential is
  f + (1 - f) x its progress on the current target, so filled slots count as completed stages
  and the finished mosaic is the most valuable state.

Weights and scales: `StagedRewardConfig` (``configs/rewards.yaml``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from configs import load_config
from configs.checks import check_fields, checked
from envs.cell.cell import Cell
from spatial.angles import rotate_xy, yaw_error

STAGES = ("reach", "seal", "lift", "transport", "align", "release")
"""Stage names; reward terms are ``stage_<name>`` (``info["reward_stage_<name>"]``)."""
REWARDS_CONFIG = "rewards"
"""Bundled config name (``configs/rewards.yaml``)."""


@dataclass(frozen=True)
class StagedRewardConfig:
    """Weights and scales of the staged reward.

    Attributes:
        reach: Weight of the reach potential (reward over the whole stage).
        seal: Weight of the seal potential.
        lift: Weight of the lift potential.
        transport: Weight of the transport potential.
        align: Weight of the align potential.
        release: Weight of the release potential (per fraction of the slots filled).
        reach_scale: Distance scale of the reach potential [m].
        lift_height: Height above rest that completes the lift stage [m].
        transport_scale: Distance scale of the transport potential [m].
        align_distance: Distance to the slot within which alignment counts [m].
    """

    reach: float = 1.0
    seal: float = 1.0
    lift: float = 1.0
    transport: float = 2.0
    align: float = 1.0
    release: float = 4.0
    reach_scale: float = checked(0.3, gt=0)
    lift_height: float = checked(0.03, gt=0)
    transport_scale: float = checked(0.3, gt=0)
    align_distance: float = checked(0.02, gt=0)

    def __post_init__(self) -> None:
        from envs.errors import CellError  # noqa: PLC0415 - the envs base error

        check_fields(self, CellError, prefix="staged reward: ")


def load_staged_config(
    name_or_path: str | None = REWARDS_CONFIG, **overrides: Any
) -> StagedRewardConfig:
    """Load a `StagedRewardConfig` strictly (unknown keys are a `configs.ConfigError`)."""
    return load_config(StagedRewardConfig, name_or_path, **overrides)


class SlotProgress(Protocol):
    """What the staged reward reads of an evaluation (`envs.task.Evaluation` is one)."""

    @property
    def correct(self) -> int:
        """Slots filled correctly."""

    @property
    def slots(self) -> int:
        """Number of slots."""

    @property
    def slot_filled(self) -> tuple[bool, ...]:
        """Per slot: filled correctly."""


class ShapedTask(Protocol):
    """What the staged reward reads of its task (`envs.task.MosaicTask` is one).

    Arrays as the task's: ``distractor``, ``tile_class``, ``symmetry`` one row per tile;
    ``slot_class`` and ``slot_xyyaw`` (x, y [m], yaw [rad]) one row per slot.
    """

    cell: Cell
    distractor: np.ndarray
    tile_class: np.ndarray
    symmetry: np.ndarray
    slot_class: np.ndarray
    slot_xyyaw: np.ndarray

    def wanted_tiles(self, evaluation: SlotProgress) -> np.ndarray:
        """Real tiles on the input side whose class fills an open slot, shape (n,) bool."""


class StagedReward:
    """Potential-based staged reward terms of one task.

    Args:
        task: The task (cell, classes, slots, symmetry periods).
        config: Weights and scales.
    """

    def __init__(self, task: ShapedTask, config: StagedRewardConfig) -> None:
        self.task = task
        self.cfg = config
        cell = task.cell
        self._rest_z = float(cell.geometry.input_centre[2] + cell.cfg.tiles.thickness / 2)
        self._lifted = False
        self._prev = dict.fromkeys(STAGES, 0.0)

    def reset(self, evaluation: SlotProgress) -> None:
        """Episode start: potentials of the initial state."""
        self._lifted = False
        self._prev = self.potentials(evaluation)

    def terms(self, evaluation: SlotProgress) -> dict[str, float]:
        """``stage_<name>`` reward terms: weight x change of each potential since the last call."""
        now = self.potentials(evaluation)
        out = {f"stage_{s}": float(getattr(self.cfg, s)) * (now[s] - self._prev[s]) for s in STAGES}
        self._prev = now
        return out

    def potentials(self, evaluation: SlotProgress) -> dict[str, float]:
        """Potential of each stage in [0, 1] now (see the module docstring)."""
        done = float(evaluation.correct) / max(int(evaluation.slots), 1)
        progress = self._progress(evaluation)
        pot = {s: done + (1 - done) * progress[s] for s in STAGES}
        pot["release"] = done
        return pot

    def _progress(self, evaluation: SlotProgress) -> dict[str, float]:
        """Progress of each stage on the current target tile, in [0, 1]."""
        task, cfg = self.task, self.cfg
        cell = task.cell
        pot = dict.fromkeys(STAGES, 0.0)
        filled = np.asarray(evaluation.slot_filled, bool)
        held = cell.held_tile
        poses = cell.tile_poses()
        if held >= 0 and not task.distractor[held]:
            free = np.flatnonzero(~filled & (task.slot_class == task.tile_class[held]))
            if len(free):
                pot["reach"] = pot["seal"] = 1.0
                h = (float(poses.pos[held, 2]) - self._rest_z) / cfg.lift_height
                self._lifted = self._lifted or h >= 1.0
                pot["lift"] = 1.0 if self._lifted else float(np.clip(h, 0.0, 1.0))
                xy = poses.pos[held, :2]
                d = np.linalg.norm(task.slot_xyyaw[free, :2] - xy, axis=1)
                j = int(free[np.argmin(d)])
                dist = float(d.min())
                pot["transport"] = pot["lift"] * (1 - math.tanh(dist / cfg.transport_scale))
                pot["align"] = self._align(held, j, dist)
                return pot
        self._lifted = False
        wanted = np.flatnonzero(task.wanted_tiles(evaluation))
        if len(wanted):
            tool = cell.tcp_pose()[0]
            grasp = np.array([poses.pos[i] for i in wanted])
            for row, i in enumerate(wanted):
                g = cell.tiles[i].grasp
                grasp[row, :2] += rotate_xy(g[:2], float(poses.yaw[i]))
            d = float(np.linalg.norm(grasp - tool, axis=1).min())
            pot["reach"] = 1 - math.tanh(d / cfg.reach_scale)
        return pot

    def _align(self, tile: int, slot: int, dist: float) -> float:
        near = max(0.0, 1 - dist / self.cfg.align_distance)
        if near == 0.0:
            return 0.0
        sym = int(self.task.symmetry[tile])
        if sym <= 0:
            return near  # continuous symmetry: any yaw fits
        yaw = float(self.task.cell.tile_poses().yaw[tile])
        err = float(yaw_error(yaw, float(self.task.slot_xyyaw[slot, 2]), sym))
        return near * (1 - err / (math.pi / sym))


__all__ = [
    "STAGES",
    "ShapedTask",
    "SlotProgress",
    "StagedReward",
    "StagedRewardConfig",
    "load_staged_config",
]
