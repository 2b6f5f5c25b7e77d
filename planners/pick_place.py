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
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
import numpy.typing as npt

from planners.config import JointLimits, PlannerConfig
from planners.errors import InvalidTargetError, PlannerError, TrajectoryError, UnreachableError
from planners.ik import IKSolver, symmetric_yaws
from planners.rest_to_rest import rest_to_rest_duration
from planners.trajectory import (
    JointState,
    JointTrajectory,
    Piecewise,
    Segment,
    as_joint_vector,
    check_in_range,
    hold_segment,
    join,
    plan_segment,
    segment_within_limits,
    superpose,
    unwrap_target,
    unwrap_values,
    window,
)
from spatial.angles import wrap_angle
from spatial.rotations import yaw_from_matrix

Array = npt.NDArray[np.float64]

_CHECK_SAMPLES = 40
"""FK samples per segment when checking drift and clearance (resolution, not a tunable)."""
_CROSSING_BISECTIONS = 12
"""Bisection steps locating where the tool crosses a clearance height between two check samples
(the drift grows fastest there; resolution, not a tunable)."""
_LEAD_CAPS = (0.5, 0.25)
"""Fractions of the vertical moves the leads are capped at when a link between them fails (then
no lead at all)."""
_STRETCHES = 2
"""Tries stretching a bridge when synchronisation holds up the link between two leads."""
_SYNC_SLACK = 1e-3
"""A link taking this much longer than its slowest joint alone is held up by synchronisation [s]."""
_COST_TIE = 1e-6
"""A counter-swung lead must gain more than this over the plain one to be used [s]."""
_MIN_SHARE = 0.05
"""Smallest fraction of a limit left to the lead's bridge (keeps ruckig's input valid)."""


def _share(limits: JointLimits, share: Array, frame_qd: Array | None = None) -> JointLimits:
    """``limits`` with acceleration and jerk scaled per joint by ``share`` (6,).

    With ``frame_qd`` (6,) [rad/s], the joint velocity of a moving frame the motion is
    superposed on (a belt), the velocity limits leave room for it (at least ``_MIN_SHARE``).
    """
    vmax = np.asarray(limits.max_velocity)
    if frame_qd is not None:
        vmax = np.maximum(vmax - np.abs(frame_qd), _MIN_SHARE * vmax)
    return JointLimits(
        lower=limits.lower,
        upper=limits.upper,
        max_velocity=tuple(vmax),
        max_acceleration=tuple(np.asarray(limits.max_acceleration) * share),
        max_jerk=tuple(np.asarray(limits.max_jerk) * share),
    )


@dataclass(frozen=True)
class CyclePlan:
    """A planned pick-and-place cycle.

    Attributes:
        trajectory: The sampled joint trajectory (times from 0 at the cycle's start).
        piecewise: The exact segments (labels as in the module docstring).
        vacuum_on: Time the vacuum switches on (pad at the pick contact) [s].
        vacuum_off: Time the vacuum switches off (tile at the place contact) [s].
        lift_off: Time the tool starts lifting the tile [s].
        duration: Total duration [s].
        bound: Lower bound of the cycle, vacuum dwells included [s] (see the module docstring;
            with ``retreat_end``, the time-optimal retreat included).
        motion_bound: Lower bound of the motion alone: start -> pick contact -> place contact
            (-> retreat end), time-optimal, no dwell [s].
        pick_q: Configuration at the pick contact, shape (6,) [rad].
        place_q: Configuration at the place contact, shape (6,) [rad].
        pick_position: Predicted tile top centre at contact, shape (3,) [m].
        place_position: Target tile top centre at the place, shape (3,) [m].
        pick_yaw: Tool yaw at the pick [rad].
        place_yaw: Tool yaw at the place [rad] (the chosen equivalent rotation).
        leads: Lead time used at each approach point (start out, pick in, pick out, place in)
            [s]; 0 for a vertical pass, NaN for a stop.
        contact_error: Predicted distance between the pad and the moving tile's grip point at
            contact [m] (residual of the contact-time prediction; 0 on a static belt).
        plan_ms: Wall-clock planning time [ms] (IK + trajectories + checks).
    """

    trajectory: JointTrajectory
    piecewise: Piecewise
    vacuum_on: float
    vacuum_off: float
    lift_off: float
    duration: float
    bound: float
    motion_bound: float
    pick_q: Array
    place_q: Array
    pick_position: Array
    place_position: Array
    pick_yaw: float
    place_yaw: float
    leads: tuple[float, float, float, float]
    contact_error: float
    plan_ms: float

    @property
    def end(self) -> JointState:
        """State at the end of the cycle."""
        return self.piecewise.end

    @property
    def ratio(self) -> float:
        """Cycle duration over its lower bound (dwells included)."""
        return self.duration / self.bound

    @property
    def motion_ratio(self) -> float:
        """Cycle duration over the motion-only bound (no dwell)."""
        return self.duration / self.motion_bound


def _rotate(xy: Array, yaw: float) -> Array:
    """Planar vector ``xy`` (2,) turned by ``yaw`` [rad], as a 3-vector with z = 0."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([c * xy[0] - s * xy[1], s * xy[0] + c * xy[1], 0.0])


def _vec3(value: npt.ArrayLike, name: str) -> Array:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InvalidTargetError(f"{name} must be 3 finite numbers [m or m/s], got {value!r}")
    return arr


@dataclass(frozen=True)
class _Contact:
    """A contact point the tool leaves or reaches vertically (in the belt's frame)."""

    point: Array  # contact position at the segment's start (leaving) or end (reaching) [m]
    belt: Array  # velocity of the frame the motion is vertical in [m/s]
    q: Array  # configuration at the contact [rad]
    qd: Array  # joint velocity at the contact [rad/s]
    approach_q: Array  # configuration at the approach point [rad]
    clearance: float  # below this height above the contact the drift is limited [m]


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
        share = np.ones(6)
        share[list(self.config.cycle.lead_joints)] = self.config.cycle.lead_share
        self._share = share
        self._vertical_limits = _share(self.limits, np.where(share < 1.0, 1.0 - share, 1.0))

    # ------------------------------------------------------------------ helpers

    def joint_velocity(self, q: Array, linear: Array) -> Array:
        """Joint velocity (6,) [rad/s] moving the TCP at ``linear`` (3,) [m/s] without turning."""
        if not np.any(linear):
            return np.zeros(q.shape)
        jac = self.ik.jacobian(q)
        twist = np.concatenate([linear, np.zeros(3)])
        qd, *_ = np.linalg.lstsq(jac, twist, rcond=None)
        return np.asarray(qd)

    def _segment(
        self,
        start: JointState,
        q: Array,
        qd: Array | None,
        label: str,
        qdd: Array | None = None,
    ) -> Segment:
        q_t = unwrap_target(start.q, q, self.limits, self._wrap)
        return plan_segment(start, q_t, self.limits, qd, target_qdd=qdd, label=label)

    def _move(
        self, start: JointState, q: Array, qd: Array | None, label: str
    ) -> tuple[float, JointState]:
        """Duration [s] and end state of the move `_segment` plans, without the trajectory.

        From rest to rest in closed form (`_rest_moves`); any other boundary state by ruckig.

        Raises:
            PlannerError: See `plan_segment`.
        """
        stops = qd is None or not as_joint_vector(qd, "target_qd").any()
        if stops and not (start.qd.any() or start.qdd.any()):
            duration, q_t = self._rest_moves(start.q, (q, label))
            return duration, JointState(np.array(q_t))
        seg = self._segment(start, q, qd, label)
        return seg.duration, seg.end

    def _rest_moves(
        self, start_q: Array, *moves: tuple[npt.ArrayLike, str]
    ) -> tuple[float, list[float]]:
        """Duration [s] of time-optimal moves from rest to rest, and the last target [rad].

        From ``start_q`` (6,) [rad] through each ``(q, label)`` of ``moves``, targets unwrapped
        as `_segment` does. In closed form (`rest_to_rest_duration`: ruckig's duration to
        ~1e-12 s), on plain floats.

        Raises:
            PlannerError: A non-finite or wrongly shaped target, or one outside the joint ranges.
        """
        prev = start_q.tolist()
        total = 0.0
        for q, label in moves:
            q_t = unwrap_values(prev, as_joint_vector(q, "q_to").tolist(), self.limits, self._wrap)
            check_in_range(q_t, self.limits, f"segment {label!r} target")
            total += rest_to_rest_duration(prev, q_t, self.limits)
            prev = q_t
        return total, prev

    def _positions(self, segs: list[Segment]) -> tuple[Array, Array]:
        """Sample times (from the first segment's start) [s] and TCP positions (n, 3) [m]."""
        times: list[Array] = []
        pos: list[Array] = []
        t0 = 0.0
        for seg in segs:
            taus = np.linspace(0.0, seg.duration, _CHECK_SAMPLES)
            times.append(t0 + taus)
            pos.extend(self.ik.fk(q)[0] for q in seg.states(taus)[0])
            t0 += seg.duration
        return np.concatenate(times), np.asarray(pos)

    def _drift_ok(self, segs: list[Segment], contact: _Contact, leaving: bool) -> bool:
        """Below the clearance height the tool stays over the (belt-moving) contact point.

        Checked at the samples and, by bisection, where the tool crosses the clearance height
        (between two samples the drift can grow by a tenth of a millimetre there).
        """
        c = self.config.cycle
        taus, pos = self._positions(segs)
        total = taus[-1]

        def relative(t: Array, p: Array) -> Array:
            t_rel = t if leaving else t - total
            return p - (contact.point[None, :] + contact.belt[None, :] * t_rel[:, None])

        rel = relative(taus, pos)
        low = rel[:, 2] < contact.clearance
        lateral = list(np.linalg.norm(rel[low, :2], axis=1))
        for k in np.flatnonzero(low[:-1] != low[1:]):
            t_low, t_high = (taus[k], taus[k + 1]) if low[k] else (taus[k + 1], taus[k])
            for _ in range(_CROSSING_BISECTIONS):
                t_mid = 0.5 * (t_low + t_high)
                r = relative(np.array([t_mid]), self._tcp_at(segs, t_mid)[None, :])[0]
                if r[2] < contact.clearance:
                    t_low = t_mid
                else:
                    t_high = t_mid
            r = relative(np.array([t_low]), self._tcp_at(segs, t_low)[None, :])[0]
            lateral.append(float(np.linalg.norm(r[:2])))
        return bool(not lateral or max(lateral) <= c.max_lateral_drift)

    def _tcp_at(self, segs: list[Segment], t: float) -> Array:
        """TCP position (3,) [m] at time ``t`` [s] from the first segment's start."""
        for seg in segs:
            if t <= seg.duration:
                return self.ik.fk(seg.state(t)[0])[0]
            t -= seg.duration
        return self.ik.fk(segs[-1].state(segs[-1].duration)[0])[0]

    def _clearance_ok(self, seg: Segment, floor_z: float) -> bool:
        _, pos = self._positions([seg])
        return bool(pos[:, 2].min() >= floor_z + self.config.cycle.transfer_clearance)

    def _solve(self, position: Array, yaw: float, seed: Array) -> Array:
        q = self.ik.solve_yaws(position, np.array([yaw]), seed=seed, reference=seed).q
        return unwrap_target(seed, q, self.limits, self._wrap)

    def _choose_place(
        self,
        place: Array,
        pick_q: Array,
        pick_yaw: float,
        rotations: list[tuple[float, Array, float]],
    ) -> tuple[Array, Array, float]:
        """Place contact point, configuration and tool yaw for the cheapest equivalent rotation.

        Raises:
            UnreachableError: No equivalent rotation is reachable.
        """
        gap = np.array([0.0, 0.0, self.config.cycle.place_gap])
        best: tuple[float, Array, Array, float] | None = None
        errors = []
        for rot, grasp, obj_yaw in rotations:
            point = place + gap + _rotate(grasp, obj_yaw + rot)
            try:
                sol = self.ik.solve_yaws(
                    point, symmetric_yaws(pick_yaw + rot, 1), seed=pick_q, reference=pick_q
                )
                q = unwrap_target(pick_q, sol.q, self.limits, self._wrap)
            except PlannerError as exc:
                errors.append(str(exc))
                continue
            cost = float(np.sum(np.abs(q - pick_q)[list(self._wrap)]))  # wrist travel [rad]
            if best is None or cost < best[0]:
                best = (cost, point, q, sol.yaw)
        if best is None:
            raise UnreachableError(
                f"place at {np.round(place, 4).tolist()} m unreachable with every equivalent "
                f"rotation: {'; '.join(errors)}"
            )
        return best[1], best[2], best[3]

    # ------------------------------------------------------------------ via points

    def _vertical(
        self, contact: _Contact, leaving: bool, start: JointState | None = None
    ) -> Segment:
        """The pure vertical move (in the belt's frame) off or onto a contact.

        A time-optimal move between the contact and the approach point above it (passed at the
        approach speed, at rest at the contact); on a moving belt the belt's joint velocity is
        superposed (exact at the contact, linearised around it), so the contact is left or
        reached travelling with the belt. ``start`` (leaving only) must be the contact state.
        """
        c = self.config.cycle
        sign = 1.0 if leaving else -1.0
        qd_v = self.joint_velocity(
            contact.approach_q, np.array([0.0, 0.0, sign * c.approach_speed])
        )
        lim = self._vertical_limits
        q_contact = contact.q if start is None else start.q
        if leaving:
            q1 = unwrap_target(q_contact, contact.approach_q, lim, self._wrap)
            static = plan_segment(JointState.at_rest(q_contact), q1, lim, qd_v, label="vertical")
        else:
            s0 = JointState(contact.approach_q, qd_v)
            q1 = unwrap_target(s0.q, q_contact, lim, self._wrap)
            static = plan_segment(s0, q1, lim, None, label="vertical")
        if not np.any(contact.belt):
            return static
        ramp = hold_segment(JointState(np.zeros(6), contact.qd), static.duration)
        offset = np.zeros(6) if leaving else contact.qd * static.duration
        return superpose([(static, 0.0), (ramp, 0.0)], static.duration, offset, "vertical")

    def _ok(self, segs: list[Segment], contact: _Contact, leaving: bool) -> bool:
        tr = self.config.trajectory
        return all(
            segment_within_limits(s, self.limits, tr.sample_dt, tr.limit_tolerance)
            for s in segs
            if s.parts
        ) and self._drift_ok(segs, contact, leaving)

    def _largest_lead(
        self,
        build: Callable[[float], list[Segment]],
        duration: float,
        contact: _Contact,
        leaving: bool,
        floor: float = 0.0,
    ) -> tuple[list[Segment], float] | None:
        """Largest lead tau in [floor, duration] whose segments pass the checks (bisection).

        Returns None when even tau = ``floor`` fails.
        """
        low = build(floor)
        if not self._ok(low, contact, leaving):
            return None
        full = build(duration)
        if self._ok(full, contact, leaving):
            return full, duration
        best, lo, hi = (low, floor), floor, duration
        for _ in range(self.config.cycle.lead_bisections):
            mid = 0.5 * (lo + hi)
            segs = build(mid)
            if self._ok(segs, contact, leaving):
                best, lo = (segs, mid), mid
            else:
                hi = mid
        return best

    def _best_lead(  # noqa: PLR0917
        self,
        build: Callable[[Segment | None, float], list[Segment]],
        base: Segment,
        contact: _Contact,
        bridge: Segment | None,
        leaving: bool,
        cap: float = 1.0,
    ) -> tuple[list[Segment], float] | None:
        """The faster of the largest plain lead and the shortest counter-swung full lead.

        Plain: the bridge starts ``tau`` before the vertical move ends (leaving; reaching: ends
        ``tau`` after it starts), the largest ``tau`` that keeps the drift (`_largest_lead`).
        When the whole vertical move (``tau = D``) breaks the drift at the clearance crossing,
        the bridge is tried over the whole move with each ``counter_swing`` length in turn
        (`_swung`), the shortest valid one kept. With a bridge of duration ``T`` the lead
        joints come to rest at their target ``T - tau`` after the vertical move's start plus
        ``D``: a swung bridge (``T_s``) wins unless the plain lead exceeds
        ``D - (T_s - T)``, which one more check decides.
        """
        if bridge is None:
            zero = build(None, 0.0)
            return (zero, 0.0) if self._ok(zero, contact, leaving) else None
        dur = base.duration * cap  # the longest lead allowed ("whole" below)
        full = build(bridge, dur)
        if self._ok(full, contact, leaving):
            return full, dur
        for pulse in self.config.cycle.counter_swing:
            swung = self._swung(bridge, pulse, leaving, contact.qd)
            if swung is None:
                continue
            segs = build(swung, dur)
            if not self._ok(segs, contact, leaving):
                continue
            # Equal finish for the plain bridge at this lead: it must do better to win.
            tau_eq = dur - (swung.duration - bridge.duration)
            if tau_eq <= 0.0 or not self._ok(build(bridge, tau_eq), contact, leaving):
                return segs, dur
            return self._largest_lead(partial(build, bridge), dur, contact, leaving, tau_eq)
        return self._largest_lead(partial(build, bridge), dur, contact, leaving)

    def _swung(
        self, bridge: Segment, pulse: float, leaving: bool, frame_qd: Array
    ) -> Segment | None:
        """The bridge with a counter-swing of ``pulse`` [s] at its start (leaving) or end.

        Leaving: the ``counter_swing_joints`` first turn away from their target at full jerk
        for ``pulse`` seconds, then the time-optimal move from that state to rest at the
        target. Reaching: the time reverse, overshooting the target and coming back to it.
        The swing ends at the clearance crossing already moving, where the plain bridge,
        started later to keep the same drift there, would be slower (a jerk-limited start
        moves as t^3: starting early and backwards gains speed for the same offset).
        ``frame_qd`` (6,) [rad/s]: joint velocity of the belt the contact moves with.
        None when ruckig rejects it (e.g. a joint without travel).
        """
        a, b = bridge.start.q, bridge.end.q
        lim = _share(self.limits, self._share, frame_qd)
        rest = bridge.duration - pulse  # a stretched bridge (`_legs`) stays stretched
        idx = list(self.config.cycle.counter_swing_joints)
        jerk = np.zeros(6)
        jerk[idx] = np.sign(b - a)[idx] * np.asarray(lim.max_jerk)[idx]
        if pulse <= 0.0 or not np.any(jerk):
            return None
        try:
            if leaving:
                j = -jerk
                first = plan_segment(
                    JointState.at_rest(a),
                    a + j * pulse**3 / 6.0,
                    lim,
                    j * pulse**2 / 2.0,
                    target_qdd=j * pulse,
                    label="swing",
                )
                second = plan_segment(first.end, b, lim, label="bridge", min_duration=rest)
            else:
                j = jerk
                first = plan_segment(
                    JointState.at_rest(a),
                    b + j * pulse**3 / 6.0,
                    lim,
                    -j * pulse**2 / 2.0,
                    target_qdd=j * pulse,
                    label="bridge",
                    min_duration=rest,
                )
                second = plan_segment(first.end, b, lim, label="swing")
        except PlannerError:
            return None
        return join([first, second], "bridge")

    def _leave(
        self,
        start: JointState,
        contact: _Contact,
        bridge: Segment | None,
        cap: float = 1.0,
        *,
        label: str,
    ) -> tuple[list[Segment], float]:
        """Vertical move off a contact to its approach point, with the largest valid lead.

        With lead tau, the move follows the pure vertical move, and during its last tau seconds
        the first tau seconds of the bridge (the transfer starting) are superposed; the bridge
        may start with a counter-swing (`_swung`), whichever gets the lead joints there first.

        Returns the segments and the lead time used (NaN when it had to stop).
        """
        if self.config.trajectory.blend:
            base = self._vertical(contact, True, start)

            def build(br: Segment | None, tau: float) -> list[Segment]:
                if br is None or tau <= 0.0:
                    return [window(base, 0.0, base.duration, label)]
                t_split = base.duration - tau
                segs = [] if t_split <= 0.0 else [window(base, 0.0, t_split, label)]
                return [*segs, superpose([(base, t_split), (br, 0.0)], tau, br.start.q, label)]

            found = self._best_lead(build, base, contact, bridge, True, cap)
            if found is not None:
                return found
        q_stop = contact.approach_q
        seg = self._segment(start, q_stop, self.joint_velocity(q_stop, contact.belt), label)
        return [seg], math.nan

    def _reach_state(
        self, contact: _Contact, bridge: Segment | None, cap: float = 1.0, *, label: str
    ) -> tuple[JointState, list[Segment], float]:
        """Approach-point state (with the largest valid lead) and the vertical move to contact.

        With lead tau, the last tau seconds of the bridge (the transfer ending, possibly with a
        counter-swing, `_swung`) are superposed on the first tau seconds of the pure vertical
        descent.

        Returns the approach-point state, the descent segments and the lead time (NaN when it
        has to stop at the approach point).
        """
        if self.config.trajectory.blend:
            base = self._vertical(contact, False)

            def build(br: Segment | None, tau: float) -> list[Segment]:
                if br is None or tau <= 0.0:
                    return [window(base, 0.0, base.duration, label)]
                first = superpose([(base, 0.0), (br, br.duration - tau)], tau, br.end.q, label)
                rest = [window(base, tau, base.duration, label)] if tau < base.duration else []
                return [first, *rest]

            found = self._best_lead(build, base, contact, bridge, False, cap)
            if found is not None:
                return found[0][0].start, found[0], found[1]
        stop = JointState(contact.approach_q, self.joint_velocity(contact.approach_q, contact.belt))
        return stop, [self._segment(stop, contact.q, contact.qd, label)], math.nan

    def _try(
        self, start: JointState, q: Array, qd: Array, qdd: Array, label: str
    ) -> Segment | None:
        try:
            return self._segment(start, q, qd, label, qdd)
        except PlannerError:
            return None

    def _bridge(self, a: Array, b: Array, frame_qd: Array, min_duration: float = 0.0) -> Segment:
        """Rest-to-rest time-optimal move of the lead joints between approach points.

        The lead's source: only ``lead_joints`` (base and wrist rotations) move, with
        ``lead_share`` of their acceleration and jerk; the vertical moves get the rest, so the
        superposition keeps every limit. Its velocity limits leave room for ``frame_qd`` (6,)
        [rad/s], the joint velocity of a moving belt superposed at an end (zero if static). It
        lasts at least ``min_duration`` [s] (see `_legs`).
        """
        target = a.copy()
        idx = list(self.config.cycle.lead_joints)
        # b's own turn of a wrapping joint: the vertical move after the bridge starts there.
        target[idx] = b[idx]
        lim = _share(self.limits, self._share, frame_qd)
        return plan_segment(
            JointState.at_rest(a), target, lim, label="bridge", min_duration=min_duration
        )

    def _legs(  # noqa: PLR0917
        self,
        start: JointState,
        leave: Callable[[Segment | None, float], tuple[list[Segment], float]] | None,
        reach: Callable[[Segment | None, float], tuple[JointState, list[Segment], float]],
        bridge: Callable[[float], Segment],
        floor_z: float,
        label: str,
    ) -> tuple[list[Segment], float, Segment, list[Segment], float]:
        """Leave a contact (or ``start``, when ``leave`` is None), link, reach the next one.

        The link must keep its clearance and limits and not be held up by ruckig's
        synchronisation: a joint arriving with a velocity cannot take every duration, so a
        link whose joints each need less time than it takes has hit such a gap (long leads on
        a short base turn: the base would finish its part of the link sooner than the arm's
        other joints can reverse the vertical motion). Then the bridge (``bridge(T)``: the
        lead joints' move stretched to at least ``T`` [s]) is stretched until the base's part
        of the link lasts as long as the slowest joint needs (``_STRETCHES`` tries); failing
        that, the leads are capped at ``_LEAD_CAPS`` of the vertical moves, then dropped.

        Returns the leave segments and lead (NaN without ``leave``), the link, the reach
        segments and lead.
        """
        br = bridge(0.0)
        tries = [(1.0, True)] * (_STRETCHES + 1) + [(cap, False) for cap in (*_LEAD_CAPS, 0.0)]
        stretching = True
        for cap, stretch in tries:
            if stretch and not stretching:
                continue
            b = br if cap > 0.0 else None
            s_out, lead_out = leave(b, cap) if leave is not None else ([], 0.0)
            via, s_in, lead_in = reach(b, cap)
            from_state = s_out[-1].end if s_out else start
            link, need = self._link(from_state, via, floor_z, label)
            if link is not None:
                lead = lead_out if leave is not None else math.nan
                return s_out, lead, link, s_in, lead_in
            if stretch and need is not None:
                middle = br.duration - np.nan_to_num(lead_out) - np.nan_to_num(lead_in)
                br = bridge(br.duration + max(need - middle, 0.0) + _SYNC_SLACK)
            elif stretch:  # not a synchronisation gap: stretching will not help
                stretching = False
                br = bridge(0.0)
        link = self._segment(from_state, via.q, via.qd, label, via.qdd)
        return s_out, lead_out if leave is not None else math.nan, link, s_in, lead_in

    def _link(
        self, leave: JointState, reach: JointState, floor_z: float, label: str
    ) -> tuple[Segment | None, float | None]:
        """The move from a leave state to a reach state, if usable (see `_legs`).

        Returns the move or None, and when synchronisation held it up, the longest time a
        joint alone needs for it [s] (else None).
        """
        try:
            seg = self._segment(leave, reach.q, reach.qd, label, reach.qdd)
        except PlannerError:
            return None, None
        if seg.ruckig is not None:
            alone = float(np.max(seg.ruckig.independent_min_durations))
            if seg.duration > alone + _SYNC_SLACK:
                return None, alone
        return (seg, None) if self._link_ok(seg, floor_z) else (None, None)

    def _link_ok(self, seg: Segment, floor_z: float) -> bool:
        """Whether a move between two leads keeps its clearance and every limit.

        Ruckig exceeds a limit when its start state cannot brake in time (a fast lead plus a
        belt's velocity, say).
        """
        tr = self.config.trajectory
        return self._clearance_ok(seg, floor_z) and segment_within_limits(
            seg, self.limits, tr.sample_dt, tr.limit_tolerance
        )

    # ------------------------------------------------------------------ planning

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
        pick0 = _vec3(pick_position, "pick_position") + _rotate(grasp, object_yaw)
        place = _vec3(place_position, "place_position")
        belt = _vec3(belt_velocity, "belt_velocity")
        if not math.isfinite(rotation):
            raise InvalidTargetError(f"rotation must be finite, got {rotation!r}")
        if start.qd.any():
            raise InvalidTargetError("plan_cycle starts at rest: start.qd must be zero")
        as_joint_vector(start.q, "start.q")
        c = self.config.cycle
        moving = bool(np.any(belt != 0.0))
        # Tool yaw at the pick: keep the current one (the round pad may pick at any yaw).
        pick_yaw = yaw_from_matrix(self.ik.fk(start.q)[1])
        # First guess of the contact time: a direct time-optimal move onto the tile.
        t_contact = 0.0
        if moving:
            q_guess = self._solve(pick0 - np.array([0.0, 0.0, c.pick_press]), pick_yaw, start.q)
            t_contact = self._segment(start, q_guess, None, "guess").duration
        rotations = [
            (rotation + k * 2.0 * math.pi / symmetry_order, grasp, object_yaw)
            for k in range(symmetry_order)
        ]

        def plan_for(t: float) -> tuple[Any, float]:
            """The cycle meeting the tile where it is at time t, and its own contact time."""
            pick_c = pick0 + belt * t - np.array([0.0, 0.0, c.pick_press])
            args = (start, start_at_contact, end_retreat, pick_c, place, pick_yaw, rotations, belt)
            res = self._plan(*args, c.approach_height)
            for height in c.approach_alternatives:
                try:
                    alt = self._plan(*args, height)
                except PlannerError:
                    continue
                if alt[0].duration < res[0].duration:
                    res = alt
            return res, res[0].end_time("descend_pick")

        # Fixed point t = T(t): the contact time of the plan aimed at the tile's position then.
        tried: list[tuple[float, Any, float]] = []
        speed = float(np.linalg.norm(belt))
        for _ in range(c.predict_iterations if moving else 1):
            res, t_new = plan_for(t_contact)
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
            result, t_plan = plan_for(t_aim)
            if t_plan > t_aim:
                raise TrajectoryError(
                    f"cannot time the pick of the moving object at {np.round(pick0, 4).tolist()}"
                    f" m: contact at {t_plan:.3f} s, aimed at {t_aim:.3f} s"
                )
            wait = t_aim - t_plan
        pw, pick_q, place_q, place_yaw, leads = result
        dwell = pw.segments[pw.index("dwell_pick")]
        if wait > 0.0:
            pw = Piecewise((hold_segment(start, wait, "wait"), *pw.segments))
        t_contact = t_aim
        contact_error = speed * abs(pw.end_time("descend_pick") - t_aim)
        traj = pw.sample(self.config.trajectory.sample_dt)
        bound_q = start.q if bound_from is None else as_joint_vector(bound_from, "bound_from")
        belt_qd = self.joint_velocity(pick_q, belt)
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
            pick_position=pick0 + belt * t_contact - _rotate(grasp, object_yaw),
            place_position=place,
            pick_yaw=pick_yaw,
            place_yaw=place_yaw,
            leads=leads,
            contact_error=contact_error,
            plan_ms=(time.perf_counter() - t_start) * 1e3,
        )

    def _plan(  # noqa: PLR0917
        self,
        start: JointState,
        start_at_contact: bool,
        end_retreat: bool,
        pick_c: Array,
        place: Array,
        pick_yaw: float,
        rotations: list[tuple[float, Array, float]],
        belt: Array,
        approach_height: float,
    ) -> tuple[Piecewise, Array, Array, float, tuple[float, float, float, float]]:
        c = self.config.cycle
        up = np.array([0.0, 0.0, approach_height])
        zero = np.zeros(3)
        moving = bool(np.any(belt))
        dwell_pick = max(c.pick_dwell, c.belt_match_time) if moving else c.pick_dwell
        # IK: pick contact, then the equivalent rotation needing least joint-6 travel.
        pick_q = self._solve(pick_c, pick_yaw, start.q)
        place_c, place_q, place_yaw = self._choose_place(place, pick_q, pick_yaw, rotations)
        place_in_q = self._solve(place_c + up, place_yaw, place_q)
        # Travelling with the belt during the dwell: constant joint velocity (linearised).
        belt_qd = self.joint_velocity(pick_q, belt)
        pick_end_q = pick_q + belt_qd * dwell_pick
        pick_end = self.ik.fk(pick_end_q)[0]
        # Approach points straight above the contacts (the belt's motion is superposed).
        pick_in_q = self._solve(pick_c + up, pick_yaw, pick_q)
        lift_q = self._solve(pick_end + up, pick_yaw, pick_end_q)
        # A wrapping joint (joint 6) may reach the place on any of its turns: the bridge takes
        # the turn nearest the lift, so the approach point and the contact take that same turn
        # (the vertical descent starts where the bridge ends).
        # (If the contact would leave the joint's range on that turn, both keep the IK's turn.)
        turn = unwrap_target(lift_q, place_in_q, self.limits, self._wrap) - place_in_q
        lo, hi = np.asarray(self.limits.lower), np.asarray(self.limits.upper)
        if turn.any() and np.all((place_q + turn >= lo) & (place_q + turn <= hi)):
            place_q, place_in_q = place_q + turn, place_in_q + turn
        # Drift limits: the empty pad only clears the tile tops, a held tile its own thickness.
        empty, loaded = c.empty_clearance_height, c.lateral_clearance_height
        pick_in = _Contact(pick_c, belt, pick_q, belt_qd, pick_in_q, empty)
        pick_out = _Contact(pick_end, belt, pick_end_q, belt_qd, lift_q, loaded)
        place_in = _Contact(place_c, zero, place_q, np.zeros(6), place_in_q, loaded)
        segs: list[Segment] = []
        lead_start = math.nan

        # Leaving the start (previous place) and reaching the pick.
        leave_start: Callable[[Segment | None, float], tuple[list[Segment], float]] | None = None
        if start_at_contact:
            p_start = self.ik.fk(start.q)[0]
            start_up_q = self._solve(p_start + up, pick_yaw, start.q)
            start_out = _Contact(p_start, zero, start.q, np.zeros(6), start_up_q, empty)
            bridge = partial(self._bridge, start_up_q, pick_in_q, belt_qd)
            leave_start = partial(self._leave, start, start_out, label="retreat")
            floor_z = min(p_start[2], pick_c[2])
        else:
            bridge = partial(self._bridge, start.q, pick_in_q, belt_qd)
            floor_z = -math.inf
        reach_pick = partial(self._reach_state, pick_in, label="descend_pick")
        s_ret, lead_start, s_to, s_desc, lead_pick_in = self._legs(
            start, leave_start, reach_pick, bridge, floor_z, "to_pick"
        )
        segs += [*s_ret, s_to, *s_desc]
        segs.append(
            hold_segment(
                JointState(pick_q, belt_qd),
                dwell_pick,
                "dwell_pick",
            )
        )

        # Lift, transfer, descend to the place.
        bridge = partial(self._bridge, lift_q, place_in_q, belt_qd)
        floor_z = min(pick_c[2], place_c[2])
        s_lift, lead_out, s_tr, s_down, lead_in = self._legs(
            segs[-1].end,
            partial(self._leave, segs[-1].end, pick_out, label="lift"),
            partial(self._reach_state, place_in, label="descend_place"),
            bridge,
            floor_z,
            "transfer",
        )
        segs += [*s_lift, s_tr, *s_down]
        segs.append(hold_segment(JointState(place_q), c.place_dwell, "dwell_place"))
        if end_retreat:
            segs.append(self._segment(segs[-1].end, place_in_q, None, "retreat_end"))
        leads = (lead_start, lead_pick_in, lead_out, lead_in)
        return Piecewise(tuple(segs)), pick_q, place_q, place_yaw, leads

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
            motion = self._rest_moves(q0, (pick_q, "bound_pick"), (place_q, "bound_place"))[0]
        else:
            t_pick, at_pick = self._move(JointState.at_rest(q0), pick_q, pick_qd, "bound_pick")
            motion = t_pick + self._move(at_pick, place_q, None, "bound_place")[0]
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
        t_pick, at_pick = self._move(s0, pick_q, pick_qd, "bound_pick")
        held = hold_segment(at_pick, pick_dwell, "bound_dwell")
        t_place, _ = self._move(held.end, place_q, None, "bound_place")
        dwells = pick_dwell + self.config.cycle.place_dwell
        return t_pick + t_place + dwells + self._end_bound(place_q, end_q)

    def _end_bound(self, place_q: Array, end_q: Array | None) -> float:
        """Time-optimal rest-to-rest move from the place contact to ``end_q`` [s] (0 if None)."""
        if end_q is None:
            return 0.0
        return self._rest_moves(as_joint_vector(place_q, "place_q"), (end_q, "bound_end"))[0]

    def plan_move(self, start: JointState, q: npt.ArrayLike, label: str = "move") -> Piecewise:
        """Time-optimal move from ``start`` to rest at ``q`` (6,) [rad] (e.g. back home).

        Raises:
            PlannerError: See `plan_segment`.
        """
        target = as_joint_vector(q, "q")
        return Piecewise((self._segment(start, target, None, label),))


def relative_rotation(tile_yaw: float, slot_yaw: float) -> float:
    """Rotation [rad] turning a tile at ``tile_yaw`` to ``slot_yaw``, wrapped to [-pi, pi).

    Raises:
        InvalidTargetError: A yaw is not finite.
    """
    if not (math.isfinite(tile_yaw) and math.isfinite(slot_yaw)):
        raise InvalidTargetError(f"yaws must be finite, got {tile_yaw!r}, {slot_yaw!r}")
    return float(wrap_angle(slot_yaw - tile_yaw))


__all__ = ["CyclePlan", "PickPlacePlanner", "relative_rotation"]
