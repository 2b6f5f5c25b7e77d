"""Action adapters of `MosaicAssembly-v0`: one class per action mode.

Each adapter owns its Gymnasium space, validates an action (shape, finite, range) and applies it
to the `Cell`, advancing simulated time. Continuous spaces are Box in [-1, 1] float32.

- `JointActions` (``joint``): 6 joint target deltas scaled by each axis' speed limit times the
  control period, plus vacuum (> 0: on).
- `CartesianActions` (``cartesian``): tool (dx, dy, dz, dyaw) scaled by the tool speed and yaw
  rate times the control period, tool kept pointing down through the planners' IK, plus vacuum.
- `PickPlaceActions` (``pick_place``): pick (x, y, yaw) over the input tile area and place
  (x, y, yaw) over the mesh, normalised to [-1, 1] (see `envs.task_spec.PickPlaceCodec`; the
  ``-v1`` layout has no pick yaw); one full cycle run by
  `envs.cell.pick_place.PickPlaceExecutor`.
- `DiscretePickPlaceActions` (``pick_place_discrete``): MultiDiscrete (tile, slot, rotation).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
from gymnasium import spaces

from envs.cell.cell import Cell
from envs.cell.pick_place import ActionResult, PickPlaceExecutor
from envs.env_config import EnvConfig
from envs.task_spec import (
    RANGE_SLACK,
    ActionError,
    Area,
    PickPlaceCodec,
    PickPlaceCommand,
    discrete_codec,
)
from planners.errors import PlannerError
from planners.ik import IKSolver
from planners.robot import joint_ranges
from spatial.angles import rotate_xy, wrap_angle
from spatial.rotations import yaw_from_matrix

N_JOINTS = 6
REAL_KINDS = "iuf"
"""`numpy.dtype.kind` of an action's allowed dtypes: real numbers (signed, unsigned, float)."""


class ActionAdapter(ABC):
    """One action mode: its space, validation and execution."""

    space: spaces.Space

    def __init__(self, cell: Cell, config: EnvConfig) -> None:
        self.cell = cell
        self.cfg = config
        self.dt = float(cell.model.opt.timestep)
        self.substeps = max(1, round(config.control_dt / self.dt))

    def reset(self) -> None:  # noqa: B027 - optional hook
        """Forget per-episode state (called after the cell's reset)."""

    def validate(self, action: object) -> np.ndarray:
        """Check an action against the space.

        Raises:
            ActionError: Wrong shape, non-finite values or out of range (names what is allowed).
        """
        a = np.asarray(action)
        space = self.space
        if a.shape != space.shape:
            raise ActionError(
                f"action has shape {a.shape}; {type(self).__name__} expects {space.shape} ({space})"
            )
        if a.dtype.kind not in REAL_KINDS:
            raise ActionError(
                f"action must be real numeric values (not complex), got dtype {a.dtype}"
            )
        if not np.isfinite(a).all():
            raise ActionError(f"action must be finite (no NaN/inf), got {a.tolist()}")
        if isinstance(space, spaces.Box):
            if (a < space.low - RANGE_SLACK).any() or (a > space.high + RANGE_SLACK).any():
                raise ActionError(f"action {a.tolist()} outside [-1, 1] ({space})")
            # `np.clip`'s values without its dispatch (~3x the cost on 6 values); all finite here.
            return np.minimum(np.maximum(a.astype(np.float64), space.low), space.high)
        if isinstance(space, spaces.MultiDiscrete):
            if np.any(a != np.round(a)) or np.any(a < 0) or np.any(a >= space.nvec):
                raise ActionError(
                    f"action {a.tolist()} must be integers in [0, {space.nvec.tolist()})"
                )
            return a.astype(np.int64)
        return a

    def noisy(self, a: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Add the configured Gaussian action noise to a continuous action (clipped to [-1, 1])."""
        if self.cfg.action_noise > 0 and isinstance(self.space, spaces.Box):
            a = np.clip(a + rng.normal(0.0, self.cfg.action_noise, a.shape), -1.0, 1.0)
        return a

    @abstractmethod
    def apply(self, action: np.ndarray) -> ActionResult:
        """Execute a validated action, advancing the cell's simulated time."""

    def _set_vacuum(self, on: bool) -> None:
        if on != self.cell.vacuum_on:
            self.cell.vacuum(on)


class JointActions(ActionAdapter):
    """``joint``: Box(7) = 6 joint target deltas (x axis speed limit x control period) + vacuum."""

    def __init__(self, cell: Cell, config: EnvConfig) -> None:
        super().__init__(cell, config)
        self.space = spaces.Box(-1.0, 1.0, (N_JOINTS + 1,), np.float32)
        self.max_step = cell.max_joint_speed * self.substeps * self.dt
        self._lo, self._hi = joint_ranges(cell.model)
        self.target = cell.qpos

    def reset(self) -> None:
        """Joint targets back to the arm's current pose."""
        self.target = self.cell.qpos

    def apply(self, action: np.ndarray) -> ActionResult:
        """Move the joint targets by the scaled deltas, switch the vacuum, step one period."""
        before = self.cell.held_tile
        new = np.clip(self.target + action[:N_JOINTS] * self.max_step, self._lo, self._hi)
        qd = (new - self.target) / (self.substeps * self.dt)
        self.target = new
        self.cell.set_servo(new, qd)
        self._set_vacuum(bool(action[N_JOINTS] > 0))
        self.cell.step(self.substeps)
        after = self.cell.held_tile
        return ActionResult(grasped=after if after >= 0 and after != before else -1)


class CartesianActions(ActionAdapter):
    """``cartesian``: Box(5) = tool (dx, dy, dz, dyaw), tool down, via IK + vacuum.

    The tool target stays in a box: x, y over the input tile area, the mesh (grown by the
    pick/place margins) and the tool's home position, z from ``tool_z_range[0]`` above the belt
    top up to the higher of ``tool_z_range[1]`` and the home height. The home position is in the
    box so that an episode starts inside it (a zero action keeps the tool still) and so that a
    carry from the input belt to the mesh can swing round in front of the robot instead of
    crossing over its base, where the tool cannot point down. An unreachable target keeps the
    previous one (the step reports a failed action).
    """

    def __init__(
        self, cell: Cell, config: EnvConfig, ik: IKSolver, pick: Area, place: Area
    ) -> None:
        super().__init__(cell, config)
        self.ik = ik
        self.space = spaces.Box(-1.0, 1.0, (5,), np.float32)
        period = self.substeps * self.dt
        self.max_step = np.array([config.tool_speed * period] * 3 + [config.tool_yaw_rate * period])
        z0 = pick.surface_z
        home, _ = cell.tcp_pose()
        self._lo = np.array([*np.minimum(pick.lo, place.lo), z0 + config.tool_z_range[0]])
        self._hi = np.array([*np.maximum(pick.hi, place.hi), z0 + config.tool_z_range[1]])
        self._lo = np.minimum(self._lo, home)
        self._hi = np.maximum(self._hi, home)
        self.reset()

    @property
    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """The tool target's box (low, high), each shape (3,) [m], world frame."""
        return self._lo.copy(), self._hi.copy()

    def reset(self) -> None:
        """Tool target back to the current tool pose."""
        pos, rot = self.cell.tcp_pose()
        self.pose = np.array([*pos, yaw_from_matrix(rot)])
        self.q = self.cell.qpos

    def apply(self, action: np.ndarray) -> ActionResult:
        """Move the tool target, solve IK (seeded at the last target), step one period."""
        before = self.cell.held_tile
        pose = self.pose + action[:4] * self.max_step
        pose[:3] = np.clip(pose[:3], self._lo, self._hi)
        pose[3] = float(wrap_angle(pose[3]))
        failed, reason = False, ""
        try:
            q = self.ik.solve(pose[:3], float(pose[3]), seed=self.q).q
            period = self.substeps * self.dt
            self.cell.set_servo(q, (q - self.q) / period)
            self.pose, self.q = pose, q
        except PlannerError as exc:
            failed, reason = True, f"IK: {exc}"
        self._set_vacuum(bool(action[4] > 0))
        self.cell.step(self.substeps)
        after = self.cell.held_tile
        return ActionResult(failed, reason, after if after >= 0 and after != before else -1)


class PickPlaceActions(ActionAdapter):
    """``pick_place``: Box(6) in [-1, 1]: pick (x, y, yaw), place (x, y, yaw); Box(5) without yaw.

    x, y map linearly onto the codec's areas (pick: the input tile area; place: the mesh), yaw
    onto [-pi, pi]. The pad goes to the pick point, then to the place point; the tile turns by
    the action's rotation (its last entry). In the Box(6) layout (``pick_yaw_entry``, the
    ``-v0`` ids) the third entry is the tile's yaw at the pick, which changes nothing; Box(5)
    (``-v1``) leaves it out.
    """

    def __init__(
        self, cell: Cell, config: EnvConfig, executor: PickPlaceExecutor, codec: PickPlaceCodec
    ) -> None:
        super().__init__(cell, config)
        self.executor = executor
        self.codec = codec
        self.space = spaces.Box(-1.0, 1.0, (codec.size,), np.float32)

    def reset(self) -> None:
        """Episode start (the executor forgets the last contact)."""
        self.executor.reset()

    def apply(self, action: np.ndarray) -> ActionResult:
        """Run one cycle to the de-normalised poses."""
        return self.executor.run(self.codec.decode(action))


class DiscretePickPlaceActions(ActionAdapter):
    """``pick_place_discrete``: MultiDiscrete([tiles, slots, rotation_bins]).

    Picks tile ``i`` at its grasp point (ground truth) and places it in slot ``j`` turned by
    ``r * 2 pi / rotation_bins`` from the slot's yaw (``r = 0``: as the slot wants). A tile
    that is not on the input side (waiting, lost, already on the mesh) is a failed action.
    """

    def __init__(self, cell: Cell, config: EnvConfig, executor: PickPlaceExecutor) -> None:
        super().__init__(cell, config)
        self.executor = executor
        self.codec = discrete_codec(cell, config)
        self.space = spaces.MultiDiscrete(list(self.codec.nvec))

    def reset(self) -> None:
        """Episode start (the executor forgets the last contact)."""
        self.executor.reset()

    def poses(self, tile: int, slot: int, rot: int) -> PickPlaceCommand:
        """The world command of a discrete action."""
        return transfer_poses(self.cell, tile, slot, self.codec.turn(rot))

    def apply(self, action: np.ndarray) -> ActionResult:
        """Run one cycle moving the chosen tile to the chosen slot."""
        tile, slot, rot = (int(v) for v in action)
        cell = self.cell
        on_input = bool(cell.input_half()[tile])  # the pad holds nothing between cycles
        if tile >= len(cell.tiles) or slot >= len(cell.slots) or not on_input:
            cell.step(self.executor.fail_steps)
            return ActionResult(True, f"tile {tile} is not on the input belt")
        return self.executor.run(self.poses(tile, slot, rot))


def transfer_poses(cell: Cell, tile: int, slot: int, extra_yaw: float = 0.0) -> PickPlaceCommand:
    """Ground-truth pick and place poses moving ``tile`` into ``slot`` (privileged).

    Args:
        cell: The cell.
        tile: Tile index.
        slot: Slot index.
        extra_yaw: Rotation added to the slot's yaw [rad] (0: as the slot wants).

    Returns:
        The command: pick pad point (the tile's grasp point) and the tile's yaw, place pad point
        and place yaw.
    """
    poses = cell.tile_poses()
    yaw = float(poses.yaw[tile])
    g = cell.tiles[tile].grasp
    sx, sy, syaw = cell.slot_poses_world()[slot]
    place_yaw = float(syaw + extra_yaw)
    pick = poses.pos[tile, :2] + rotate_xy(g, yaw)
    place = np.array([sx, sy]) + rotate_xy(g, place_yaw)
    return PickPlaceCommand.between_yaws(
        (float(pick[0]), float(pick[1])), yaw, (float(place[0]), float(place[1])), place_yaw
    )


__all__ = [
    "ActionAdapter",
    "ActionError",
    "ActionResult",
    "CartesianActions",
    "DiscretePickPlaceActions",
    "JointActions",
    "PickPlaceActions",
    "PickPlaceExecutor",
    "transfer_poses",
]
