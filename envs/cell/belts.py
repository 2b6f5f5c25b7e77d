"""Conveyor belts: input speed through ``geom_surfacevel`` and lost-tile accounting."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from envs.cell.config import CellConfig
from envs.cell.scene import SceneIds, cell_geometry
from envs.errors import CellError


def set_input_speed(model: mujoco.MjModel, ids: SceneIds, speed: float) -> None:
    """Set the input belt's surface speed along +x [m/s] at run time.

    Sleeping tiles do not notice the change: wake them (`Cell` does this on its next step).

    Raises:
        CellError: Negative or non-finite speed.
    """
    if not (math.isfinite(speed) and speed >= 0):
        raise CellError(f"belt speed must be finite and >= 0 m/s, got {speed!r}")
    model.geom_surfacevel[ids.input_belt_geom, 0] = speed
    # MuJoCo only applies surface velocities when this compile-time flag is set.
    model.flg_surfacevel = int(np.any(model.geom_surfacevel != 0))


def input_speed(model: mujoco.MjModel, ids: SceneIds) -> float:
    """The input belt's surface speed [m/s]."""
    return float(model.geom_surfacevel[ids.input_belt_geom, 0])


class LostTracker:
    """Counts tiles lost: past the input belt's end (into the bin) or fallen below belt level.

    A tile the pad releases over the bin is rejected on purpose (`reject_if_over_bin`), not lost.

    Args:
        cfg: Cell configuration.
        n_tiles: Number of tiles.
    """

    def __init__(self, cfg: CellConfig, n_tiles: int) -> None:
        geo = cell_geometry(cfg)
        self._x_end = geo.input_belt_end
        self._y = geo.input_y
        self._half_w = cfg.input_belt.width / 2 + 0.05
        self._z_min = geo.belt_top - cfg.input_belt.lost_margin
        self.lost = np.zeros(n_tiles, bool)
        self.rejected = np.zeros(n_tiles, bool)
        """Tiles released by the pad over the reject bin, shape (n,) bool."""

    def reset(self) -> None:
        """No tile lost or rejected."""
        self.lost[:] = False
        self.rejected[:] = False

    def over_bin(self, pos: np.ndarray) -> np.ndarray:
        """Points over the bin past the input belt's end, for positions of shape (..., 3) [m]."""
        return (pos[..., 0] > self._x_end) & (np.abs(pos[..., 1] - self._y) < self._half_w)

    def reject_if_over_bin(self, tile: int, pos: np.ndarray) -> bool:
        """Count a tile the pad just released at ``pos`` (3,) [m] as rejected if over the bin."""
        if tile >= 0 and bool(self.over_bin(pos)) and not self.lost[tile]:
            self.rejected[tile] = True
            return True
        return False

    @property
    def count(self) -> int:
        """Number of tiles lost so far."""
        return int(self.lost.sum())

    def update(self, pos: np.ndarray, on_stage: np.ndarray, held: int) -> np.ndarray:
        """Mark newly lost tiles.

        Args:
            pos: Tile positions, shape (n, 3) [m].
            on_stage: Tiles that have been fed into the cell, shape (n,).
            held: Index of the tile on the pad (never lost), or -1.

        Returns:
            Indices of tiles lost in this update.
        """
        fell = pos[:, 2] < self._z_min
        now = on_stage & (self.over_bin(pos) | fell) & ~self.lost & ~self.rejected
        if held >= 0:
            now[held] = False
        self.lost |= now
        return np.flatnonzero(now)


__all__ = ["LostTracker", "input_speed", "set_input_speed"]
