"""The env's pick-and-place executor: one cycle in the cell, dynamically or kinematically.

``dynamic``: the planners' time-optimal cycle is played by `planners.executor` (servo feed-
forward at every physics step), the vacuum switched at the plan's seal and release times.
``kinematic``: the arm is put (qpos, no dynamics) at the pick contact, the vacuum seals, then at
the place contact (the held tile moves with the pad, and is set down on the surface: the pad as
far below the place height as it pressed at the pick, where a dynamic cycle releases it
``place_gap`` above and lets it drop), the vacuum releases, the arm is put at the approach point
above, and physics settles the released tile for ``kinematic_settle``; tiles then at rest end
their sleep countdown (`Cell.sleep_still_tiles`), so a step simulates only what still moves.
Simulated time advances by the planners' lower bound of the cycle plus the pick and place
dwells (tiles on a moving belt do not move during that jump).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from envs.cell.cell import Cell
from envs.env_config import EnvConfig
from envs.errors import CellError
from envs.task_spec import Area, PickPlaceCommand
from planners.config import PlannerConfig
from planners.errors import PlannerError
from planners.executor import TimedEvent, TrajectoryExecutor
from planners.ik import IKSolver
from planners.joints import JointState
from planners.pick_place import PickPlacePlanner
from planners.trajectory import chain
from spatial.rotations import yaw_from_matrix

ARM_PLANNERS = 8
"""(IK solver, planner settings, timestep) whose planner and tracker are kept (`arm_planners`):
a procedural env builds an executor at every reset for the same arm. An entry holds the
references and two small planner objects (kB)."""
_PLANNERS: OrderedDict[
    tuple[int, int, float], tuple[IKSolver, PlannerConfig, PickPlacePlanner, TrajectoryExecutor]
] = OrderedDict()


def arm_planners(
    ik: IKSolver, config: PlannerConfig, dt: float
) -> tuple[PickPlacePlanner, TrajectoryExecutor]:
    """The cycle planner and the servo tracker of an arm (IK solver), settings and timestep [s].

    Both keep no state between cycles (settings and a scratch MuJoCo data), so the executors of
    one arm share them: the last `ARM_PLANNERS` are kept, least recently used dropped first.
    """
    key = (id(ik), id(config), dt)
    kept = _PLANNERS.get(key)
    if kept is None or kept[0] is not ik or kept[1] is not config:
        kept = (ik, config, PickPlacePlanner(ik, config), TrajectoryExecutor(ik.model, dt))
        _PLANNERS[key] = kept
        while len(_PLANNERS) > ARM_PLANNERS:
            _PLANNERS.popitem(last=False)
    _PLANNERS.move_to_end(key)
    return kept[2], kept[3]


AT_TARGET = 1e-6
"""Joint distance [rad] below which `PickPlaceExecutor.move_to` has nothing to move."""


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


class PickPlaceExecutor:
    """Runs pick-and-place commands in a cell.

    Args:
        cell: The cell.
        config: Env settings (execution, chaining, settle and failure times).
        planner_config: Planner settings.
        ik: Arm-only IK solver.
        pick: The pick area (its ``tile_top_z`` is the pick height).
        place: The place area (its ``tile_top_z`` is the place height).
    """

    def __init__(
        self,
        cell: Cell,
        config: EnvConfig,
        planner_config: PlannerConfig,
        ik: IKSolver,
        *,
        pick: Area,
        place: Area,
    ) -> None:
        self.cell = cell
        self.cfg = config
        self.pcfg = planner_config
        self.ik = ik
        self.dt = float(cell.model.opt.timestep)
        self.planner, self.tracker = arm_planners(ik, planner_config, self.dt)
        self.pick_z = pick.tile_top_z
        self.place_z = place.tile_top_z
        self._settle = max(1, round(config.kinematic_settle / self.dt))
        self._press = np.array([0.0, 0.0, planner_config.cycle.pick_press])
        """The pad's press below a contact height [m], as an offset (3,)."""
        self.fail_steps = max(1, round(config.failed_action_time / self.dt))
        """Physics steps charged for an action that cannot execute."""
        self.at_contact = False
        """The arm rests at the last place contact (a chained dynamic cycle ended there)."""
        self.on_physics_step: Callable[[], None] | None = None
        """Called after every physics step of a dynamic cycle (video frames mid-cycle)."""

    def reset(self) -> None:
        """Episode start: the arm is at home, not at a contact."""
        self.at_contact = False

    def run(self, cmd: PickPlaceCommand, place_z: float | None = None) -> ActionResult:
        """Pick at ``cmd.pick_xy``, place at ``cmd.place_xy``, the tile turned by ``cmd.rotation``.

        A planner or cell error (unreachable pose, joint limit) is a failed action charged
        ``failed_action_time``. ``place_z`` [m] replaces the mesh's tile-top height (a release
        over the reject bin).
        """
        pick = np.array([*cmd.pick_xy, self.pick_z])
        place = np.array([*cmd.place_xy, self.place_z if place_z is None else place_z])
        try:
            if self.cfg.execution == "kinematic":
                return self._kinematic(pick, place, cmd.rotation)
            return self._dynamic(pick, place, cmd.rotation, cmd.pick_yaw)
        except (PlannerError, CellError) as exc:
            self.cell.vacuum(False)
            self.cell.step(self.fail_steps)
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
        grasped = [-1]

        def release() -> None:
            grasped[0] = cell.held_tile
            cell.vacuum(False)

        def after(_k: int) -> None:
            if self.on_physics_step is not None:
                self.on_physics_step()

        self.tracker.run(
            self.tracker.commands(plan.trajectory),
            lambda q, qd, _ref: cell.set_servo(q, qd),
            lambda: cell.step(1),
            events=(
                TimedEvent(plan.vacuum_on, lambda: cell.vacuum(True)),
                TimedEvent(plan.vacuum_off, release),
            ),
            after_step=after,
        )
        cell.vacuum(False)
        self.at_contact = self.cfg.chain_cycles
        if grasped[0] < 0:
            return ActionResult(True, "nothing held at the place (empty pick or dropped)")
        return ActionResult(grasped=grasped[0])

    def _kinematic(self, pick: np.ndarray, place: np.ndarray, rotation: float) -> ActionResult:
        cell, c = self.cell, self.pcfg.cycle
        q0 = cell.qpos
        tool_yaw = yaw_from_matrix(cell.data.site_xmat[cell.ids.tcp_site].reshape(3, 3))
        q_pick = self.ik.solve(pick - self._press, tool_yaw, seed=q0).q
        place_yaw = tool_yaw + rotation
        # Set down, not dropped: the tile's bottom on the surface (it hangs pick_press lower).
        q_place = self.ik.solve(place - self._press, place_yaw, seed=q_pick).q
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
        cell.sleep_still_tiles()
        if grasped < 0:
            return ActionResult(True, "no tile sealed at the pick")
        return ActionResult(grasped=grasped)

    def move_to(self, q: np.ndarray) -> None:
        """Move the arm at rest to joint angles ``q`` [rad] with one time-optimal move.

        ``dynamic``: tracked by the servos (simulated time advances by the move); ``kinematic``:
        the arm is put there. Nothing is held afterwards.

        Raises:
            PlannerError: ``q`` outside the joint ranges.
        """
        cell = self.cell
        cell.vacuum(False)
        if np.max(np.abs(np.asarray(q, float) - cell.qpos)) < AT_TARGET:
            return  # already there: no move to plan
        if self.cfg.execution == "kinematic":
            cell.set_qpos(np.asarray(q, float))
            return
        move = chain(JointState.at_rest(cell.qpos), [(q, None, "move")], self.ik.limits, ())
        traj = move.sample(self.pcfg.trajectory.sample_dt)
        self.tracker.run(
            self.tracker.commands(traj),
            lambda qc, qd, _ref: cell.set_servo(qc, qd),
            lambda: cell.step(1),
        )
        self.at_contact = False

    def _lift(self, q: np.ndarray, height: float) -> np.ndarray:
        """Joint angles [rad] raising the tool by ``height`` [m], orientation kept.

        One Jacobian step (for the short retreat the linearisation error is far below a
        millimetre); falls back to IK if the step leaves the joint ranges.
        """
        twist = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0])
        up = q + np.linalg.solve(self.ik.jacobian(q), twist)
        lo, hi = self.ik.limits.lower, self.ik.limits.upper
        if all(lo[i] <= v <= hi[i] for i, v in enumerate(up.tolist())):
            return up
        pos, rot = self.ik.fk(q)
        return self.ik.solve(pos + twist[:3], yaw_from_matrix(rot), seed=q).q

    def _put_arm(self, q: np.ndarray) -> None:
        """Arm joints at ``q`` [rad] at rest, servo holding it, nothing held.

        No `mj_forward`: the next `vacuum` or `step` computes what it needs.
        """
        d, ids = self.cell.data, self.cell.ids
        d.qpos[ids.arm_qpos] = q
        d.qvel[ids.arm_dof] = 0.0
        d.ctrl[ids.pos_actuators] = q
        d.ctrl[ids.vel_actuators] = 0.0


__all__ = ["ARM_PLANNERS", "ActionResult", "PickPlaceExecutor", "arm_planners"]
