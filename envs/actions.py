"""Action adapters of `MosaicAssembly-v0`: one class per action mode.

Each adapter owns its Gymnasium space, validates an action (shape, finite, range) and applies it
to the `Cell`, advancing simulated time. Continuous spaces are Box in [-1, 1] float32.

- `JointActions` (``joint``): 6 joint target deltas scaled by each axis' speed limit times the
  control period, plus vacuum (> 0: on).
- `CartesianActions` (``cartesian``): tool (dx, dy, dz, dyaw) scaled by the tool speed and yaw
  rate times the control period, tool kept pointing down through the planners' IK, plus vacuum.
- `PickPlaceActions` (``pick_place``): pick (x, y, yaw) over the input tile area and place
  (x, y, yaw) over the mesh, normalised to [-1, 1] (see `PickPlaceBounds`); one full cycle.
- `DiscretePickPlaceActions` (``pick_place_discrete``): MultiDiscrete (tile, slot, rotation).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from envs.cell import Cell
from envs.env_config import EnvConfig
from envs.errors import CellError
from planners.config import PlannerConfig
from planners.errors import PlannerError
from planners.ik import IKSolver, wrap_angle
from planners.pick_place import PickPlacePlanner
from planners.servo import ServoFeedForward
from planners.trajectory import JointState

RANGE_SLACK = 1e-6
"""Allowed excess over [-1, 1] for float rounding in normalised actions."""
N_JOINTS = 6
EVENT_SLACK = 1e-9
"""Time slack [s] so a vacuum event falls on the physics step at (not after) its time."""


class ActionError(ValueError):
    """An action the space does not allow (wrong shape, dtype, NaN/inf, out of range)."""


@dataclass(frozen=True)
class ActionResult:
    """What applying one action did.

    Attributes:
        failed: The action could not be executed as asked (unreachable, nothing picked, ...).
        reason: Why it failed ("" when it did not).
        grasped: Index of the tile the pad sealed on during the action, or -1.
    """

    failed: bool = False
    reason: str = ""
    grasped: int = -1


@dataclass(frozen=True)
class PickPlaceBounds:
    """World bounds that normalised pick and place actions map onto.

    Attributes:
        pick_lo: Lower (x, y) of the pick area [m] (input tile area grown by the margin).
        pick_hi: Upper (x, y) of the pick area [m] (x up to the belt's end when it moves).
        place_lo: Lower (x, y) of the place area [m] (mesh minus margin).
        place_hi: Upper (x, y) of the place area [m].
        pick_z: Height of a tile's top face on the input belt [m].
        place_z: Height of a placed tile's top face on the mesh [m].
    """

    pick_lo: np.ndarray
    pick_hi: np.ndarray
    place_lo: np.ndarray
    place_hi: np.ndarray
    pick_z: float
    place_z: float

    @staticmethod
    def of(cell: Cell, config: EnvConfig) -> PickPlaceBounds:
        """Bounds of a cell: input tile area and mesh, each grown by the configured margin."""
        g, c = cell.geometry, cell.cfg
        area = np.asarray(c.input_belt.tile_area) / 2 + config.pick_margin
        mesh = np.asarray(c.output_belt.mesh_size) / 2 + config.place_margin
        t = c.tiles.thickness
        pick_hi = g.input_centre[:2] + area
        if config.belt_speed > 0:  # tiles travel downstream: up to the belt's end
            pick_hi[0] = max(pick_hi[0], g.input_belt_end)
        return PickPlaceBounds(
            g.input_centre[:2] - area,
            pick_hi,
            g.output_centre[:2] - mesh,
            g.output_centre[:2] + mesh,
            float(g.input_centre[2] + t),
            float(g.mesh_top + t),
        )

    def to_world(self, a: np.ndarray) -> tuple[np.ndarray, float, np.ndarray, float]:
        """Normalised (6,) action -> pick (x, y) [m], pick yaw [rad], place (x, y), place yaw."""
        pick = self.pick_lo + (a[:2] + 1) / 2 * (self.pick_hi - self.pick_lo)
        place = self.place_lo + (a[3:5] + 1) / 2 * (self.place_hi - self.place_lo)
        return pick, float(a[2] * math.pi), place, float(a[5] * math.pi)

    def normalize(
        self, pick_xy: np.ndarray, pick_yaw: float, place_xy: np.ndarray, place_yaw: float
    ) -> np.ndarray:
        """World pick and place poses -> the normalised (6,) float32 action (yaws wrapped).

        Raises:
            ActionError: A position outside its area.
        """
        p = 2 * (np.asarray(pick_xy, float) - self.pick_lo) / (self.pick_hi - self.pick_lo) - 1
        q = 2 * (np.asarray(place_xy, float) - self.place_lo) / (self.place_hi - self.place_lo) - 1
        if np.any(np.abs(p) > 1 + RANGE_SLACK) or np.any(np.abs(q) > 1 + RANGE_SLACK):
            raise ActionError(
                f"pick {np.round(pick_xy, 4).tolist()} or place {np.round(place_xy, 4).tolist()} "
                f"outside the areas: pick {self.pick_lo.tolist()}..{self.pick_hi.tolist()}, "
                f"place {self.place_lo.tolist()}..{self.place_hi.tolist()} [m]"
            )
        yaw_a = float(wrap_angle(pick_yaw)) / math.pi
        yaw_b = float(wrap_angle(place_yaw)) / math.pi
        out = np.array([p[0], p[1], yaw_a, q[0], q[1], yaw_b])
        return np.clip(out, -1, 1).astype(np.float32)


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
        if not np.issubdtype(a.dtype, np.number):
            raise ActionError(f"action must be numeric, got dtype {a.dtype}")
        if not np.all(np.isfinite(a)):
            raise ActionError(f"action must be finite (no NaN/inf), got {a.tolist()}")
        if isinstance(space, spaces.Box):
            if np.any(a < space.low - RANGE_SLACK) or np.any(a > space.high + RANGE_SLACK):
                raise ActionError(f"action {a.tolist()} outside [-1, 1] ({space})")
            return np.clip(a.astype(np.float64), space.low, space.high)
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
        self.max_step = np.asarray(cell.cfg.robot.max_joint_speed) * self.substeps * self.dt
        self._lo = cell.model.jnt_range[cell._arm_joints(), 0].copy()
        self._hi = cell.model.jnt_range[cell._arm_joints(), 1].copy()
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

    The tool target stays in a box: x, y over the input tile area and the mesh (grown by the
    pick/place margins), z in ``tool_z_range`` above the belt top. An unreachable target keeps
    the previous one (the step reports a failed action).
    """

    def __init__(self, cell: Cell, config: EnvConfig, ik: IKSolver) -> None:
        super().__init__(cell, config)
        self.ik = ik
        self.space = spaces.Box(-1.0, 1.0, (5,), np.float32)
        period = self.substeps * self.dt
        self.max_step = np.array([config.tool_speed * period] * 3 + [config.tool_yaw_rate * period])
        b = PickPlaceBounds.of(cell, config)
        z0 = cell.geometry.belt_top
        self._lo = np.array([*np.minimum(b.pick_lo, b.place_lo), z0 + config.tool_z_range[0]])
        self._hi = np.array([*np.maximum(b.pick_hi, b.place_hi), z0 + config.tool_z_range[1]])
        self.reset()

    def reset(self) -> None:
        """Tool target back to the current tool pose."""
        pos, rot = self.cell.tcp_pose()
        self.pose = np.array([*pos, IKSolver.yaw_of(rot)])
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


class PickPlaceExecutor:
    """Runs one pick-and-place cycle in the cell, dynamically or kinematically.

    ``dynamic``: the planners' time-optimal cycle is tracked by the servo actuators every physics
    step (inverse-dynamics feed-forward), vacuum switched at the plan's event times.
    ``kinematic``: the arm is put (qpos, no dynamics) at the pick contact, the vacuum seals, then
    at the place contact (the held tile moves with the pad), the vacuum releases, the arm is put
    at the approach point above, and physics settles the released tile for
    ``kinematic_settle``. Simulated time advances by the planners' lower bound of the cycle plus
    the pick and place dwells (tiles on a moving belt do not move during that jump).
    """

    def __init__(
        self, cell: Cell, config: EnvConfig, planner_config: PlannerConfig, ik: IKSolver
    ) -> None:
        self.cell = cell
        self.cfg = config
        self.pcfg = planner_config
        self.ik = ik
        self.planner = PickPlacePlanner(ik, planner_config)
        self.servo = ServoFeedForward(ik.model)
        self.dt = float(cell.model.opt.timestep)
        self.bounds = PickPlaceBounds.of(cell, config)
        self._settle = max(1, round(config.kinematic_settle / self.dt))
        self._fail_steps = max(1, round(config.failed_action_time / self.dt))
        self.at_contact = False
        """The arm rests at the last place contact (a chained dynamic cycle ended there)."""
        self.on_physics_step: Callable[[], None] | None = None
        """Called after every physics step of a dynamic cycle (video frames mid-cycle)."""

    def reset(self) -> None:
        """Episode start: the arm is at home, not at a contact."""
        self.at_contact = False

    def run(
        self, pick_xy: np.ndarray, pick_yaw: float, place_xy: np.ndarray, place_yaw: float
    ) -> ActionResult:
        """Pick at the pad point ``pick_xy`` [m], place at ``place_xy``, turn by the yaw change.

        The tile turns by ``place_yaw - pick_yaw`` [rad]; a planner or cell error (unreachable
        pose, joint limit) is a failed action charged ``failed_action_time``.
        """
        pick = np.array([pick_xy[0], pick_xy[1], self.bounds.pick_z])
        place = np.array([place_xy[0], place_xy[1], self.bounds.place_z])
        rotation = float(wrap_angle(place_yaw - pick_yaw))
        try:
            if self.cfg.execution == "kinematic":
                return self._kinematic(pick, place, rotation)
            return self._dynamic(pick, place, rotation, pick_yaw)
        except (PlannerError, CellError) as exc:
            self.cell.vacuum(False)
            self.cell.step(self._fail_steps)
            return ActionResult(True, f"{type(exc).__name__}: {exc}")

    def _dynamic(
        self, pick: np.ndarray, place: np.ndarray, rotation: float, pick_yaw: float
    ) -> ActionResult:
        cell = self.cell
        plan = self.planner.plan_cycle(
            JointState.at_rest(cell.qpos),
            pick,
            place,
            rotation,
            object_yaw=pick_yaw,
            belt_velocity=(cell.belt_speed, 0.0, 0.0),
            start_at_contact=self.at_contact,
            end_retreat=not self.cfg.chain_cycles,
        )
        cmds = self.servo.commands(plan.trajectory, self.dt)
        k_on = int(np.searchsorted(cmds.times, plan.vacuum_on - EVENT_SLACK))
        k_off = int(np.searchsorted(cmds.times, plan.vacuum_off - EVENT_SLACK))
        grasped = -1
        for k in range(len(cmds.times)):  # servo commands change every physics step
            if k == k_on:
                cell.vacuum(True)
            if k == k_off:
                grasped = cell.held_tile
                cell.vacuum(False)
            cell.set_servo(cmds.q[k], cmds.qd[k])
            cell.step(1)
            if self.on_physics_step is not None:
                self.on_physics_step()
        cell.vacuum(False)
        self.at_contact = self.cfg.chain_cycles
        if grasped < 0:
            return ActionResult(True, "nothing held at the place (empty pick or dropped)")
        return ActionResult(grasped=grasped)

    def _kinematic(self, pick: np.ndarray, place: np.ndarray, rotation: float) -> ActionResult:
        cell, c = self.cell, self.pcfg.cycle
        q0 = cell.qpos
        tool_yaw = IKSolver.yaw_of(cell.tcp_pose()[1])
        q_pick = self.ik.solve(pick - [0.0, 0.0, c.pick_press], tool_yaw, seed=q0).q
        place_yaw = tool_yaw + rotation
        q_place = self.ik.solve(place + [0.0, 0.0, c.place_gap], place_yaw, seed=q_pick).q
        q_up = self._lift(q_place, c.approach_height)
        duration = self.planner.lower_bound(q0, q_pick, q_place) + c.pick_dwell + c.place_dwell
        self._put_arm(q_pick)  # `vacuum` updates the kinematics before its seal check
        cell.vacuum(True)
        grasped = cell.held_tile
        if grasped >= 0:
            cell.set_qpos(q_place, forward=False)  # carries the held tile; stepped below
        cell.vacuum(False)
        self._put_arm(q_up if grasped >= 0 else q_pick)
        cell.data.time += duration
        cell.step(self._settle)
        if grasped < 0:
            return ActionResult(True, "no tile sealed at the pick")
        return ActionResult(grasped=grasped)

    def _lift(self, q: np.ndarray, height: float) -> np.ndarray:
        """Joint angles [rad] raising the tool by ``height`` [m], orientation kept.

        One Jacobian step (for the short retreat the linearisation error is far below a
        millimetre); falls back to IK if the step leaves the joint ranges.
        """
        twist = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0])
        up = q + np.linalg.solve(self.ik.jacobian(q), twist)
        lo, hi = self.pcfg.limits.lower, self.pcfg.limits.upper
        if np.all(up >= np.asarray(lo)) and np.all(up <= np.asarray(hi)):
            return up
        pos, rot = self.ik.fk(q)
        return self.ik.solve(pos + twist[:3], IKSolver.yaw_of(rot), seed=q).q

    def _put_arm(self, q: np.ndarray) -> None:
        """Arm joints at ``q`` [rad] at rest, servo holding it, nothing held.

        No `mj_forward`: the next `vacuum` or `step` computes what it needs.
        """
        d, ids = self.cell.data, self.cell.ids
        d.qpos[ids.arm_qpos] = q
        d.qvel[ids.arm_dof] = 0.0
        d.ctrl[ids.pos_actuators] = q
        d.ctrl[ids.vel_actuators] = 0.0


class PickPlaceActions(ActionAdapter):
    """``pick_place``: Box(6) in [-1, 1]: pick (x, y, yaw), place (x, y, yaw).

    x, y map linearly onto `PickPlaceBounds` (pick: the input tile area; place: the mesh), yaw
    onto [-pi, pi]. The pad goes to the pick point, then to the place point; the tile turns by
    place yaw minus pick yaw (pass the tile's yaw at the pick and the slot's yaw at the place).
    """

    def __init__(self, cell: Cell, config: EnvConfig, executor: PickPlaceExecutor) -> None:
        super().__init__(cell, config)
        self.executor = executor
        self.bounds = executor.bounds
        self.space = spaces.Box(-1.0, 1.0, (6,), np.float32)

    def reset(self) -> None:
        """Episode start (the executor forgets the last contact)."""
        self.executor.reset()

    def apply(self, action: np.ndarray) -> ActionResult:
        """Run one cycle to the de-normalised poses."""
        return self.executor.run(*self.bounds.to_world(action))


class DiscretePickPlaceActions(ActionAdapter):
    """``pick_place_discrete``: MultiDiscrete([tiles, slots, rotation_bins]).

    Picks tile ``i`` at its grasp point (ground truth) and places it in slot ``j`` turned by
    ``r * 2 pi / rotation_bins`` from the slot's yaw (``r = 0``: as the slot wants). A tile
    that is not on the input side (waiting, lost, already on the mesh) is a failed action.
    """

    def __init__(self, cell: Cell, config: EnvConfig, executor: PickPlaceExecutor) -> None:
        super().__init__(cell, config)
        self.executor = executor
        n = max(len(cell.tiles), 1)
        k = max(len(cell.slots), 1)
        self.space = spaces.MultiDiscrete([n, k, config.rotation_bins])

    def reset(self) -> None:
        """Episode start (the executor forgets the last contact)."""
        self.executor.reset()

    def poses(self, tile: int, slot: int, rot: int) -> tuple[np.ndarray, float, np.ndarray, float]:
        """World pick (x, y), yaw and place (x, y), yaw of a discrete action."""
        return transfer_poses(self.cell, tile, slot, rot * 2 * math.pi / self.cfg.rotation_bins)

    def apply(self, action: np.ndarray) -> ActionResult:
        """Run one cycle moving the chosen tile to the chosen slot."""
        tile, slot, rot = (int(v) for v in action)
        cell = self.cell
        on_input = (
            cell.on_stage[tile]
            and not cell.lost[tile]
            and cell.tile_poses().pos[tile, 1]
            > cell.geometry.output_centre[1] / 2 + cell.geometry.input_centre[1] / 2
        )
        if tile >= len(cell.tiles) or slot >= len(cell.slots) or not on_input:
            cell.step(self.executor._fail_steps)
            return ActionResult(True, f"tile {tile} is not on the input belt")
        return self.executor.run(*self.poses(tile, slot, rot))


def transfer_poses(
    cell: Cell, tile: int, slot: int, extra_yaw: float = 0.0
) -> tuple[np.ndarray, float, np.ndarray, float]:
    """Ground-truth pick and place poses moving ``tile`` into ``slot`` (privileged).

    Args:
        cell: The cell.
        tile: Tile index.
        slot: Slot index.
        extra_yaw: Rotation added to the slot's yaw [rad] (0: as the slot wants).

    Returns:
        Pick pad point (x, y) [m] (the tile's grasp point), the tile's yaw [rad], place pad
        point (x, y) [m] and place yaw [rad], as a `PickPlaceActions` step expects.
    """
    poses = cell.tile_poses()
    yaw = float(poses.yaw[tile])
    g = cell.tiles[tile].grasp
    sx, sy, syaw = cell.slot_poses_world()[slot]
    place_yaw = float(syaw + extra_yaw)
    pick = poses.pos[tile, :2] + _rot(g, yaw)
    place = np.array([sx, sy]) + _rot(g, place_yaw)
    return pick, yaw, place, place_yaw


def _rot(v: np.ndarray, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


__all__ = [
    "ActionAdapter",
    "ActionError",
    "ActionResult",
    "CartesianActions",
    "DiscretePickPlaceActions",
    "JointActions",
    "PickPlaceActions",
    "PickPlaceBounds",
    "PickPlaceExecutor",
    "transfer_poses",
]
