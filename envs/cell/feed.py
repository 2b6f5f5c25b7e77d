"""Tile feeding: which tiles are on the input belt, and when (``all``, ``stream``, ``batch``).

`TileFeed` owns the feed's episode state (the feed order, the next feed time, a batch's due
time, the retired tiles) and decides; the `Cell` does the physics (`Cell.place_tiles`,
`Cell.park_tiles`) and calls `TileFeed.update` after its physics steps.

- ``all``: every tile is laid out at random over the tile area at reset.
- ``stream``: ``stream_initial`` tiles at reset (``stream_start``: at random over the tile
  area, or ``spaced`` one supply period's belt travel apart from its upstream edge, as a running
  stream leaves them, the travel shortened where the oldest would reach past the tile area),
  then one every ``stream_period`` at the upstream edge of the tile area, as soon as there is
  room.
- ``batch``: up to ``batch_size`` tiles over the whole tile area (fewer when it would be too
  full); the next batch is indexed in ``batch_index_time`` after the input side last held a
  real tile, and leftover tiles (distractors rightly left) leave with their batch (`retired`).
"""

from __future__ import annotations

from typing import Protocol

import mujoco
import numpy as np

from envs.cell.config import CellConfig
from envs.cell.layout import Footprint, layout_capacity, sample_layout
from envs.cell.scene import CellGeometry, SceneIds
from envs.cell.tiles.tile import PhysicalTile
from envs.errors import CellError

STREAM_LOOKAHEAD_RADII = 3
"""Tiles within this many radii (plus `STREAM_LOOKAHEAD`) of the upstream edge block a spawn."""
STREAM_LOOKAHEAD = 0.05
"""Extra distance [m] from the upstream edge within which tiles block a spawn."""


class FedCell(Protocol):
    """What the feed reads and calls of its cell (`envs.cell.cell.Cell` is one).

    Attributes are the cell's (see `Cell`); arrays have one row per tile.
    """

    cfg: CellConfig
    tiles: tuple[PhysicalTile, ...]
    tile_pool: tuple[tuple[PhysicalTile, ...], ...]
    variant: np.ndarray
    radii: np.ndarray
    on_stage: np.ndarray
    is_distractor: np.ndarray
    geometry: CellGeometry
    ids: SceneIds
    model: mujoco.MjModel
    data: mujoco.MjData

    def place_tiles(self, idx: np.ndarray, poses: np.ndarray) -> None:
        """Put tiles at (x, y, yaw) poses relative to the tile area's centre, at rest."""

    def park_tiles(self, idx: np.ndarray) -> None:
        """Tiles ``idx`` to their parking spots, off the stage."""

    def input_side(self) -> np.ndarray:
        """Tiles on the input belt, shape (n,) bool."""


class TileFeed:
    """The feed of one cell (its ``cfg.tiles.feed`` mode).

    Args:
        cell: The cell whose tiles are fed.
    """

    def __init__(self, cell: FedCell) -> None:
        self.cell = cell
        self.cfg = cell.cfg.tiles
        n = len(cell.tiles)
        self.retired = np.zeros(n, bool)
        """Tiles the batch feed took off the belt with their batch (leftover distractors)."""
        self.order = np.arange(n)
        """The order tiles are fed in (a random permutation when not all start on the belt)."""
        self.next_time = np.inf
        """Simulated time [s] of the next feed decision."""
        self._batch_due = np.inf
        self._footprints = [
            [Footprint.of(t.outline, self.cfg.min_gap) for t in variant]
            for variant in cell.tile_pool
        ]
        """Layout footprint of every built tile, ``[variant][tile]`` (made once)."""

    def footprint(self, i: int) -> Footprint:
        """Layout footprint of tile ``i`` as shown in this episode."""
        return self._footprints[int(self.cell.variant[i])][int(i)]

    def initial_count(self) -> int:
        """Tiles laid out at the start of an episode."""
        n = len(self.cell.tiles)
        if self.cfg.feed == "all":
            return n
        if self.cfg.feed == "batch":
            return min(self.cfg.batch_size, n)
        return min(self.cfg.stream_initial, n)

    def start_episode(self, rng: np.random.Generator) -> None:
        """Park every tile, then lay out the initial ones (the cell's reset calls this)."""
        cell = self.cell
        n = len(cell.tiles)
        if n:
            cell.park_tiles(np.arange(n))
            self.retired[:] = False
            k = self.initial_count()
            self.order = rng.permutation(n) if k < n else np.arange(n)
            if k and self.cfg.feed == "stream" and self.cfg.stream_start == "spaced":
                self.lay_out_spaced(self.order[:k], rng)
            elif k:
                self.lay_out(self.order[:k], rng)
        self._batch_due = np.inf
        self.next_time = {"stream": self.cfg.stream_period, "batch": 0.0}.get(self.cfg.feed, np.inf)

    def update(self, rng: np.random.Generator) -> None:
        """Feed what is due now (called after the cell's physics steps)."""
        cell = self.cell
        if cell.data.time < self.next_time:
            return
        if self.cfg.feed == "batch":
            self._feed_batch(rng)  # checked every call; forwards only when it lays out
        else:
            self._feed_stream(rng)
            mujoco.mj_forward(cell.model, cell.data)

    def lay_out(self, order: np.ndarray, rng: np.random.Generator) -> None:
        """Lay tiles ``order`` out at random over the whole tile area, at rest.

        In batch mode the batch ends early where the tile area would be too full.
        """
        cell, cfg = self.cell, self.cfg
        area = tuple(cell.cfg.input_belt.tile_area)
        shapes = [self.footprint(i) for i in order]
        if cfg.feed == "batch":
            k = max(layout_capacity(shapes, area, cfg.min_gap), 1)
            order, shapes = order[:k], shapes[:k]
        poses = sample_layout(
            cell.radii[order],
            area,
            cfg.min_gap,
            cfg.placement_attempts,
            rng,
            outlines=shapes,
            restarts=cfg.placement_restarts,
        )
        cell.place_tiles(order, poses)

    def lay_out_spaced(self, order: np.ndarray, rng: np.random.Generator) -> None:
        """Lay tiles ``order`` out as a running stream leaves them, at rest.

        ``order[-1]`` lies where a spawn puts it (the upstream edge), each earlier one a supply
        period's belt travel further downstream, in feed order: ``order[0]`` is the oldest.
        Where the oldest would then reach past the tile area (partly out of the camera's view,
        never seen whole), the travel is shortened alike for all so that it lies inside. Across
        the belt and in yaw each is drawn as a spawn draws it.

        Raises:
            CellError: Shortened, two neighbours would overlap (the tile area is too short for
                these tiles).
        """
        cell, cfg = self.cell, self.cfg
        step = cfg.stream_period * cell.cfg.input_belt.speed
        poses = np.concatenate([self._spawn_pose(int(i), rng) for i in order])
        travel = step * np.arange(len(order))[::-1]
        room = cell.cfg.input_belt.tile_area[0] / 2 - cell.radii[order] - cfg.min_gap - poses[:, 0]
        moved = travel > 0
        scale = min(1.0, float(np.min(room[moved] / travel[moved]))) if moved.any() else 1.0
        poses[:, 0] += scale * travel
        gaps = -np.diff(poses[:, 0]) - cell.radii[order[:-1]] - cell.radii[order[1:]]
        if np.any(gaps < cfg.min_gap):
            raise CellError(
                f"stream_start 'spaced': {len(order)} tiles of radii up to "
                f"{cell.radii[order].max():.3f} m do not fit one behind the other on the "
                f"{cell.cfg.input_belt.tile_area[0]} m tile area; lay fewer out at reset "
                "(stream_initial) or use stream_start 'random'"
            )
        cell.place_tiles(order, poses)

    def _spawn_pose(
        self,
        i: int,
        rng: np.random.Generator,
        busy_xy: np.ndarray | None = None,
        busy_radii: np.ndarray | None = None,
    ) -> np.ndarray:
        """Pose (1, 3) of tile ``i`` spawned at the tile area's upstream edge.

        Relative to the tile area's centre: x at the spawn strip's middle, y and yaw drawn at
        random clear of the tiles at world ``busy_xy`` (rows x, y [m]) with ``busy_radii``.

        Raises:
            CellError: No room in the strip.
        """
        cell, cfg = self.cell, self.cfg
        ta = cell.cfg.input_belt.tile_area
        c = cell.geometry.input_centre
        strip = (2 * cell.radii[i] + 2 * cfg.min_gap, ta[1])
        edge = c[0] - ta[0] / 2
        if busy_xy is None or busy_radii is None:
            busy_xy, busy_radii = np.empty((0, 2)), np.empty(0)
        pose = sample_layout(
            cell.radii[[i]],
            strip,
            cfg.min_gap,
            cfg.placement_attempts,
            rng,
            occupied=busy_xy - [edge + strip[0] / 2, c[1]],
            occupied_radii=busy_radii,
        )
        pose[:, 0] += -ta[0] / 2 + strip[0] / 2
        return pose

    def _feed_stream(self, rng: np.random.Generator) -> None:
        """Spawn the next waiting tile at the upstream edge of the tile area, if there is room."""
        cell = self.cell
        waiting = self.order[~cell.on_stage[self.order]]  # the per-reset order, not the design's
        if len(waiting) == 0:
            self.next_time = np.inf
            return
        i = int(waiting[0])
        ta = cell.cfg.input_belt.tile_area
        r = cell.radii[i]
        c = cell.geometry.input_centre
        pos = cell.data.xpos[cell.ids.tile_body]
        edge = c[0] - ta[0] / 2
        near = cell.on_stage & (pos[:, 0] < edge + STREAM_LOOKAHEAD_RADII * r + STREAM_LOOKAHEAD)
        try:
            pose = self._spawn_pose(i, rng, pos[near, :2], cell.radii[near])
        except CellError:
            return  # no room yet; try again next step
        cell.place_tiles(np.array([i]), pose)
        self.next_time += self.cfg.stream_period

    def _feed_batch(self, rng: np.random.Generator) -> None:
        """Index the next batch in once the input side has held no real tile long enough."""
        cell = self.cell
        order = self.order
        waiting = order[~(cell.on_stage | self.retired)[order]]
        if len(waiting) == 0:
            self.next_time = np.inf
            return
        side = cell.input_side()
        if np.any(side & ~cell.is_distractor):
            self._batch_due = np.inf
            return
        if not np.isfinite(self._batch_due):
            self._batch_due = cell.data.time + self.cfg.batch_index_time
            return
        if cell.data.time < self._batch_due:
            return
        left = np.flatnonzero(side)
        cell.park_tiles(left)
        self.retired[left] = True
        self.lay_out(waiting[: self.cfg.batch_size], rng)
        self._batch_due = np.inf
        mujoco.mj_forward(cell.model, cell.data)


__all__ = ["FedCell", "TileFeed"]
