"""The simulated cell: robot, vacuum pad, belts, mesh, cameras and tiles behind one small object.

Typical use::

    from envs.cell.cell import Cell
    from envs.cell.tiles.shapes import basic_shapes

    cell = Cell(load_cell_config(), basic_shapes(), seed=0)
    cell.set_servo(q_target, qd_target)   # joint targets [rad], feed-forward [rad/s]
    cell.step(10)                         # 10 physics steps (mj_step nstep)
    cell.vacuum(True)
    rgb = cell.render("input_camera")
    cell.close()
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np

from envs.cell.belts import LostTracker, input_speed, set_input_speed
from envs.cell.cameras import CameraModel
from envs.cell.config import CellConfig, load_cell_config
from envs.cell.feed import TileFeed
from envs.cell.scene import (
    WAKE_FORCE,
    build_scene,
    cell_geometry,
    park_positions,
)
from envs.cell.sleep import end_countdowns, start_asleep
from envs.cell.suction import Suction, SuctionEvent
from envs.cell.tiles.shapes import basic_shapes
from envs.cell.tiles.tile import PhysicalTile, SlotSpec, TilePoses, TileShape, make_tile_pool
from envs.cell.tiles.variants import TileVariants
from envs.cell.views import CAMERAS, CellViews
from envs.errors import CellError
from planners.robot import joint_ranges, joint_speed_limits
from spatial.rotations import quat_from_yaw, yaw_from_quat

JOINT_RANGE_SLACK = 1e-9
"""Rounding [rad] `Cell.set_qpos` allows beyond a joint's range."""


class Cell:
    """Robot + pad + belts + mesh + cameras + tiles, stepped through MuJoCo.

    Args:
        config: Cell configuration (bundled ``configs/cell.yaml`` when None).
        shapes: Tile shapes to feed (the built-in test shapes when None).
        slots: Slots of the mesh (visual marks on the output belt).
        seed: Seed or generator for noise, distractors and layout.
        mesh_size: (x, y) of the design's mesh [m] (the sheet, the on-mesh test, the place
            area and the output camera's framing follow it: `geometry`); None: the
            configuration's largest mesh (``output_belt.max_mesh_size``).

    Raises:
        MeshSizeError: A mesh larger than ``output_belt.max_mesh_size`` (names the largest).
        CellError: Bad configuration, slots outside the mesh, or tiles that do not fit the
            input belt (checked before anything is simulated).
    """

    def __init__(
        self,
        config: CellConfig | None = None,
        shapes: Sequence[TileShape] | None = None,
        slots: Sequence[SlotSpec] = (),
        seed: int | np.random.Generator | None = 0,
        mesh_size: Sequence[float] | None = None,
    ) -> None:
        self.cfg = config if config is not None else load_cell_config()
        self.geometry = cell_geometry(self.cfg, mesh_size)
        """Where the cell's parts are, with the design's mesh (`envs.cell.geometry`)."""
        self._rng = np.random.default_rng(seed)
        self.shapes = tuple(shapes) if shapes is not None else basic_shapes()
        self.slots = tuple(slots)
        self.tile_pool = make_tile_pool(self.shapes, self.cfg.tiles, self._rng)
        """Every built tile, ``[variant][tile]`` (``cfg.tiles.variants`` variants)."""
        pool = [t for variant in self.tile_pool for t in variant]
        n, n_variants = len(self.tile_pool[0]), len(self.tile_pool)
        self.is_distractor = np.array([t.distractor != "" for t in self.tile_pool[0]])
        self.model, self.ids = build_scene(self.cfg, pool, self.slots, n_variants, self.geometry)
        self.data = mujoco.MjData(self.model)
        self._park = park_positions(n, self.cfg.tiles.thickness)
        self.variants = TileVariants(
            self.model, self.tile_pool, self.cfg.tiles.body_color, self.cfg.tiles.color_jitter
        )
        """The built variants and which one each tile shows (`envs.cell.tiles.variants`)."""
        self.variant = np.zeros(n, int)
        """Variant of each tile in this episode, shape (n,)."""
        self._select(self.variant, self.tile_pool[0])
        self._tile_trees = self.model.body_treeid[self.ids.tile_body]
        """Kinematic tree of each tile, shape (n,)."""
        self.lost_tracker = LostTracker(self.cfg, n)
        self.views = CellViews(self.model, self.cfg, self.ids, self.geometry)
        """Camera models and pictures (`envs.cell.views`)."""
        self.cameras = self.views.rig
        self.on_stage = np.zeros(n, bool)
        self._wake = np.zeros(n, bool)
        self.feed = TileFeed(self)
        """When which tiles are on the input belt (`envs.cell.feed`)."""
        self.max_joint_speed = joint_speed_limits(self.model)
        """Axis speed limits [rad/s], shape (6,), from the robot model's velocity actuators."""
        self._speed_lo, self._speed_hi = -self.max_joint_speed, self.max_joint_speed
        self._q_lo, self._q_hi = joint_ranges(self.model)
        self._q_lo_list = (self._q_lo - JOINT_RANGE_SLACK).tolist()
        self._q_hi_list = (self._q_hi + JOINT_RANGE_SLACK).tolist()
        home = np.asarray(self.cfg.robot.home, float)
        outside = np.flatnonzero((home < self._q_lo) | (home > self._q_hi))
        if len(outside):
            i = int(outside[0])
            raise CellError(
                f"robot.home[{i}] = {float(home[i])!r} rad is outside joint {i + 1}'s range "
                f"[{self._q_lo[i]:.4f}, {self._q_hi[i]:.4f}] rad (the robot model's limits)"
            )
        self._closed = False
        self.layout_seed = seed if isinstance(seed, int) else None
        """The seed the cell was built with (see `envs.episode_setup.build_cell`), when an int."""
        self.reset()

    # ----------------------------------------------------------------- set-up
    def _select(self, variant: np.ndarray, tiles: Sequence[PhysicalTile]) -> None:
        """Make ``tiles`` (tile i is variant ``variant[i]``) the episode's tiles.

        `tiles`, `ids`, `radii` and the suction's seal check follow the shown variants; the
        others are massless, out of contact and hidden (`TileVariants`).
        """
        m = self.model
        self.variant = variant
        self.tiles = tuple(tiles)
        self.ids = self.ids.with_variants(variant)
        self.radii = np.array([t.radius for t in self.tiles])
        """Bounding radius of each tile about its centroid, shape (n,) [m]."""
        self.suction = Suction(m, self.ids, self.cfg.suction, self.tiles, self.cfg.tiles.thickness)
        self.variants.show(m, self.data, self.ids, variant)

    def reset(self, seed: int | np.random.Generator | None = None) -> None:
        """Arm at home, vacuum off, tiles laid out afresh on the input belt, counters cleared.

        With ``tiles.variants`` V > 1, each tile first gets one of its V pre-built variants
        at random (outline noise) and a fresh glaze colour noise; `tiles`, `ids`, `suction`
        and every per-tile array then describe that variant (each tile's body holds the
        shapes of all its variants; the others are massless, out of contact and hidden). With
        V = 1 the noise drawn at build is kept. Tile colours are restored to the drawn ones
        (undoing run-time changes such as the env's ``color_randomization``).

        Args:
            seed: New seed or generator for the noise and layout; None continues the cell's
                generator.
        """
        self._check_open()
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        drawn = self.variants.draw(self._rng)
        if drawn is not None:
            self._select(*drawn)
        self.variants.paint(self.model, self.ids, self.tiles)
        m, d, ids = self.model, self.data, self.ids
        mujoco.mj_resetData(m, d)
        self._wake[:] = False
        self.suction.reset(d)
        self.lost_tracker.reset()
        home = np.asarray(self.cfg.robot.home)
        d.qpos[ids.arm_qpos] = home
        d.ctrl[ids.pos_actuators] = home
        d.ctrl[ids.vel_actuators] = 0.0
        self.feed.start_episode(self._rng)
        if self.cfg.physics.sleep:
            self._start_asleep()
        mujoco.mj_forward(m, d)

    def _start_asleep(self) -> None:
        """Start the tiles laid out at rest asleep (parked ones, and on a still belt all).

        Tiles on a moving belt stay awake: they must notice the belt's surface speed.
        """
        asleep = ~self.on_stage if self.belt_speed != 0.0 else np.ones(len(self.on_stage), bool)
        if not asleep.any():
            return
        start_asleep(self.model, self.data, self._tile_trees[asleep])
        self._wake[asleep] = False

    def sleep_still_tiles(self) -> None:
        """Let the tiles now under the sleep tolerance fall asleep at the next physics step.

        MuJoCo puts a tree to sleep once it has stayed under ``physics.sleep_tolerance`` for a
        countdown of physics steps; this ends the countdown of the tiles still now. MuJoCo
        checks the tolerance again, over each tile's whole contact island, at that step. For
        kinematic execution, whose released tiles are set down within one step.
        """
        if self.cfg.physics.sleep:
            end_countdowns(self.model, self.data, self._tile_trees, self.ids.tile_dof_index)

    def place_tiles(self, idx: np.ndarray, poses: np.ndarray) -> None:
        """Put tiles at (x, y, yaw) poses relative to the tile area's centre, at rest.

        Each lies flat at its contact height on the belt (bottom face on the belt top), so it
        needs no settling: within the first physics steps it sinks into its resting contact
        (about 2 um) and falls asleep.
        """
        c = self.geometry.input_centre
        qadr = self.ids.tile_qpos_index[idx]
        z = c[2] + self.cfg.tiles.thickness / 2
        self.data.qpos[qadr[:, 0]] = c[0] + poses[:, 0]
        self.data.qpos[qadr[:, 1]] = c[1] + poses[:, 1]
        self.data.qpos[qadr[:, 2]] = z
        self.data.qpos[qadr[:, 3:]] = quat_from_yaw(poses[:, 2])
        self.data.qvel[self.ids.tile_dof_index[idx]] = 0.0
        self.on_stage[idx] = True
        self._wake[idx] = True

    def put_tiles(self, idx: np.ndarray, poses: np.ndarray, surface_z: float) -> None:
        """Put tiles at world (x, y, yaw) poses, lying flat on a surface at ``surface_z`` [m].

        For a state no episode reaches by itself (a finished mosaic on the mesh, to take apart
        into demonstrations); like `place_tiles`, at rest and on the stage.
        """
        qadr = self.ids.tile_qpos_index[idx]
        self.data.qpos[qadr[:, 0]] = poses[:, 0]
        self.data.qpos[qadr[:, 1]] = poses[:, 1]
        self.data.qpos[qadr[:, 2]] = surface_z + self.cfg.tiles.thickness / 2
        self.data.qpos[qadr[:, 3:]] = quat_from_yaw(poses[:, 2])
        self.data.qvel[self.ids.tile_dof_index[idx]] = 0.0
        self.on_stage[idx] = True
        self._wake[idx] = True

    def park_tiles(self, idx: np.ndarray) -> None:
        """Tiles ``idx`` to their parking spots, at rest, off the stage."""
        qadr = self.ids.tile_qpos_index[idx]
        self.data.qpos[qadr[:, :3]] = self._park[idx]
        self.data.qpos[qadr[:, 3:]] = [1.0, 0.0, 0.0, 0.0]
        self.data.qvel[self.ids.tile_dof_index[idx]] = 0.0
        self.on_stage[idx] = False

    def input_side(self) -> np.ndarray:
        """Tiles on the input belt (fed, not lost, not on the pad), shape (n,) bool.

        On the belt: the centroid within the belt's half width plus the tile's radius of the
        belt's centre line. The feed and the tile accounting use it; `input_half` is the
        coarser test of the decision-level actions and indices.
        """
        pos = self.data.xpos[self.ids.tile_body]
        half_w = self.cfg.input_belt.width / 2 + self.radii
        side = self.on_stage & ~self.lost_tracker.lost
        side &= np.abs(pos[:, 1] - self.geometry.input_y) < half_w
        if self.suction.held >= 0:
            side[self.suction.held] = False
        return side

    def input_half(self) -> np.ndarray:
        """Tiles on the input belt's side of the cell, shape (n,) bool.

        Fed, not lost, not on the pad, with the centroid beyond the midline between the belts
        (`CellGeometry.midline_y`, strictly). Unlike `input_side` it also holds a tile lying
        between the belts or beyond the belt's outer edge; the decision-level actions
        (`envs.actions`) and tile indices (`envs.indexing`) use it.
        """
        pos = self.data.qpos[self.ids.tile_qpos_index[:, 1]]
        half = self.on_stage & ~self.lost_tracker.lost & (pos > self.geometry.midline_y)
        if self.suction.held >= 0:
            half[self.suction.held] = False
        return half

    # ------------------------------------------------------------- stepping
    def step(self, n: int = 1) -> list[SuctionEvent]:
        """Advance ``n`` physics steps (one `mj_step` call), then update suction and counters.

        The holding force is checked, and a seal attempted, once per call: call with ``n``
        equal to the control period.

        Returns:
            Suction events (grasp, drop) of this call.
        """
        self._check_open()
        if n < 1:
            raise CellError(f"step needs n >= 1 physics steps, got {n}")
        if self._wake.any():  # for one physics step: a force held longer keeps tiles awake
            self.data.xfrc_applied[self.ids.tile_body[self._wake], 2] = WAKE_FORCE
            mujoco.mj_step(self.model, self.data)
            self.data.xfrc_applied[self.ids.tile_body[self._wake], 2] = 0.0
            self._wake[:] = False
            n -= 1
        if n:
            mujoco.mj_step(self.model, self.data, nstep=n)
        events = []
        ev = self.suction.update(self.data)
        if ev is not None:
            events.append(ev)
        self.feed.update(self._rng)
        self.lost_tracker.update(
            self.data.xpos[self.ids.tile_body], self.on_stage, self.suction.held
        )
        return events

    def set_servo(self, q: np.ndarray, qd: np.ndarray | None = None) -> None:
        """Servo targets: joint angles [rad] and feed-forward velocities [rad/s], shape (6,).

        Targets are clipped to the joint ranges and axis speed limits.

        Raises:
            CellError: Wrong shape or non-finite values.
        """
        q = self._vec6(q, "q")
        qd = np.zeros(6) if qd is None else self._vec6(qd, "qd")
        self.data.ctrl[self.ids.pos_actuators] = np.clip(q, self._q_lo, self._q_hi)
        self.data.ctrl[self.ids.vel_actuators] = np.clip(qd, self._speed_lo, self._speed_hi)

    def set_qpos(self, q: np.ndarray, forward: bool = True) -> None:
        """Kinematic mode: put the arm at ``q`` [rad] at rest (no dynamics), carrying a held tile.

        Servo targets are set to ``q`` too, so a following `step` holds the pose.

        Args:
            q: Joint angles, shape (6,) [rad].
            forward: Recompute all derived quantities (`mujoco.mj_forward`); False updates
                positions only (`mujoco.mj_kinematics`), for callers that step next.

        Raises:
            CellError: Wrong shape, non-finite, or outside the joint ranges.
        """
        q = self._vec6(q, "q")
        lo, hi = self._q_lo_list, self._q_hi_list
        if any(not lo[i] <= v <= hi[i] for i, v in enumerate(q.tolist())):
            raise CellError(
                f"q {np.round(q, 4).tolist()} is outside the joint ranges "
                f"{np.round(np.column_stack([self._q_lo, self._q_hi]), 4).tolist()} [rad]"
            )
        m, d, ids = self.model, self.data, self.ids
        d.qpos[ids.arm_qpos] = q
        d.qvel[ids.arm_dof] = 0.0
        d.ctrl[ids.pos_actuators] = q
        d.ctrl[ids.vel_actuators] = 0.0
        if self.suction.held >= 0:
            mujoco.mj_kinematics(m, d)
            self.suction.carry(d)
        if forward:
            mujoco.mj_forward(m, d)
        else:
            mujoco.mj_kinematics(m, d)

    def vacuum(self, on: bool) -> SuctionEvent | None:
        """Switch the vacuum on (seals at once if the pad is on a tile) or off (releases).

        Returns:
            The grasp or release event, if one happened.
        """
        self._check_open()
        before = len(self.suction.events)
        if on:  # the seal check reads the pad and tile poses
            mujoco.mj_kinematics(self.model, self.data)
        self.suction.set_vacuum(self.data, on)
        if len(self.suction.events) == before:
            return None
        event = self.suction.events[-1]
        if event.kind == "release":
            pos = self.data.xpos[self.ids.tile_body[event.tile]]
            self.lost_tracker.reject_if_over_bin(event.tile, pos)
        return event

    @staticmethod
    def _vec6(v: np.ndarray, name: str) -> np.ndarray:
        a = np.asarray(v, dtype=float)
        if a.shape != (6,) or not all(map(math.isfinite, a.tolist())):
            raise CellError(f"{name} must be 6 finite joint values, got {np.asarray(v)!r}")
        return a

    # -------------------------------------------------------------- reading
    @property
    def time(self) -> float:
        """Simulation time [s]."""
        return float(self.data.time)

    @property
    def qpos(self) -> np.ndarray:
        """Arm joint angles, shape (6,) [rad] (copy)."""
        return self.data.qpos[self.ids.arm_qpos].copy()

    @property
    def qvel(self) -> np.ndarray:
        """Arm joint velocities, shape (6,) [rad/s] (copy)."""
        return self.data.qvel[self.ids.arm_dof].copy()

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Pad-face position (3,) [m] and rotation matrix (3, 3) (z out of the pad)."""
        s = self.ids.tcp_site
        return self.data.site_xpos[s].copy(), self.data.site_xmat[s].reshape(3, 3).copy()

    def tile_xy(self) -> np.ndarray:
        """Tile positions x, y (parked ones included), shape (n, 2) [m] (copy; no yaw computed)."""
        return self.data.qpos[self.ids.tile_qpos_index[:, :2]]

    def tile_poses(self) -> TilePoses:
        """Poses of all tiles (parked ones included; see `on_stage`)."""
        q = self.data.qpos[self.ids.tile_qpos_index]
        quat = q[:, 3:].copy()
        return TilePoses(q[:, :3].copy(), quat, yaw_from_quat(quat))

    @property
    def retired(self) -> np.ndarray:
        """Tiles the batch feed took off the belt with their batch, shape (n,) bool."""
        return self.feed.retired

    @property
    def vacuum_on(self) -> bool:
        """Vacuum sensor: the valve is open."""
        return self.suction.vacuum_on

    @property
    def tile_held(self) -> bool:
        """Pressure switch: a tile is sealed on the pad."""
        return self.suction.tile_held

    @property
    def held_tile(self) -> int:
        """Index of the held tile, or -1."""
        return self.suction.held

    @property
    def lost(self) -> np.ndarray:
        """Tiles lost off the input belt or onto the floor, shape (n,) bool (copy)."""
        return self.lost_tracker.lost.copy()

    @property
    def n_lost(self) -> int:
        """Number of tiles lost."""
        return self.lost_tracker.count

    @property
    def rejected(self) -> np.ndarray:
        """Tiles the pad released over the reject bin, shape (n,) bool (copy)."""
        return self.lost_tracker.rejected.copy()

    @property
    def was_dropped(self) -> np.ndarray:
        """Tiles the pad last let go of by a drop, shape (n,) bool (copy)."""
        return self.suction.was_dropped.copy()

    @property
    def n_dropped(self) -> int:
        """Drop events since reset (the holding force was exceeded; a tile can drop twice)."""
        return self.suction.dropped

    @property
    def events(self) -> list[SuctionEvent]:
        """Every suction event since reset."""
        return list(self.suction.events)

    @property
    def belt_speed(self) -> float:
        """Input belt speed [m/s]."""
        return input_speed(self.model, self.ids)

    @belt_speed.setter
    def belt_speed(self, speed: float) -> None:
        if speed != self.belt_speed:  # sleeping tiles would not notice a new speed
            self._wake |= self.on_stage
        set_input_speed(self.model, self.ids, speed)

    def warnings(self) -> int:
        """Total count of MuJoCo warnings raised so far (should stay 0)."""
        return int(np.sum(self.data.warning.number))

    def slot_poses_world(self) -> np.ndarray:
        """Slot poses in the world, shape (k, 3): x, y [m] and yaw [rad] of each slot's centroid."""
        c = self.geometry.output_centre
        poses = np.array([s.pose for s in self.slots]).reshape(-1, 3)
        return poses + [c[0], c[1], 0.0]

    # ------------------------------------------------------------ rendering
    def camera_model(
        self, name: str, height: int | None = None, width: int | None = None
    ) -> CameraModel:
        """Intrinsics/extrinsics of ``input_camera`` or ``output_camera`` at an image size.

        Raises:
            CellError: Unknown camera.
        """
        return self.views.camera_model(self.data, name, height, width)

    def render(
        self,
        name: str = "input_camera",
        height: int | None = None,
        width: int | None = None,
        depth: bool = False,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Render a camera: ``input_camera``, ``output_camera`` or ``overview``.

        Args:
            name: Camera name.
            height: Image height [px] (the camera's configured size when None).
            width: Image width [px].
            depth: Depth [m] instead of RGB.
            out: Optional preallocated output buffer.

        Returns:
            RGB uint8 (height, width, 3) or depth float32 (height, width).
        """
        self._check_open()
        return self.views.render(self.data, name, height, width, depth=depth, out=out)

    def close(self) -> None:
        """Free renderers; the cell cannot be stepped afterwards (safe to call twice)."""
        if not self._closed:
            self.views.close()
            self._closed = True

    def _check_open(self) -> None:
        if self._closed:
            raise CellError("the cell is closed")

    def __enter__(self) -> Cell:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["CAMERAS", "Cell", "TilePoses"]
