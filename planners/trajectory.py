"""Jerk-limited, time-optimal joint trajectories with ruckig, chained point to point.

Ruckig's community version sends intermediate waypoints to a remote service, so a path through
several configurations is a chain of point-to-point segments. Each segment starts at the state
(position, velocity, acceleration) where the previous one ended and reaches its target position
with a target velocity: zero for a stop, non-zero to pass a via point without stopping
(blending), or a belt's velocity to travel with a moving tile. A `Piecewise` trajectory holds the
exact segments; `Piecewise.sample` turns it into a `JointTrajectory` value sampled at the control
period.

Joints 4 and 6 turn more than a full turn: targets are unwrapped to the equivalent angle
(``q + 2 pi k``) nearest to the start inside the joint range (`unwrap_target`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from ruckig import InputParameter, Result, Ruckig, Trajectory

from planners.config import N_JOINTS, JointLimits
from planners.errors import LimitError, TrajectoryError
from planners.joints import Array, JointState, as_joint_vector, check_in_range, unwrap_target

_OK_RESULTS = (Result.Working, Result.Finished)
_JOIN_TOLERANCE = 1e-9
"""Largest position [rad] or velocity [rad/s] jump accepted between joined pieces (rounding)."""


@dataclass(frozen=True)
class JointTrajectory:
    """A joint trajectory sampled at a fixed period.

    Attributes:
        times: Sample times, shape (n,) [s], starting at 0.
        q: Joint angles, shape (n, 6) [rad].
        qd: Joint velocities, shape (n, 6) [rad/s].
        qdd: Joint accelerations, shape (n, 6) [rad/s^2].
    """

    times: Array
    q: Array
    qd: Array
    qdd: Array

    @property
    def duration(self) -> float:
        """Time of the last sample [s]."""
        return float(self.times[-1])

    def at(self, t: float) -> tuple[Array, Array, Array]:
        """State at time ``t`` [s] (clamped to the trajectory), each shape (6,).

        Positions use cubic Hermite interpolation with the sampled velocities; velocities and
        accelerations are linear between samples.
        """
        t = min(max(float(t), 0.0), self.duration)
        i = int(np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 2))
        t0, t1 = self.times[i], self.times[i + 1]
        h = t1 - t0
        s = (t - t0) / h
        h00 = 2 * s**3 - 3 * s**2 + 1
        h10 = s**3 - 2 * s**2 + s
        h01 = -2 * s**3 + 3 * s**2
        h11 = s**3 - s**2
        q = h00 * self.q[i] + h10 * h * self.qd[i] + h01 * self.q[i + 1] + h11 * h * self.qd[i + 1]
        qd = (1 - s) * self.qd[i] + s * self.qd[i + 1]
        qdd = (1 - s) * self.qdd[i] + s * self.qdd[i + 1]
        return q, qd, qdd


@dataclass(frozen=True, eq=False)
class Segment:
    """One piece of a chained trajectory.

    A ruckig segment (``ruckig`` set), a superposition of time windows of other segments
    (``parts`` set, see `superpose`), segments played one after the other (``pieces`` set, see
    `join`), or a constant-velocity segment from ``start.q`` with velocity ``start.qd`` (a hold
    at rest when that velocity is zero).

    Attributes:
        start: State at the segment's start.
        end: State at the segment's end.
        duration: Length [s].
        label: Name of the phase (``"descend_pick"``, ``"dwell_pick"``, ...).
        ruckig: Ruckig's trajectory, or None.
        parts: (segment, time offset [s]) pairs summed by a superposed segment.
        offset: Subtracted from the parts' summed positions, shape (6,) [rad].
        pieces: Segments played in order, each starting where the previous one ends.
    """

    start: JointState
    end: JointState
    duration: float
    label: str = ""
    ruckig: Trajectory | None = None
    parts: tuple[tuple[Segment, float], ...] = ()
    offset: Array | None = None
    pieces: tuple[Segment, ...] = ()

    def state(self, tau: float) -> tuple[Array, Array, Array]:
        """State at ``tau`` [s] after the segment's start, each shape (6,)."""
        tau = min(max(tau, 0.0), self.duration)
        if self.pieces:
            for piece in self.pieces[:-1]:
                if tau <= piece.duration:
                    return piece.state(tau)
                tau -= piece.duration
            return self.pieces[-1].state(tau)
        if self.parts:
            q, qd, qdd = np.zeros(N_JOINTS), np.zeros(N_JOINTS), np.zeros(N_JOINTS)
            for seg, t0 in self.parts:
                pq, pqd, pqdd = seg.state(t0 + tau)
                q, qd, qdd = q + pq, qd + pqd, qdd + pqdd
            assert self.offset is not None
            return q - self.offset, qd, qdd
        if self.ruckig is None:
            return self.start.q + self.start.qd * tau, self.start.qd, np.zeros(N_JOINTS)
        p, v, a = self.ruckig.at_time(tau)
        return np.asarray(p), np.asarray(v), np.asarray(a)

    def states(self, taus: npt.ArrayLike) -> tuple[Array, Array, Array]:
        """States at times ``taus`` (n,) [s] after the segment's start, each shape (n, 6).

        The same values as `state` at each time, evaluated a whole array at once.
        """
        t = np.clip(np.asarray(taus, dtype=np.float64), 0.0, self.duration)
        if self.pieces:
            q, qd, qdd = (np.empty((t.size, N_JOINTS)) for _ in range(3))
            starts = np.cumsum([0.0] + [p.duration for p in self.pieces[:-1]])
            which = np.clip(np.searchsorted(starts, t, side="left") - 1, 0, len(self.pieces) - 1)
            for k, piece in enumerate(self.pieces):
                sel = which == k
                if sel.any():
                    q[sel], qd[sel], qdd[sel] = piece.states(t[sel] - starts[k])
            return q, qd, qdd
        if self.parts:
            q, qd, qdd = (np.zeros((t.size, N_JOINTS)) for _ in range(3))
            for seg, t0 in self.parts:
                pq, pqd, pqdd = seg.states(t0 + t)
                q, qd, qdd = q + pq, qd + pqd, qdd + pqdd
            assert self.offset is not None
            return q - self.offset, qd, qdd
        if self.ruckig is None:
            q = self.start.q[None, :] + self.start.qd[None, :] * t[:, None]
            return q, np.repeat(self.start.qd[None, :], t.size, 0), np.zeros((t.size, N_JOINTS))
        rows = [self.ruckig.at_time(float(x)) for x in t]
        return (
            np.array([r[0] for r in rows]).reshape(t.size, N_JOINTS),
            np.array([r[1] for r in rows]).reshape(t.size, N_JOINTS),
            np.array([r[2] for r in rows]).reshape(t.size, N_JOINTS),
        )


def _ruckig_input(
    start: JointState, target_q: Array, target_qd: Array, target_qdd: Array, limits: JointLimits
) -> InputParameter:
    inp = InputParameter(N_JOINTS)
    inp.current_position = start.q.tolist()
    inp.current_velocity = start.qd.tolist()
    inp.current_acceleration = start.qdd.tolist()
    inp.target_position = target_q.tolist()
    inp.target_velocity = target_qd.tolist()
    inp.target_acceleration = target_qdd.tolist()
    inp.max_velocity = list(limits.max_velocity)
    inp.max_acceleration = list(limits.max_acceleration)
    inp.max_jerk = list(limits.max_jerk)
    return inp


def plan_segment(
    start: JointState,
    target_q: npt.ArrayLike,
    limits: JointLimits,
    target_qd: npt.ArrayLike | None = None,
    *,
    target_qdd: npt.ArrayLike | None = None,
    label: str = "",
    min_duration: float = 0.0,
) -> Segment:
    """Time-optimal jerk-limited segment from ``start`` to a target position and velocity.

    Args:
        start: Start state (any velocity and acceleration inside the limits).
        target_q: Target configuration, shape (6,) [rad] (already unwrapped).
        limits: Kinematic limits.
        target_qd: Target velocity, shape (6,) [rad/s]; None stops at the target.
        target_qdd: Target acceleration, shape (6,) [rad/s^2]; None is zero.
        label: Phase name stored on the segment.
        min_duration: Stretch the segment to at least this long [s].

    Raises:
        InvalidTargetError: Non-finite or wrongly shaped targets.
        LimitError: Target outside the joint range or target speed above the axis limit.
        TrajectoryError: Ruckig found no trajectory.
    """
    q1 = as_joint_vector(target_q, "target_q")
    qd1 = np.zeros(N_JOINTS) if target_qd is None else as_joint_vector(target_qd, "target_qd")
    qdd1 = np.zeros(N_JOINTS) if target_qdd is None else as_joint_vector(target_qdd, "target_qdd")
    check_in_range(q1, limits, f"segment {label!r} target")
    over = np.flatnonzero(np.abs(qd1) > np.asarray(limits.max_velocity))
    if over.size:
        i = int(over[0])
        raise LimitError(
            f"segment {label!r}: target velocity of joint {i + 1} {qd1[i]:.4f} rad/s exceeds "
            f"the axis limit {limits.max_velocity[i]:.4f} rad/s"
        )
    inp = _ruckig_input(start, q1, qd1, qdd1, limits)
    if min_duration > 0.0:
        inp.minimum_duration = min_duration
    traj = Trajectory(N_JOINTS)
    try:
        result = Ruckig(N_JOINTS).calculate(inp, traj)
    except RuntimeError as exc:
        raise TrajectoryError(f"segment {label!r}: ruckig rejected the input: {exc}") from exc
    if result not in _OK_RESULTS:
        raise TrajectoryError(
            f"segment {label!r}: ruckig returned {result} from q={start.q.tolist()} "
            f"qd={start.qd.tolist()} to q={q1.tolist()} qd={qd1.tolist()}"
        )
    end = JointState(q1, qd1, qdd1)
    return Segment(start, end, float(traj.duration), label, traj)


def hold_segment(state: JointState, duration: float, label: str = "") -> Segment:
    """Constant-velocity segment (a hold when ``state.qd`` is zero) of ``duration`` [s].

    Raises:
        LimitError: Negative or non-finite duration.
    """
    if not (math.isfinite(duration) and duration >= 0.0):
        raise LimitError(f"segment {label!r}: duration must be >= 0 s, got {duration!r}")
    q_end = state.q + state.qd * duration
    start = JointState(state.q, state.qd, np.zeros(N_JOINTS))
    return Segment(start, JointState(q_end, state.qd, np.zeros(N_JOINTS)), duration, label)


def window(seg: Segment, t0: float, t1: float, label: str | None = None) -> Segment:
    """The part of ``seg`` between ``t0`` and ``t1`` [s] as a segment of its own."""
    return superpose(
        [(seg, t0)], t1 - t0, np.zeros(N_JOINTS), seg.label if label is None else label
    )


def superpose(
    parts: Sequence[tuple[Segment, float]], duration: float, offset: Array, label: str
) -> Segment:
    """Sum of time windows of segments: ``sum(seg.state(t0 + tau)) - offset``.

    Used to overlap two motions (a vertical lift and the start of a transfer). Limits are not
    checked here: sample the result and `validate` it.

    Args:
        parts: (segment, start time inside it [s]) pairs.
        duration: Length of the superposed segment [s].
        offset: Position subtracted from the sum, shape (6,) [rad].
        label: Phase name.
    """
    proto = Segment(
        JointState(np.zeros(N_JOINTS)),
        JointState(np.zeros(N_JOINTS)),
        duration,
        label,
        parts=tuple(parts),
        offset=offset,
    )
    q0, qd0, qdd0 = proto.state(0.0)
    q1, qd1, qdd1 = proto.state(duration)
    return Segment(
        JointState(q0, qd0, qdd0),
        JointState(q1, qd1, qdd1),
        duration,
        label,
        parts=tuple(parts),
        offset=offset,
    )


def join(pieces: Sequence[Segment], label: str) -> Segment:
    """Segments played one after the other as one segment (each starts where the last ended).

    Raises:
        TrajectoryError: No pieces, or a piece does not start where the previous one ended.
    """
    if not pieces:
        raise TrajectoryError(f"segment {label!r}: join needs at least one piece")
    for a, b in zip(pieces[:-1], pieces[1:], strict=True):
        gap = max(
            float(np.max(np.abs(a.end.q - b.start.q))),
            float(np.max(np.abs(a.end.qd - b.start.qd))),
        )
        if gap > _JOIN_TOLERANCE:
            raise TrajectoryError(
                f"segment {label!r}: piece {b.label!r} starts {gap:.2e} (rad or rad/s) away "
                f"from where {a.label!r} ends"
            )
    return Segment(
        pieces[0].start,
        pieces[-1].end,
        float(sum(p.duration for p in pieces)),
        label,
        pieces=tuple(pieces),
    )


@dataclass(frozen=True)
class Piecewise:
    """A chain of segments, each starting where the previous one ends.

    Attributes:
        segments: The segments in order.
    """

    segments: tuple[Segment, ...]

    @property
    def duration(self) -> float:
        """Total duration [s]."""
        return float(sum(s.duration for s in self.segments))

    @property
    def end(self) -> JointState:
        """State at the end."""
        return self.segments[-1].end

    def index(self, label: str) -> int:
        """Index of the first segment with ``label``.

        Raises:
            KeyError: No segment has that label.
        """
        for i, s in enumerate(self.segments):
            if s.label == label:
                return i
        raise KeyError(f"no segment labelled {label!r}; labels: {[s.label for s in self.segments]}")

    def start_time(self, label: str) -> float:
        """Start time [s] of the first segment with ``label``.

        Raises:
            KeyError: No segment has that label.
        """
        t = 0.0
        for s in self.segments:
            if s.label == label:
                return t
            t += s.duration
        raise KeyError(f"no segment labelled {label!r}; labels: {[s.label for s in self.segments]}")

    def end_time(self, label: str) -> float:
        """End time [s] of the last segment with ``label``.

        Raises:
            KeyError: No segment has that label.
        """
        t, found = 0.0, None
        for s in self.segments:
            t += s.duration
            if s.label == label:
                found = t
        if found is None:
            raise KeyError(f"no segment labelled {label!r}")
        return found

    def sample(self, dt: float) -> JointTrajectory:
        """Sample every ``dt`` [s] from 0 to the end (the end state is always the last sample).

        Raises:
            LimitError: ``dt`` not positive.
        """
        if not (math.isfinite(dt) and dt > 0.0):
            raise LimitError(f"sample period must be positive, got {dt!r}")
        total = self.duration
        n = int(math.floor(total / dt + 1e-9)) + 1
        times = np.arange(n, dtype=np.float64) * dt
        if total - times[-1] > 1e-9:
            times = np.append(times, total)
        q = np.empty((times.size, N_JOINTS))
        qd = np.empty_like(q)
        qdd = np.empty_like(q)
        bounds = np.cumsum([0.0] + [s.duration for s in self.segments])
        seg_of = np.clip(
            np.searchsorted(bounds, times, side="right") - 1, 0, len(self.segments) - 1
        )
        for k, (t, i) in enumerate(zip(times, seg_of, strict=True)):
            q[k], qd[k], qdd[k] = self.segments[i].state(float(t - bounds[i]))
        return JointTrajectory(times, q, qd, qdd)


def chain(
    start: JointState,
    targets: Sequence[tuple[npt.ArrayLike, npt.ArrayLike | None, str]],
    limits: JointLimits,
    wrap_joints: Sequence[int] = (3, 5),
) -> Piecewise:
    """Chain time-optimal segments through targets ``(q, qd or None, label)``.

    Wrapping joints of each target are unwrapped relative to the previous target.

    Raises:
        PlannerError: See `plan_segment` and `unwrap_target`.
    """
    segments: list[Segment] = []
    state = start
    for q, qd, label in targets:
        q_t = unwrap_target(state.q, q, limits, wrap_joints)
        seg = plan_segment(state, q_t, limits, qd, label=label)
        segments.append(seg)
        state = seg.end
    return Piecewise(tuple(segments))


__all__ = [
    "JointTrajectory",
    "Piecewise",
    "Segment",
    "chain",
    "hold_segment",
    "join",
    "plan_segment",
    "superpose",
    "window",
]
