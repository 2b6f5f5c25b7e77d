"""The contacts of one pick-and-place cycle: what is asked, and where the arm touches.

The pick contact and the approach points above the contacts by IK, and the place contact of the
equivalent rotation needing the least wrist travel (`choose_place`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planners.cycle.moves import ArmMoves, Array, Contact
from planners.errors import PlannerError, UnreachableError
from planners.joints import JointState, unwrap_target
from planners.tool_pose import symmetric_yaws


def rotate(xy: Array, yaw: float) -> Array:
    """Planar vector ``xy`` (2,) turned by ``yaw`` [rad], as a 3-vector with z = 0."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([c * xy[0] - s * xy[1], s * xy[0] + c * xy[1], 0.0])


@dataclass(frozen=True)
class CycleRequest:
    """What one `PickPlacePlanner.plan_cycle` call asks for (validated).

    Attributes:
        start: Arm state at the cycle's start (at rest). start_at_contact, end_retreat: As
            `PickPlacePlanner.plan_cycle` takes them.
        pick0: The grip point at the cycle's start, shape (3,) [m]. place: The place reference
            point, shape (3,) [m]. pick_yaw: Tool yaw at the pick [rad].
        rotations: Per equivalent rotation (rotation [rad], grasp offset (2,) [m], object yaw
            [rad]). belt: Belt velocity, shape (3,) [m/s].
    """

    start: JointState
    start_at_contact: bool
    end_retreat: bool
    pick0: Array
    place: Array
    pick_yaw: float
    rotations: tuple[tuple[float, Array, float], ...]
    belt: Array


@dataclass(frozen=True)
class CycleContacts:
    """The contacts of one cycle: pick (reached, then left after the dwell) and place."""

    pick_in: Contact
    pick_out: Contact
    place_in: Contact
    place_yaw: float
    belt_qd: Array


def choose_place(
    moves: ArmMoves,
    place: Array,
    pick_q: Array,
    pick_yaw: float,
    rotations: list[tuple[float, Array, float]],
) -> tuple[Array, Array, float]:
    """Place contact point, configuration and tool yaw for the cheapest equivalent rotation.

    Raises:
        UnreachableError: No equivalent rotation is reachable.
    """
    gap = np.array([0.0, 0.0, moves.config.cycle.place_gap])
    best: tuple[float, Array, Array, float] | None = None
    errors = []
    for rot, grasp, obj_yaw in rotations:
        point = place + gap + rotate(grasp, obj_yaw + rot)
        try:
            sol = moves.ik.solve_yaws(
                point, symmetric_yaws(pick_yaw + rot, 1), seed=pick_q, reference=pick_q
            )
            q = unwrap_target(pick_q, sol.q, moves.limits, moves.wrap)
        except PlannerError as exc:
            errors.append(str(exc))
            continue
        cost = float(np.sum(np.abs(q - pick_q)[list(moves.wrap)]))  # wrist travel [rad]
        if best is None or cost < best[0]:
            best = (cost, point, q, sol.yaw)
    if best is None:
        raise UnreachableError(
            f"place at {np.round(place, 4).tolist()} m unreachable with every equivalent "
            f"rotation: {'; '.join(errors)}"
        )
    return best[1], best[2], best[3]


def cycle_contacts(
    moves: ArmMoves, req: CycleRequest, pick_c: Array, up: Array, dwell_pick: float
) -> CycleContacts:
    """IK of the pick and place contacts and of the approach points above them."""
    c = moves.config.cycle
    # IK: pick contact, then the equivalent rotation needing least joint-6 travel.
    pick_q = moves.solve(pick_c, req.pick_yaw, req.start.q)
    place_c, place_q, place_yaw = choose_place(
        moves, req.place, pick_q, req.pick_yaw, list(req.rotations)
    )
    place_in_q = moves.solve(place_c + up, place_yaw, place_q)
    # Travelling with the belt during the dwell: constant joint velocity (linearised).
    belt_qd = moves.joint_velocity(pick_q, req.belt)
    pick_end_q = pick_q + belt_qd * dwell_pick
    pick_end = moves.ik.fk(pick_end_q)[0]
    # Approach points straight above the contacts (the belt's motion is superposed).
    pick_in_q = moves.solve(pick_c + up, req.pick_yaw, pick_q)
    lift_q = moves.solve(pick_end + up, req.pick_yaw, pick_end_q)
    # A wrapping joint (joint 6) may reach the place on any of its turns: the bridge takes
    # the turn nearest the lift, so the approach point and the contact take that same turn
    # (the vertical descent starts where the bridge ends).
    # (If the contact would leave the joint's range on that turn, both keep the IK's turn.)
    turn = unwrap_target(lift_q, place_in_q, moves.limits, moves.wrap) - place_in_q
    lo, hi = np.asarray(moves.limits.lower), np.asarray(moves.limits.upper)
    if turn.any() and np.all((place_q + turn >= lo) & (place_q + turn <= hi)):
        place_q, place_in_q = place_q + turn, place_in_q + turn
    # Drift limits: the empty pad only clears the tile tops, a held tile its own thickness.
    empty, loaded = c.empty_clearance_height, c.lateral_clearance_height
    zero = np.zeros(3)
    return CycleContacts(
        pick_in=Contact(pick_c, req.belt, pick_q, belt_qd, pick_in_q, empty),
        pick_out=Contact(pick_end, req.belt, pick_end_q, belt_qd, lift_q, loaded),
        place_in=Contact(place_c, zero, place_q, np.zeros(6), place_in_q, loaded),
        place_yaw=place_yaw,
        belt_qd=belt_qd,
    )


__all__ = ["CycleContacts", "CycleRequest", "choose_place", "cycle_contacts", "rotate"]
