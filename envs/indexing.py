"""Index maps of the decision-level encoding: which tile, slot and rotation an index names.

A decision-level action ``(tile, slot, rotation)`` and the privileged ``tiles``/``slots``
observation refer to tiles and slots by index. If tile ``i`` were always built from design slot
``i`` and rotation 0 were always right, the open-loop sequence ``(i, i, 0)`` would solve every
episode without looking. The maps here remove that answer from the encoding:

- ``tile_order``: ``belt`` (default): agent tile ``i`` is the ``i``-th tile on the input belt,
  counted from the downstream end (largest x first, then y), recomputed at every observation,
  so an index names what the input camera shows; tiles not on the input belt follow in an order
  shuffled per reset. ``shuffled``: one random permutation per reset. ``design``: the design
  order (leaks the answer; kept for comparisons).
- ``slot_order``: ``mesh`` (default): slots in raster order of their position on the mesh (top
  row first, left to right), what the output camera shows, independent of the design's list
  order. ``shuffled``: one random permutation per reset. ``design``: the design order.
- ``rotation_frame``: ``tile`` (default): rotation ``r`` turns the tile by ``r`` steps of
  ``2 pi / rotation_bins`` from the slot-aligned pose nearest to how the tile lies now (r = 0:
  the smallest turn), so the right index depends on the tile's yaw as the camera sees it.
  ``shape``: as ``tile``, but the tile's offset from its slot is counted modulo the figure's
  rotational symmetry before rounding (into half a period either side), so the right index
  depends only on how the tile looks: under ``tile`` a hexagon lying 60 deg from its slot looks
  the same as one lying 0 deg but rounds to another index, which no camera can tell (for
  figures whose symmetry period is not a multiple of a rotation step). ``slot``: ``r`` steps
  from the slot's own yaw (0 always right).

All randomness comes from the generator passed to `IndexMaps.reset` (the env's
``np_random``).
"""

from __future__ import annotations

import math

import numpy as np

from envs.cell.cell import Cell
from envs.env_config import EnvConfig
from envs.task_spec import rotation_step
from spatial.angles import symmetry_period

ROW_DECIMALS = 3
"""Slot rows: y positions rounded to this many decimals of a metre group slots into one row."""


class IndexMaps:
    """Per-reset and per-observation maps between agent indices and the cell's indices.

    Args:
        cell: The cell (tiles, slots, poses).
        config: Environment configuration (``tile_order``, ``slot_order``,
            ``rotation_frame``, ``rotation_bins``).

    Attributes:
        tiles: Agent tile index -> cell tile index, shape (n,) int.
        slots: Agent slot index -> cell slot index, shape (k,) int.
    """

    def __init__(self, cell: Cell, config: EnvConfig) -> None:
        self.cell = cell
        self.cfg = config
        n, k = len(cell.tiles), len(cell.slots)
        self.tiles = np.arange(n)
        self.slots = np.arange(k)
        self._rest = np.arange(n)
        self._mesh_order = raster_order(cell.slot_poses_world()[:, :2]) if k else self.slots
        self._step = rotation_step(config.rotation_bins)

    def reset(self, rng: np.random.Generator) -> None:
        """Draw the per-reset permutations, then compute the tile order of the first observation."""
        n, k = len(self.cell.tiles), len(self.cell.slots)
        self._rest = rng.permutation(n)
        order = self.cfg.slot_order
        if order == "mesh":
            self.slots = self._mesh_order.copy()
        elif order == "shuffled":
            self.slots = rng.permutation(k)
        else:
            self.slots = np.arange(k)
        if self.cfg.tile_order == "design":
            self.tiles = np.arange(n)
        elif self.cfg.tile_order == "shuffled":
            self.tiles = self._rest.copy()
        self.update()

    def update(self) -> None:
        """Recompute the ``belt`` tile order from where the tiles lie now (before observing)."""
        if self.cfg.tile_order != "belt" or not len(self.cell.tiles):
            return
        cell = self.cell
        x, y = cell.tile_xy().T.tolist()
        on_input = cell.input_half().tolist()
        # Downstream first (x descending), then across (y ascending); a stable sort.
        first = sorted((i for i, on in enumerate(on_input) if on), key=lambda i: (-x[i], y[i]))
        rest = [i for i in self._rest.tolist() if not on_input[i]]
        self.tiles = np.array(first + rest, dtype=int)

    def decode(self, action: np.ndarray) -> np.ndarray:
        """Agent ``(tile, slot, rotation)`` -> the cell's ``(tile, slot, steps from slot yaw)``."""
        tile = int(self.tiles[int(action[0])])
        slot = int(self.slots[int(action[1])])
        rot = int(action[2])
        if self.cfg.rotation_frame != "slot":
            rot = (rot + self._base(tile, slot)) % self.cfg.rotation_bins
        return np.array([tile, slot, rot], dtype=np.int64)

    def encode(self, tile: int, slot: int, slot_steps: int = 0) -> np.ndarray:
        """The agent action moving cell ``tile`` into ``slot``, ``slot_steps`` from its yaw.

        Inverse of `decode` for the current maps (the privileged expert's action).
        """
        rot = slot_steps
        if self.cfg.rotation_frame != "slot":
            rot = (slot_steps - self._base(tile, slot)) % self.cfg.rotation_bins
        return np.array(
            [
                int(np.flatnonzero(self.tiles == tile)[0]),
                int(np.flatnonzero(self.slots == slot)[0]),
                rot,
            ],
            dtype=np.int64,
        )

    def permute_state(self, tiles: np.ndarray, slots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Privileged ``tiles`` and ``slots`` rows in agent order.

        Flat ``state`` rows (n * d,) and (k * e,) stay flat; ``objects`` rows (rows, D) stay
        2-D, their first n (k) rows permuted and the zero padding after them kept.
        """
        n, k = len(self.tiles), len(self.slots)
        if tiles.ndim == 2:  # noqa: PLR2004 - objects rows
            tiles[:n], slots[:k] = tiles[self.tiles], slots[self.slots]
            return tiles, slots
        t = tiles.reshape(n, -1)[self.tiles].reshape(-1) if n else tiles
        s = slots.reshape(k, -1)[self.slots].reshape(-1) if k else slots
        return t, s

    def _base(self, tile: int, slot: int) -> int:
        """Steps from the slot's yaw to the slot-aligned pose nearest the tile's yaw now."""
        tile_yaw = float(self.cell.tile_poses().yaw[tile])
        slot_yaw = float(self.cell.slot_poses_world()[slot, 2])
        period = 2 * math.pi
        if self.cfg.rotation_frame == "shape":
            period = symmetry_period(self.cell.tiles[tile].shape.symmetry)
            if period == 0:  # a round tile: every yaw is its slot's
                return 0
        d = math.remainder(tile_yaw - slot_yaw, period)
        return round(d / self._step) % self.cfg.rotation_bins


def raster_order(xy: np.ndarray) -> np.ndarray:
    """Indices of points in raster order: rows by y descending, each row by x ascending."""
    rows = -np.round(xy[:, 1], ROW_DECIMALS)
    return np.lexsort((xy[:, 0], rows)).astype(int)


__all__ = ["IndexMaps", "raster_order"]
