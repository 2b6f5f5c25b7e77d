"""Leads at the approach points: how far the next move may overlap a vertical one.

A lead superposes the lead joints' bridge on the vertical move off or onto a contact; the largest
lead (bisection) that keeps the tool within ``max_lateral_drift`` of vertical below the clearance
height is used, or a counter-swung bridge when that is faster. The links between two leads must
keep their clearance and limits and not be held up by ruckig's synchronisation (see
`planners.pick_place` for the whole cycle).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial

import numpy as np

from planners.cycle.moves import ArmMoves, Array, Contact
from planners.errors import PlannerError
from planners.joints import JointState
from planners.limit_checks import segment_within_limits
from planners.trajectory import Segment, superpose, window

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


class Leads:
    """Vertical moves with leads, and the links between them, for one `ArmMoves`."""

    def __init__(self, moves: ArmMoves) -> None:
        self.moves = moves
        self.config = moves.config
        self.limits = moves.limits

    def drift_ok(self, segs: list[Segment], contact: Contact, leaving: bool) -> bool:
        """Below the clearance height the tool stays over the (belt-moving) contact point.

        Checked at the samples and, by bisection, where the tool crosses the clearance height
        (between two samples the drift can grow by a tenth of a millimetre there).
        """
        c = self.config.cycle
        taus, pos = self.moves.positions(segs)
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
                r = relative(np.array([t_mid]), self.moves.tcp_at(segs, t_mid)[None, :])[0]
                if r[2] < contact.clearance:
                    t_low = t_mid
                else:
                    t_high = t_mid
            r = relative(np.array([t_low]), self.moves.tcp_at(segs, t_low)[None, :])[0]
            lateral.append(float(np.linalg.norm(r[:2])))
        return bool(not lateral or max(lateral) <= c.max_lateral_drift)

    def ok(self, segs: list[Segment], contact: Contact, leaving: bool) -> bool:
        """Segments within every limit and, below the clearance height, over the contact."""
        tr = self.config.trajectory
        return all(
            segment_within_limits(s, self.limits, tr.sample_dt, tr.limit_tolerance)
            for s in segs
            if s.parts
        ) and self.drift_ok(segs, contact, leaving)

    def largest_lead(
        self,
        build: Callable[[float], list[Segment]],
        duration: float,
        contact: Contact,
        leaving: bool,
        floor: float = 0.0,
    ) -> tuple[list[Segment], float] | None:
        """Largest lead tau in [floor, duration] whose segments pass the checks (bisection).

        Returns None when even tau = ``floor`` fails.
        """
        low = build(floor)
        if not self.ok(low, contact, leaving):
            return None
        full = build(duration)
        if self.ok(full, contact, leaving):
            return full, duration
        best, lo, hi = (low, floor), floor, duration
        for _ in range(self.config.cycle.lead_bisections):
            mid = 0.5 * (lo + hi)
            segs = build(mid)
            if self.ok(segs, contact, leaving):
                best, lo = (segs, mid), mid
            else:
                hi = mid
        return best

    def best_lead(  # noqa: PLR0917
        self,
        build: Callable[[Segment | None, float], list[Segment]],
        base: Segment,
        contact: Contact,
        bridge: Segment | None,
        leaving: bool,
        cap: float = 1.0,
    ) -> tuple[list[Segment], float] | None:
        """The faster of the largest plain lead and the shortest counter-swung full lead.

        Plain: the bridge starts ``tau`` before the vertical move ends (leaving; reaching: ends
        ``tau`` after it starts), the largest ``tau`` that keeps the drift (`largest_lead`).
        When the whole vertical move (``tau = D``) breaks the drift at the clearance crossing,
        the bridge is tried over the whole move with each ``counter_swing`` length in turn
        (`swung`), the shortest valid one kept. With a bridge of duration ``T`` the lead
        joints come to rest at their target ``T - tau`` after the vertical move's start plus
        ``D``: a swung bridge (``T_s``) wins unless the plain lead exceeds
        ``D - (T_s - T)``, which one more check decides.
        """
        if bridge is None:
            zero = build(None, 0.0)
            return (zero, 0.0) if self.ok(zero, contact, leaving) else None
        dur = base.duration * cap  # the longest lead allowed ("whole" below)
        full = build(bridge, dur)
        if self.ok(full, contact, leaving):
            return full, dur
        for pulse in self.config.cycle.counter_swing:
            swung = self.moves.swung(bridge, pulse, leaving, contact.qd)
            if swung is None:
                continue
            segs = build(swung, dur)
            if not self.ok(segs, contact, leaving):
                continue
            # Equal finish for the plain bridge at this lead: it must do better to win.
            tau_eq = dur - (swung.duration - bridge.duration)
            if tau_eq <= 0.0 or not self.ok(build(bridge, tau_eq), contact, leaving):
                return segs, dur
            return self.largest_lead(partial(build, bridge), dur, contact, leaving, tau_eq)
        return self.largest_lead(partial(build, bridge), dur, contact, leaving)

    def leave(
        self,
        start: JointState,
        contact: Contact,
        bridge: Segment | None,
        cap: float = 1.0,
        *,
        label: str,
    ) -> tuple[list[Segment], float]:
        """Vertical move off a contact to its approach point, with the largest valid lead.

        With lead tau, the move follows the pure vertical move, and during its last tau seconds
        the first tau seconds of the bridge (the transfer starting) are superposed; the bridge
        may start with a counter-swing (`swung`), whichever gets the lead joints there first.

        Returns the segments and the lead time used (NaN when it had to stop).
        """
        if self.config.trajectory.blend:
            base = self.moves.vertical(contact, True, start)

            def build(br: Segment | None, tau: float) -> list[Segment]:
                if br is None or tau <= 0.0:
                    return [window(base, 0.0, base.duration, label)]
                t_split = base.duration - tau
                segs = [] if t_split <= 0.0 else [window(base, 0.0, t_split, label)]
                return [*segs, superpose([(base, t_split), (br, 0.0)], tau, br.start.q, label)]

            found = self.best_lead(build, base, contact, bridge, True, cap)
            if found is not None:
                return found
        q_stop = contact.approach_q
        seg = self.moves.segment(
            start, q_stop, self.moves.joint_velocity(q_stop, contact.belt), label
        )
        return [seg], math.nan

    def reach_state(
        self, contact: Contact, bridge: Segment | None, cap: float = 1.0, *, label: str
    ) -> tuple[JointState, list[Segment], float]:
        """Approach-point state (with the largest valid lead) and the vertical move to contact.

        With lead tau, the last tau seconds of the bridge (the transfer ending, possibly with a
        counter-swing, `swung`) are superposed on the first tau seconds of the pure vertical
        descent.

        Returns the approach-point state, the descent segments and the lead time (NaN when it
        has to stop at the approach point).
        """
        if self.config.trajectory.blend:
            base = self.moves.vertical(contact, False)

            def build(br: Segment | None, tau: float) -> list[Segment]:
                if br is None or tau <= 0.0:
                    return [window(base, 0.0, base.duration, label)]
                first = superpose([(base, 0.0), (br, br.duration - tau)], tau, br.end.q, label)
                rest = [window(base, tau, base.duration, label)] if tau < base.duration else []
                return [first, *rest]

            found = self.best_lead(build, base, contact, bridge, False, cap)
            if found is not None:
                return found[0][0].start, found[0], found[1]
        stop = JointState(
            contact.approach_q, self.moves.joint_velocity(contact.approach_q, contact.belt)
        )
        return stop, [self.moves.segment(stop, contact.q, contact.qd, label)], math.nan

    def legs(  # noqa: PLR0917
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
            link, need = self.link(from_state, via, floor_z, label)
            if link is not None:
                lead = lead_out if leave is not None else math.nan
                return s_out, lead, link, s_in, lead_in
            if stretch and need is not None:
                middle = br.duration - np.nan_to_num(lead_out) - np.nan_to_num(lead_in)
                br = bridge(br.duration + max(need - middle, 0.0) + _SYNC_SLACK)
            elif stretch:  # not a synchronisation gap: stretching will not help
                stretching = False
                br = bridge(0.0)
        link = self.moves.segment(from_state, via.q, via.qd, label, via.qdd)
        return s_out, lead_out if leave is not None else math.nan, link, s_in, lead_in

    def link(
        self, leave: JointState, reach: JointState, floor_z: float, label: str
    ) -> tuple[Segment | None, float | None]:
        """The move from a leave state to a reach state, if usable (see `legs`).

        Returns the move or None, and when synchronisation held it up, the longest time a
        joint alone needs for it [s] (else None).
        """
        try:
            seg = self.moves.segment(leave, reach.q, reach.qd, label, reach.qdd)
        except PlannerError:
            return None, None
        if seg.ruckig is not None:
            alone = float(np.max(seg.ruckig.independent_min_durations))
            if seg.duration > alone + _SYNC_SLACK:
                return None, alone
        return (seg, None) if self.link_ok(seg, floor_z) else (None, None)

    def link_ok(self, seg: Segment, floor_z: float) -> bool:
        """Whether a move between two leads keeps its clearance and every limit.

        Ruckig exceeds a limit when its start state cannot brake in time (a fast lead plus a
        belt's velocity, say).
        """
        tr = self.config.trajectory
        return self.moves.clearance_ok(seg, floor_z) and segment_within_limits(
            seg, self.limits, tr.sample_dt, tr.limit_tolerance
        )


__all__ = ["Leads"]
