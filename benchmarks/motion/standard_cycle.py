"""ABB's standard cycle timed by the planner, stopping at every corner and blended.

25 mm up, 300 mm across, 25 mm down (`STANDARD_CYCLE`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from envs.cell.config import load_cell_config
from envs.cell.scene import build_arm_model
from planners.config import PlannerConfig
from planners.ik import IKSolver
from planners.joints import JointState
from planners.pick_place import PickPlacePlanner

STANDARD_CYCLE = (0.025, 0.300, 0.025)
"""ABB's standard picking cycle: up 25 mm, 300 mm across, down 25 mm, and back [m]."""


STANDARD_CYCLE_CENTRE = (0.5, 0.0, 0.3)
"""Where the standard cycle is planned: its lower midpoint, 0.5 m in front of the base [m]."""


def _standard_cycle_ends(
    planner_config: PlannerConfig,
) -> tuple[IKSolver, PickPlacePlanner, np.ndarray, np.ndarray, np.ndarray]:
    """IK, planner, the two lower corners (3,) [m] and the lift (3,) [m] of the standard cycle."""
    up, across, _ = STANDARD_CYCLE
    arm = build_arm_model(load_cell_config(), with_cell=False)
    ik = IKSolver(arm, planner_config.ik, planner_config.limits)
    planner = PickPlacePlanner(ik, planner_config)
    cx, cy, cz = STANDARD_CYCLE_CENTRE
    a, b = np.array([cx, cy - across / 2, cz]), np.array([cx, cy + across / 2, cz])
    return ik, planner, a, b, np.array([0.0, 0.0, up])


def standard_cycle_s(planner_config: PlannerConfig) -> float:
    """The standard cycle's duration [s] with the planners' limits and a stop at every corner.

    Tool down, up 25 mm, 300 mm sideways, down 25 mm and the same way back, each leg a
    time-optimal joint-space move from rest to rest. ABB's catalogue figure is for a blended
    path (1 kg payload), so this stop-everywhere time is no check of the limits: compare
    `standard_cycle_blended_s`.
    """
    ik, planner, a, b, lift = _standard_cycle_ends(planner_config)
    corners = [a, a + lift, b + lift, b, b + lift, a + lift, a]
    q = ik.solve(corners[0], 0.0).q
    total = 0.0
    for p in corners[1:]:
        q_next = ik.solve(p, 0.0, seed=q).q
        move = planner.plan_move(JointState.at_rest(q), q_next)
        total += move.duration
        q = move.end.q
    return total


def standard_cycle_blended_s(planner_config: PlannerConfig) -> float:
    """The standard cycle's duration [s] with the top of the cycle flown through.

    The cell's own pick-and-place planning with the approach points at the cycle's 25 mm height
    and no vacuum dwell, press or gap: from one lower corner, up, across and down to the other
    (the vertical legs flown through with the planner's lead, the tool within
    ``max_lateral_drift`` of vertical below the clearance heights), and back. This is the
    figure to hold against ABB's (about 0.85 s for the IRB 140, 1 kg, blended path).
    """
    up = STANDARD_CYCLE[0]
    cycle = replace(
        planner_config.cycle,
        approach_height=up,
        pick_dwell=0.0,
        place_dwell=0.0,
        belt_match_time=0.0,
        pick_press=0.0,
        place_gap=0.0,
    )
    ik, planner, a, b, _ = _standard_cycle_ends(replace(planner_config, cycle=cycle))
    q_b = ik.solve(b, 0.0).q
    plan = planner.plan_cycle(
        JointState.at_rest(q_b), a, b, 0.0, start_at_contact=True, end_retreat=False
    )
    return plan.duration


__all__ = [
    "STANDARD_CYCLE",
    "STANDARD_CYCLE_CENTRE",
    "standard_cycle_blended_s",
    "standard_cycle_s",
]
