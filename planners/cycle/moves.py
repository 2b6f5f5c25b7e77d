"""The arm's moves at its limits, as one pick-and-place cycle uses them.

Time-optimal segments (ruckig) and rest-to-rest durations in closed form, joint targets
unwrapped on the wrapping joints, the TCP sampled along segments, the vertical moves off and onto
a contact (`Contact`) and the lead joints' bridge between two approach points (with or without a
counter-swing). Which leads pass the checks is `planners.cycle.leads`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from planners.config import JointLimits, PlannerConfig
from planners.errors import PlannerError
from planners.ik import IKSolver
from planners.joints import (
    JointState,
    as_joint_vector,
    check_in_range,
    unwrap_target,
    unwrap_values,
)
from planners.rest_to_rest import rest_to_rest_duration
from planners.trajectory import Segment, hold_segment, join, plan_segment, superpose

Array = npt.NDArray[np.float64]

_CHECK_SAMPLES = 40
"""FK samples per segment when checking drift and clearance (resolution, not a tunable)."""
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
class Contact:
    """A contact point the tool leaves or reaches vertically (in the belt's frame)."""

    point: Array  # contact position at the segment's start (leaving) or end (reaching) [m]
    belt: Array  # velocity of the frame the motion is vertical in [m/s]
    q: Array  # configuration at the contact [rad]
    qd: Array  # joint velocity at the contact [rad/s]
    approach_q: Array  # configuration at the approach point [rad]
    clearance: float  # below this height above the contact the drift is limited [m]


class ArmMoves:
    """The moves of one robot under one planner configuration.

    Args:
        ik: The IK solver (its model defines the robot).
        config: Planner settings.
    """

    def __init__(self, ik: IKSolver, config: PlannerConfig) -> None:
        self.ik = ik
        self.config = config
        self.limits = config.limits
        self.wrap = config.trajectory.wrap_joints
        share = np.ones(6)
        share[list(config.cycle.lead_joints)] = config.cycle.lead_share
        self.share = share
        self.vertical_limits = _share(self.limits, np.where(share < 1.0, 1.0 - share, 1.0))

    def joint_velocity(self, q: Array, linear: Array) -> Array:
        """Joint velocity (6,) [rad/s] moving the TCP at ``linear`` (3,) [m/s] without turning."""
        if not np.any(linear):
            return np.zeros(q.shape)
        jac = self.ik.jacobian(q)
        twist = np.concatenate([linear, np.zeros(3)])
        qd, *_ = np.linalg.lstsq(jac, twist, rcond=None)
        return np.asarray(qd)

    def segment(
        self,
        start: JointState,
        q: Array,
        qd: Array | None,
        label: str,
        qdd: Array | None = None,
    ) -> Segment:
        """Time-optimal segment from ``start`` to ``q`` (unwrapped), ending at ``qd``, ``qdd``."""
        q_t = unwrap_target(start.q, q, self.limits, self.wrap)
        return plan_segment(start, q_t, self.limits, qd, target_qdd=qdd, label=label)

    def move(
        self, start: JointState, q: Array, qd: Array | None, label: str
    ) -> tuple[float, JointState]:
        """Duration [s] and end state of the move `segment` plans, without the trajectory.

        From rest to rest in closed form (`rest_moves`); any other boundary state by ruckig.

        Raises:
            PlannerError: See `plan_segment`.
        """
        stops = qd is None or not as_joint_vector(qd, "target_qd").any()
        if stops and not (start.qd.any() or start.qdd.any()):
            duration, q_t = self.rest_moves(start.q, (q, label))
            return duration, JointState(np.array(q_t))
        seg = self.segment(start, q, qd, label)
        return seg.duration, seg.end

    def rest_moves(
        self, start_q: Array, *moves: tuple[npt.ArrayLike, str]
    ) -> tuple[float, list[float]]:
        """Duration [s] of time-optimal moves from rest to rest, and the last target [rad].

        From ``start_q`` (6,) [rad] through each ``(q, label)`` of ``moves``, targets unwrapped
        as `segment` does. In closed form (`rest_to_rest_duration`: ruckig's duration to
        ~1e-12 s), on plain floats.

        Raises:
            PlannerError: A non-finite or wrongly shaped target, or one outside the joint ranges.
        """
        prev = start_q.tolist()
        total = 0.0
        for q, label in moves:
            q_t = unwrap_values(prev, as_joint_vector(q, "q_to").tolist(), self.limits, self.wrap)
            check_in_range(q_t, self.limits, f"segment {label!r} target")
            total += rest_to_rest_duration(prev, q_t, self.limits)
            prev = q_t
        return total, prev

    def positions(self, segs: list[Segment]) -> tuple[Array, Array]:
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

    def tcp_at(self, segs: list[Segment], t: float) -> Array:
        """TCP position (3,) [m] at time ``t`` [s] from the first segment's start."""
        for seg in segs:
            if t <= seg.duration:
                return self.ik.fk(seg.state(t)[0])[0]
            t -= seg.duration
        return self.ik.fk(segs[-1].state(segs[-1].duration)[0])[0]

    def clearance_ok(self, seg: Segment, floor_z: float) -> bool:
        """The segment keeps ``transfer_clearance`` above ``floor_z`` [m] throughout."""
        _, pos = self.positions([seg])
        return bool(pos[:, 2].min() >= floor_z + self.config.cycle.transfer_clearance)

    def solve(self, position: Array, yaw: float, seed: Array) -> Array:
        """Tool-down IK at ``position`` (3,) [m] and ``yaw`` [rad], unwrapped towards ``seed``."""
        q = self.ik.solve_yaws(position, np.array([yaw]), seed=seed, reference=seed).q
        return unwrap_target(seed, q, self.limits, self.wrap)

    def vertical(self, contact: Contact, leaving: bool, start: JointState | None = None) -> Segment:
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
        lim = self.vertical_limits
        q_contact = contact.q if start is None else start.q
        if leaving:
            q1 = unwrap_target(q_contact, contact.approach_q, lim, self.wrap)
            static = plan_segment(JointState.at_rest(q_contact), q1, lim, qd_v, label="vertical")
        else:
            s0 = JointState(contact.approach_q, qd_v)
            q1 = unwrap_target(s0.q, q_contact, lim, self.wrap)
            static = plan_segment(s0, q1, lim, None, label="vertical")
        if not np.any(contact.belt):
            return static
        ramp = hold_segment(JointState(np.zeros(6), contact.qd), static.duration)
        offset = np.zeros(6) if leaving else contact.qd * static.duration
        return superpose([(static, 0.0), (ramp, 0.0)], static.duration, offset, "vertical")

    def swung(
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
        lim = _share(self.limits, self.share, frame_qd)
        rest = bridge.duration - pulse  # a stretched bridge (`legs`) stays stretched
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

    def bridge(self, a: Array, b: Array, frame_qd: Array, min_duration: float = 0.0) -> Segment:
        """Rest-to-rest time-optimal move of the lead joints between approach points.

        The lead's source: only ``lead_joints`` (base and wrist rotations) move, with
        ``lead_share`` of their acceleration and jerk; the vertical moves get the rest, so the
        superposition keeps every limit. Its velocity limits leave room for ``frame_qd`` (6,)
        [rad/s], the joint velocity of a moving belt superposed at an end (zero if static). It
        lasts at least ``min_duration`` [s] (see `legs`).
        """
        target = a.copy()
        idx = list(self.config.cycle.lead_joints)
        # b's own turn of a wrapping joint: the vertical move after the bridge starts there.
        target[idx] = b[idx]
        lim = _share(self.limits, self.share, frame_qd)
        return plan_segment(
            JointState.at_rest(a), target, lim, label="bridge", min_duration=min_duration
        )


__all__ = ["ArmMoves", "Array", "Contact"]
