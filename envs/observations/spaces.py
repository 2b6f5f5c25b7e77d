"""Observations of `MosaicAssembly-v0`: a Dict space built from the cell's sensors.

Keys (by ``obs_mode``):

- ``input_camera``, ``output_camera`` (``rgb``, ``rgb+state``): RGB uint8, (H, W, 3).
- ``input_depth``, ``output_depth`` (with ``depth=True``): float32 (H, W, 1) [m].
- ``robot`` (always): float32 (19,) = joint positions (6) [rad], joint velocities (6) [rad/s],
  tool position (3) [m], tool yaw as (cos, sin) (2), vacuum on (1), tile held (1).
- ``tiles`` and ``slots`` (``state``, ``rgb+state``; privileged), flattened 1-D (SB3's
  MultiInputPolicy wants vectors): float32 (n * 7,), per tile
  x, y, z [m], cos yaw, sin yaw, class index, present (on the belts and not lost); float32
  (k * 6,), per slot x, y [m], cos yaw, sin yaw, class index, filled correctly.
- ``tiles`` and ``slots`` (``objects``; no class ids): float32 (rows, D), one entity row per
  tile / slot (outline points [mm], colour, area, hole area, position, yaw, flag, valid),
  laid out by `envs.observations.objects.OBJECT_FIELDS`; rows past the episode's counts are zero
  padding. With ``objects_source="perception"`` the tile rows come from the input camera's picture
  (`envs.observations.objects_perception`): a tile not seen there is a masked row of zeros.

The ``state`` vectors' field maps are `envs.observations.fields`. Every observation is a fresh
array (no memory shared between steps).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from envs.cell.cell import CAMERAS, Cell
from envs.env_config import EnvConfig
from envs.observations.fields import ROBOT_DIM, SLOT_DIM, TILE_DIM
from envs.observations.objects import ObjectRows
from envs.observations.objects_perception import PerceivedTiles
from envs.task import Evaluation, MosaicTask
from spatial.rotations import yaw_from_matrix, yaw_from_quat

DEPTH_MAX = 10.0
"""Upper bound of depth values [m] (the far plane is well below)."""
BIG = 1e3
"""Bound of unbounded float features (positions [m], velocities [rad/s])."""


class Observer:
    """Builds the observation space and observations of one cell.

    Args:
        cell: The cell.
        task: The task (slot fill and classes).
        config: Environment configuration (obs_mode, image_size, depth, obs_noise, the
            ``objects_*`` keys).
    """

    def __init__(self, cell: Cell, task: MosaicTask, config: EnvConfig) -> None:
        self.cell = cell
        self.task = task
        self.cfg = config
        self.images = config.obs_mode in ("rgb", "rgb+state")
        self.state = config.obs_mode in ("state", "rgb+state")
        self.objects = ObjectRows(cell, task, config) if config.obs_mode == "objects" else None
        self.perceived = (
            PerceivedTiles(cell, config, self.objects.fields, self.objects.dim)
            if self.objects is not None and config.objects_source == "perception"
            else None
        )
        h, w = config.image_size
        d: dict[str, spaces.Space] = {}
        if self.images:
            for name in CAMERAS:
                d[name] = spaces.Box(0, 255, (h, w, 3), np.uint8)
                if config.depth:
                    d[_depth_key(name)] = spaces.Box(0.0, DEPTH_MAX, (h, w, 1), np.float32)
        d["robot"] = spaces.Box(-BIG, BIG, (ROBOT_DIM,), np.float32)
        if self.state:
            n, k = len(cell.tiles), len(cell.slots)
            d["tiles"] = spaces.Box(-BIG, BIG, (n * TILE_DIM,), np.float32)
            d["slots"] = spaces.Box(-BIG, BIG, (k * SLOT_DIM,), np.float32)
        if self.objects is not None:
            d.update(self.objects.spaces())
        self.space = spaces.Dict(d)
        self._slot_rows = self._slot_constants() if self.state else None
        """The ``slots`` rows without the filled flag (x, y, cos yaw, sin yaw, class), shape
        (k, 6) float32: the slots and their classes are fixed for the cell and task this
        observer is built with (a new design builds a new observer), so nothing invalidates it."""

    def observe(self, rng: np.random.Generator, evaluation: Evaluation) -> dict[str, Any]:
        """The current observation (fresh arrays).

        Args:
            rng: Generator for observation noise.
            evaluation: The task's current `Evaluation` (slot fill).
        """
        cell, (h, w) = self.cell, self.cfg.image_size
        obs: dict[str, Any] = {}
        if self.images:
            for name in CAMERAS:
                obs[name] = cell.render(name, h, w)
                if self.cfg.depth:
                    depth = cell.render(name, h, w, depth=True)
                    obs[_depth_key(name)] = np.clip(depth, 0.0, DEPTH_MAX)[..., None].astype(
                        np.float32
                    )
        obs["robot"] = self._robot(rng)
        if self.state:
            obs["tiles"], obs["slots"] = self._state(evaluation)
        if self.objects is not None:
            obs["tiles"], obs["slots"] = self.objects.observe(rng, evaluation)
            if self.perceived is not None:  # tile rows from the input picture instead
                obs["tiles"] = self.perceived.observe(obs["tiles"])
        return obs

    def _robot(self, rng: np.random.Generator) -> np.ndarray:
        cell = self.cell
        d, ids = cell.data, cell.ids
        v = np.empty(ROBOT_DIM)
        v[:6] = d.qpos[ids.arm_qpos]
        if self.cfg.obs_noise > 0:
            v[:6] += rng.normal(0.0, self.cfg.obs_noise, 6)
        v[6:12] = d.qvel[ids.arm_dof]
        v[12:15] = d.site_xpos[ids.tcp_site]
        yaw = yaw_from_matrix(d.site_xmat[ids.tcp_site].reshape(3, 3))
        v[15], v[16] = np.cos(yaw), np.sin(yaw)
        v[17], v[18] = cell.vacuum_on, cell.tile_held
        return np.minimum(np.maximum(v, -BIG), BIG).astype(np.float32)

    def _state(self, evaluation: Evaluation) -> tuple[np.ndarray, np.ndarray]:
        cell, task = self.cell, self.task
        q = cell.data.qpos[cell.ids.tile_qpos_index]  # position, quaternion (w, x, y, z)
        yaw = yaw_from_quat(q[:, 3:])
        tiles = np.empty((len(q), TILE_DIM))
        tiles[:, :3] = q[:, :3]
        tiles[:, 3], tiles[:, 4] = np.cos(yaw), np.sin(yaw)
        tiles[:, 5] = task.tile_class
        tiles[:, 6] = cell.on_stage & ~cell.lost_tracker.lost
        slots = self._slot_rows.copy()  # type: ignore[union-attr] # set in state modes
        slots[:, 5] = evaluation.slot_filled
        return (
            np.minimum(np.maximum(tiles, -BIG), BIG).astype(np.float32).reshape(-1),
            slots.reshape(-1),
        )

    def _slot_constants(self) -> np.ndarray:
        """The ``slots`` rows with the filled flag 0, shape (k, 6) float32."""
        s = self.task.slot_xyyaw
        rows = np.zeros((len(s), SLOT_DIM))
        rows[:, :2] = s[:, :2]
        rows[:, 2], rows[:, 3] = np.cos(s[:, 2]), np.sin(s[:, 2])
        rows[:, 4] = self.task.slot_class
        return rows.astype(np.float32)


def _depth_key(camera: str) -> str:
    return camera.replace("_camera", "_depth")


__all__ = ["ROBOT_DIM", "SLOT_DIM", "TILE_DIM", "Observer"]
