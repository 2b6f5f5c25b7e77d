"""One pick-and-place cycle as a timed joint trajectory with vacuum events.

Phases (segment labels), in order:

* ``retreat`` (only when the cycle starts at a contact, e.g. the previous place): vertical lift
  from the start;
* ``to_pick``: to the approach point above the pick;
* ``descend_pick``: vertical descent to the tile (on a moving belt: arriving with its velocity);
* ``dwell_pick``: vacuum on, build-up (on a moving belt: travelling with it);
* ``lift``: vertical lift to the approach point;
* ``transfer``: to the approach point above the place, turning the tool to the place yaw;
* ``descend_place``: vertical descent to the place;
* ``dwell_place``: vacuum off, release;
* ``retreat_end`` (optional): back up to the approach point, at rest.

Every segment is a time-optimal ruckig move at the axis limits. Blending: approach points are
passed with a vertical tool velocity (``approach_speed``) plus a *lead*: the state, at time tau,
of the time-optimal rest-to-rest move between the two approach points is superposed, so the
base axis already turns while the tool rises (and still turns while it descends). tau is the
largest lead (bisection, ``lead_bisections`` steps) up to the vertical move's duration for which
the tool stays within ``max_lateral_drift`` of vertical (in the belt's frame) below a clearance
height: ``lateral_clearance_height`` while it carries a tile (lift, place descent: the tile's
underside must clear its neighbours' tops), ``empty_clearance_height`` for the empty pad (pick
descent, retreat from the place: its face only clears tile tops level with the contact). The
transfer must stay ``transfer_clearance`` above the lower contact. Where even a lead over the
whole vertical move breaks the drift, the base may first turn away from its target at full jerk
for a few milliseconds (``counter_swing``; reaching a contact it overshoots and comes back): it
then crosses the clearance height at the allowed drift already moving faster, and the transfer
starts with the lift (ends with the descent). A link between two leads that ruckig's
synchronisation holds up (a joint arriving with a velocity cannot take every duration) gets a
stretched bridge, then capped leads, and finally none. Each cycle is planned with
``approach_height`` and each of ``approach_alternatives``; the fastest plan is kept.

Moving belt: the tile at ``pick_position`` (at the cycle's start) moves with ``belt_velocity``.
The planner predicts where it is at contact (fixed-point iteration on the contact time), arrives
with the belt's velocity, travels with the belt during the vacuum dwell and lifts still moving
with it.

Lower bound of a cycle (`PickPlacePlanner.cycle_bound`): time-optimal moves at the same limits
from the bound's start configuration to the pick contact (matching the belt), the pick dwell,
the time-optimal move from the end of the dwell to the place contact, and the place dwell; no
approach points and no clearance zones; a cycle ending with ``retreat_end`` adds the
time-optimal move from rest at the place contact to rest where the retreat ends (both sides of
the ratio then cover the same phases). Every cycle that holds the pad on the tile for the
vacuum dwells takes at least this long: the dwells are process time no motion can overlap. The
motion-only bound (`PickPlacePlanner.lower_bound`, no dwell) is kept as ``motion_bound``.

The module knows poses, yaw sets and belt velocities only: no tiles, shapes or tasks.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from functools import partial

import numpy as np
import numpy.typing as npt

from planners.config import PlannerConfig
from planners.cycle.contacts import CycleRequest, cycle_contacts, rotate
from planners.cycle.leads import Leads
from planners.cycle.moves import ArmMoves, Array, Contact
from planners.cycle.plan import CyclePlan
from planners.errors import InvalidTargetError, PlannerError, TrajectoryError
from planners.ik import IKSolver
from planners.joints import JointState, as_joint_vector
from planners.tool_pose import symmetric_yaws
from planners.trajectory import Piecewise, Segment, hold_segment
from spatial.angles import wrap_angle
from spatial.rotations import yaw_from_matrix


def _vec3(value: npt.ArrayLike, name: str) -> Array:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InvalidTargetError(f"{name} must be 3 finite numbers [m or m/s], got {value!r}")
    return arr


_Planned = tuple[Piecewise, Array, Array, float, tuple[float, float, float, float]]
"""One planned cycle: segments, pick and place contact configurations [rad], place yaw [rad],
leads [s]."""


class PickPlacePlanner:
    """Plans pick-and-place cycles (see the module docstring).

    Args:
        ik: The IK solver (its model defines the robot).
        config: Planner settings; None uses the dataclass defaults.
    """

    def __init__(self, ik: IKSolver, config: PlannerConfig | None = None) -> None:
        self.ik = ik
        self.config = config if config is not None else PlannerConfig()
        self.limits = self.config.limits
        self._wrap = self.config.trajectory.wrap_joints
        self._moves = ArmMoves(ik, self.config)
        self._leads = Leads(self._moves)

    def joint_velocity(self, q: Array, linear: Array) -> Array:
        """Joint velocity (6,) [rad/s] moving the TCP at ``linear`` (3,) [m/s] without turning."""
        return self._moves.joint_velocity(q, linear)

    def plan_cycle(
        self,
        start: JointState,
        pick_position: npt.ArrayLike,
        place_position: npt.ArrayLike,
        rotation: float,
        *,
        symmetry_order: int = 1,
        grasp_offset: npt.ArrayLike = (0.0, 0.0),
        object_yaw: float = 0.0,
        belt_velocity: npt.ArrayLike = (0.0, 0.0, 0.0),
        start_at_contact: bool = False,
        end_retreat: bool = True,
        bound_from: npt.ArrayLike | None = None,
    ) -> CyclePlan:
        """Plan one cycle.

        Args:
            start: Arm state at the cycle's start (at rest).
            pick_position: The object's reference point (top face) at the cycle's start,
                shape (3,) [m].
            place_position: Where that reference point must end, shape (3,) [m].
            rotation: Yaw to turn the object by between pick and place [rad] (target yaw minus
                object yaw); any of its ``symmetry_order`` equivalents is accepted.
            symmetry_order: Rotational symmetry order of the object (1: none); the equivalent
                rotation needing the least joint-6 travel is used.
            grasp_offset: Where the pad grips, in the object's frame relative to its reference
                point, shape (2,) [m].
            object_yaw: The object's yaw at the pick [rad] (orients ``grasp_offset``).
            belt_velocity: Input belt velocity, shape (3,) [m/s]; zero for a static belt.
            start_at_contact: The start is a contact (the previous place): leave it vertically.
            end_retreat: End with a vertical retreat to the approach point, at rest; False ends
                at rest at the place contact (chain the next cycle with ``start_at_contact``).
            bound_from: Configuration the lower bound starts from, shape (6,) [rad]; default
                ``start.q``.

        Raises:
            InvalidTargetError: Non-finite or wrongly shaped inputs.
            UnreachableError: A contact or approach pose has no tool-down IK solution.
            LimitError: No equivalent rotation fits joint 6's range, or a limit is exceeded.
            TrajectoryError: Ruckig failed.
        """
        t_start = time.perf_counter()
        grasp = np.asarray(grasp_offset, dtype=np.float64)
        if grasp.shape != (2,) or not np.all(np.isfinite(grasp)) or not math.isfinite(object_yaw):
            raise InvalidTargetError(
                f"grasp_offset must be 2 finite numbers [m] and object_yaw finite, got "
                f"{grasp_offset!r}, {object_yaw!r}"
            )
        if symmetry_order < 1:
            raise InvalidTargetError(f"symmetry_order must be >= 1, got {symmetry_order!r}")
        pick0 = _vec3(pick_position, "pick_position") + rotate(grasp, object_yaw)
        place = _vec3(place_position, "place_position")
        belt = _vec3(belt_velocity, "belt_velocity")
        if not math.isfinite(rotation):
            raise InvalidTargetError(f"rotation must be finite, got {rotation!r}")
        if start.qd.any():
            raise InvalidTargetError("plan_cycle starts at rest: start.qd must be zero")
        as_joint_vector(start.q, "start.q")
        # Tool yaw at the pick: keep the current one (the round pad may pick at any yaw).
        pick_yaw = yaw_from_matrix(self.ik.fk(start.q)[1])
        rotations = [
            (float(turn), grasp, object_yaw) for turn in symmetric_yaws(rotation, symmetry_order)
        ]
        req = CycleRequest(
            start, start_at_contact, end_retreat, pick0, place, pick_yaw, tuple(rotations), belt
        )
        result, t_contact, wait = self._timed(req)
        return self._cycle_plan(
            req, (result, t_contact, wait), bound_from, rotate(grasp, object_yaw), t_start
        )

    def _cycle_plan(  # noqa: PLR0917
        self,
        req: CycleRequest,
        timed: tuple[_Planned, float, float],
        bound_from: npt.ArrayLike | None,
        grip: Array,
        t_start: float,
    ) -> CyclePlan:
        """The `CyclePlan` of a timed plan (`_timed`), its bounds computed.

        ``grip``: the grip point's offset from the object's reference point, shape (3,) [m];
        ``t_start``: `time.perf_counter` at the call's start [s].
        """
        result, t_contact, wait = timed
        start, belt, pick0, place, pick_yaw = (
            req.start,
            req.belt,
            req.pick0,
            req.place,
            req.pick_yaw,
        )
        end_retreat = req.end_retreat
        pw, pick_q, place_q, place_yaw, leads = result
        dwell = pw.segments[pw.index("dwell_pick")]
        if wait > 0.0:
            pw = Piecewise((hold_segment(start, wait, "wait"), *pw.segments))
        speed = float(np.linalg.norm(belt))
        contact_error = speed * abs(pw.end_time("descend_pick") - t_contact)
        traj = pw.sample(self.config.trajectory.sample_dt)
        bound_q = start.q if bound_from is None else as_joint_vector(bound_from, "bound_from")
        belt_qd = self._moves.joint_velocity(pick_q, belt)
        end_q = pw.end.q if end_retreat else None
        motion_bound = self.lower_bound(bound_q, pick_q, place_q, belt_qd, end_q)
        bound = self.cycle_bound(bound_q, pick_q, belt_qd, dwell.duration, place_q, end_q)
        return CyclePlan(
            trajectory=traj,
            piecewise=pw,
            vacuum_on=pw.start_time("dwell_pick"),
            vacuum_off=pw.start_time("dwell_place"),
            lift_off=pw.start_time("lift"),
            duration=pw.duration,
            bound=bound,
            motion_bound=motion_bound,
            pick_q=pick_q,
            place_q=place_q,
            pick_position=pick0 + belt * t_contact - grip,
            place_position=place,
            pick_yaw=pick_yaw,
            place_yaw=place_yaw,
            leads=leads,
            contact_error=contact_error,
            plan_ms=(time.perf_counter() - t_start) * 1e3,
        )

    def _timed(self, req: CycleRequest) -> tuple[_Planned, float, float]:
        """The plan meeting the tile on time, the contact time aimed at [s], the wait [s].

        The contact time is the fixed point t = T(t) of the plan aimed at the tile's position at
        t; without one, the plan aims later than it arrives and waits at the start.

        Raises:
            TrajectoryError: No timing of the moving tile's pick works.
        """
        c = self.config.cycle
        moving = bool(np.any(req.belt != 0.0))
        # First guess of the contact time: a direct time-optimal move onto the tile.
        t_contact = 0.0
        if moving:
            q_guess = self._moves.solve(
                req.pick0 - np.array([0.0, 0.0, c.pick_press]), req.pick_yaw, req.start.q
            )
            t_contact = self._moves.segment(req.start, q_guess, None, "guess").duration
        # Fixed point t = T(t): the contact time of the plan aimed at the tile's position then.
        tried: list[tuple[float, _Planned, float]] = []
        speed = float(np.linalg.norm(req.belt))
        for _ in range(c.predict_iterations if moving else 1):
            res, t_new = self._fastest(req, t_contact)
            tried.append((t_contact, res, t_new))
            if speed * abs(t_new - t_contact) <= c.predict_tolerance:
                break
            t_contact = t_new
        t_aim, result, t_plan = min(tried, key=lambda x: abs(x[2] - x[0]))
        wait = 0.0
        if speed * abs(t_plan - t_aim) > c.predict_tolerance:
            # No fixed point (e.g. the wrist's turn changed between iterations): aim later than
            # the plan arrives and wait at the start for the difference.
            t_aim = max(t for _, _, t in tried) + c.predict_margin
            result, t_plan = self._fastest(req, t_aim)
            if t_plan > t_aim:
                raise TrajectoryError(
                    f"cannot time the pick of the moving object at "
                    f"{np.round(req.pick0, 4).tolist()} m: contact at {t_plan:.3f} s, aimed at "
                    f"{t_aim:.3f} s"
                )
            wait = t_aim - t_plan
        return result, t_aim, wait

    def _fastest(self, req: CycleRequest, t: float) -> tuple[_Planned, float]:
        """The fastest cycle meeting the tile where it is at time t, and its own contact time."""
        c = self.config.cycle
        pick_c = req.pick0 + req.belt * t - np.array([0.0, 0.0, c.pick_press])
        res = self._plan(req, pick_c, c.approach_height)
        for height in c.approach_alternatives:
            try:
                alt = self._plan(req, pick_c, height)
            except PlannerError:
                continue
            if alt[0].duration < res[0].duration:
                res = alt
        return res, res[0].end_time("descend_pick")

    def _plan(self, req: CycleRequest, pick_c: Array, approach_height: float) -> _Planned:
        """The cycle through the pick contact ``pick_c`` (3,) [m] at one approach height [m]."""
        c = self.config.cycle
        up = np.array([0.0, 0.0, approach_height])
        moving = bool(np.any(req.belt))
        dwell_pick = max(c.pick_dwell, c.belt_match_time) if moving else c.pick_dwell
        cs = cycle_contacts(self._moves, req, pick_c, up, dwell_pick)
        start = req.start
        empty = c.empty_clearance_height
        segs: list[Segment] = []
        lead_start = math.nan

        # Leaving the start (previous place) and reaching the pick.
        leave_start: Callable[[Segment | None, float], tuple[list[Segment], float]] | None = None
        if req.start_at_contact:
            p_start = self.ik.fk(start.q)[0]
            start_up_q = self._moves.solve(p_start + up, req.pick_yaw, start.q)
            start_out = Contact(p_start, np.zeros(3), start.q, np.zeros(6), start_up_q, empty)
            bridge = partial(self._moves.bridge, start_up_q, cs.pick_in.approach_q, cs.belt_qd)
            leave_start = partial(self._leads.leave, start, start_out, label="retreat")
            floor_z = min(p_start[2], pick_c[2])
        else:
            bridge = partial(self._moves.bridge, start.q, cs.pick_in.approach_q, cs.belt_qd)
            floor_z = -math.inf
        reach_pick = partial(self._leads.reach_state, cs.pick_in, label="descend_pick")
        s_ret, lead_start, s_to, s_desc, lead_pick_in = self._leads.legs(
            start, leave_start, reach_pick, bridge, floor_z, "to_pick"
        )
        segs += [*s_ret, s_to, *s_desc]
        segs.append(
            hold_segment(
                JointState(cs.pick_in.q, cs.belt_qd),
                dwell_pick,
                "dwell_pick",
            )
        )

        # Lift, transfer, descend to the place.
        bridge = partial(
            self._moves.bridge, cs.pick_out.approach_q, cs.place_in.approach_q, cs.belt_qd
        )
        floor_z = min(pick_c[2], cs.place_in.point[2])
        s_lift, lead_out, s_tr, s_down, lead_in = self._leads.legs(
            segs[-1].end,
            partial(self._leads.leave, segs[-1].end, cs.pick_out, label="lift"),
            partial(self._leads.reach_state, cs.place_in, label="descend_place"),
            bridge,
            floor_z,
            "transfer",
        )
        segs += [*s_lift, s_tr, *s_down]
        segs.append(hold_segment(JointState(cs.place_in.q), c.place_dwell, "dwell_place"))
        if req.end_retreat:
            segs.append(
                self._moves.segment(segs[-1].end, cs.place_in.approach_q, None, "retreat_end")
            )
        leads = (lead_start, lead_pick_in, lead_out, lead_in)
        return Piecewise(tuple(segs)), cs.pick_in.q, cs.place_in.q, cs.place_yaw, leads

    def lower_bound(
        self,
        start_q: npt.ArrayLike,
        pick_q: Array,
        place_q: Array,
        pick_qd: Array | None = None,
        end_q: Array | None = None,
    ) -> float:
        """Lower bound [s]: time-optimal start -> pick contact -> place contact, no dwell.

        Args:
            start_q: Start configuration (at rest), shape (6,) [rad].
            pick_q: Pick contact configuration, shape (6,) [rad].
            place_q: Place contact configuration, shape (6,) [rad].
            pick_qd: Joint velocity at the pick contact (belt matching), shape (6,) [rad/s].
            end_q: Where the cycle ends at rest after the place (a retreat), shape (6,) [rad];
                None: it ends at the place contact.
        """
        q0 = as_joint_vector(start_q, "start_q")
        if pick_qd is None or not as_joint_vector(pick_qd, "pick_qd").any():
            motion = self._moves.rest_moves(q0, (pick_q, "bound_pick"), (place_q, "bound_place"))[0]
        else:
            t_pick, at_pick = self._moves.move(
                JointState.at_rest(q0), pick_q, pick_qd, "bound_pick"
            )
            motion = t_pick + self._moves.move(at_pick, place_q, None, "bound_place")[0]
        return motion + self._end_bound(place_q, end_q)

    def cycle_bound(  # noqa: PLR0917
        self,
        start_q: npt.ArrayLike,
        pick_q: Array,
        pick_qd: Array,
        pick_dwell: float,
        place_q: Array,
        end_q: Array | None = None,
    ) -> float:
        """Lower bound [s] of a cycle with vacuum dwells (see the module docstring).

        Time-optimal start -> pick contact (arriving with ``pick_qd``), the pick dwell travelling
        at ``pick_qd``, time-optimal from there to rest at the place contact, the place dwell
        (and, with ``end_q``, time-optimal from there to rest at ``end_q``).

        Args:
            start_q: Start configuration (at rest), shape (6,) [rad].
            pick_q: Pick contact configuration, shape (6,) [rad].
            pick_qd: Joint velocity at the pick contact (belt matching), shape (6,) [rad/s].
            pick_dwell: Time at the pick contact (vacuum build-up, belt matching) [s].
            place_q: Place contact configuration, shape (6,) [rad].
            end_q: Where the cycle ends at rest after the place dwell (a retreat), shape (6,)
                [rad]; None: it ends at the place contact.
        """
        s0 = JointState.at_rest(as_joint_vector(start_q, "start_q"))
        t_pick, at_pick = self._moves.move(s0, pick_q, pick_qd, "bound_pick")
        held = hold_segment(at_pick, pick_dwell, "bound_dwell")
        t_place, _ = self._moves.move(held.end, place_q, None, "bound_place")
        dwells = pick_dwell + self.config.cycle.place_dwell
        return t_pick + t_place + dwells + self._end_bound(place_q, end_q)

    def _end_bound(self, place_q: Array, end_q: Array | None) -> float:
        """Time-optimal rest-to-rest move from the place contact to ``end_q`` [s] (0 if None)."""
        if end_q is None:
            return 0.0
        return self._moves.rest_moves(as_joint_vector(place_q, "place_q"), (end_q, "bound_end"))[0]

    def plan_move(self, start: JointState, q: npt.ArrayLike, label: str = "move") -> Piecewise:
        """Time-optimal move from ``start`` to rest at ``q`` (6,) [rad] (e.g. back home).

        Raises:
            PlannerError: See `plan_segment`.
        """
        target = as_joint_vector(q, "q")
        return Piecewise((self._moves.segment(start, target, None, label),))


def relative_rotation(tile_yaw: float, slot_yaw: float) -> float:
    """Rotation [rad] turning a tile at ``tile_yaw`` to ``slot_yaw``, wrapped to [-pi, pi).

    Raises:
        InvalidTargetError: A yaw is not finite.
    """
    if not (math.isfinite(tile_yaw) and math.isfinite(slot_yaw)):
        raise InvalidTargetError(f"yaws must be finite, got {tile_yaw!r}, {slot_yaw!r}")
    return float(wrap_angle(slot_yaw - tile_yaw))


__all__ = ["PickPlacePlanner", "relative_rotation"]
