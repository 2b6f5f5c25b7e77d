"""Closed-form rest-to-rest durations against ruckig, and the planners' bounds that use them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from ruckig import InputParameter, Ruckig, Trajectory

from planners.config import JointLimits, load_planner_config
from planners.errors import LimitError
from planners.joints import JointState, unwrap_target
from planners.pick_place import PickPlacePlanner
from planners.rest_to_rest import axis_duration, rest_to_rest_duration
from planners.trajectory import hold_segment, plan_segment

CFG = load_planner_config()
LIMITS = CFG.limits
TOL = 1e-9  # s


def _ruckig_duration(q0: np.ndarray, q1: np.ndarray, v: list, a: list, j: list) -> float:
    n = len(v)
    inp = InputParameter(n)
    inp.current_position = list(q0)
    inp.target_position = list(q1)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = v, a, j
    traj = Trajectory(n)
    Ruckig(n).calculate(inp, traj)
    return float(traj.duration)


def test_one_axis_matches_ruckig_over_random_limits_and_distances() -> None:
    """All three profile shapes (cruise, acceleration-limited, jerk only) over wide ranges."""
    rng = np.random.default_rng(0)
    shapes = {"cruise": 0, "accel": 0, "jerk": 0}
    for _ in range(4000):
        v, a, j = 10 ** rng.uniform(-1, 1), 10 ** rng.uniform(-0.5, 2), 10 ** rng.uniform(0, 3)
        d = (10 ** rng.uniform(-6, 1.5) if rng.random() < 0.5 else rng.uniform(0, 3)) * (
            1 if rng.random() < 0.5 else -1
        )
        t_up = 2 * math.sqrt(v / j) if v * j <= a * a else v / a + a / j
        shapes[
            "cruise" if abs(d) >= v * t_up else "jerk" if abs(d) <= 2 * a**3 / j**2 else "accel"
        ] += 1
        expected = _ruckig_duration(np.zeros(1), np.array([d]), [v], [a], [j])
        assert axis_duration(d, v, a, j) == pytest.approx(expected, abs=TOL)
    assert min(shapes.values()) > 400, shapes
    assert axis_duration(0.0, 1.0, 1.0, 1.0) == 0.0


def test_synchronised_duration_is_ruckigs_for_the_arm() -> None:
    """Six joints at the arm's limits, random configurations (large and tiny moves)."""
    rng = np.random.default_rng(1)
    lo, hi = np.array(LIMITS.lower), np.array(LIMITS.upper)
    v, a, j = list(LIMITS.max_velocity), list(LIMITS.max_acceleration), list(LIMITS.max_jerk)
    for k in range(2000):
        q0 = rng.uniform(lo, hi)
        q1 = rng.uniform(lo, hi)
        if k % 3 == 0:  # small moves, some joints standing still
            q1 = np.clip(q0 + rng.normal(0, 0.01, 6) * (rng.random(6) < 0.5), lo, hi)
        expected = _ruckig_duration(q0, q1, v, a, j)
        assert rest_to_rest_duration(q0, q1, LIMITS) == pytest.approx(expected, abs=TOL)
    assert rest_to_rest_duration(lo, lo, LIMITS) == 0.0
    with pytest.raises(LimitError, match="6 start and target"):
        rest_to_rest_duration(np.zeros(5), np.zeros(5), LIMITS)


def test_limits_below_a_squared_over_j_reach_velocity_without_full_acceleration() -> None:
    # v < a^2 / j: the acceleration limit is never reached, even when cruising.
    limits = JointLimits(max_velocity=(0.5,) * 6, max_acceleration=(5.0,) * 6, max_jerk=(10.0,) * 6)
    rng = np.random.default_rng(2)
    for _ in range(300):
        q0, q1 = rng.uniform(-1.5, 1.5, 6), rng.uniform(-1.5, 1.5, 6)
        expected = _ruckig_duration(q0, q1, [0.5] * 6, [5.0] * 6, [10.0] * 6)
        assert rest_to_rest_duration(q0, q1, limits) == pytest.approx(expected, abs=TOL)


def _by_ruckig(planner: PickPlacePlanner, start: np.ndarray, *targets: np.ndarray) -> float:
    """Chained ruckig segments from rest through ``targets`` (each unwrapped) to rest."""
    state, total = JointState.at_rest(start), 0.0
    for q in targets:
        q_t = unwrap_target(state.q, q, LIMITS, CFG.trajectory.wrap_joints)
        seg = plan_segment(state, q_t, LIMITS)
        state, total = seg.end, total + seg.duration
    return total


def test_bounds_equal_the_chained_ruckig_moves(planner: PickPlacePlanner) -> None:
    """`lower_bound`, `cycle_bound` at rest (closed form) and on a belt (ruckig) as planned."""
    rng = np.random.default_rng(3)
    ik = planner.ik
    for _ in range(20):
        pick = np.array([rng.uniform(-0.15, 0.15), rng.uniform(0.4, 0.6), 0.205])
        place = np.array([rng.uniform(-0.1, 0.1), rng.uniform(-0.6, -0.4), 0.207])
        q0 = ik.solve(place + [0.0, 0.0, 0.05], rng.uniform(-3, 3)).q
        q_pick = ik.solve(pick, rng.uniform(-3, 3), seed=q0).q
        q_place = ik.solve(place, rng.uniform(-3, 3), seed=q_pick).q
        q_end = ik.solve(place + [0.0, 0.0, 0.015], 0.0, seed=q_place).q
        expected = _by_ruckig(planner, q0, q_pick, q_place)
        assert planner.lower_bound(q0, q_pick, q_place) == pytest.approx(expected, abs=TOL)
        with_end = expected + _by_ruckig(planner, q_place, q_end)
        got = planner.lower_bound(q0, q_pick, q_place, end_q=q_end)
        assert got == pytest.approx(with_end, abs=TOL)
        dwells = CFG.cycle.pick_dwell + CFG.cycle.place_dwell
        got = planner.cycle_bound(q0, q_pick, np.zeros(6), CFG.cycle.pick_dwell, q_place)
        assert got == pytest.approx(expected + dwells, abs=TOL)
    # On a moving belt the pick arrives moving: ruckig plans both moves.
    belt_qd = planner.joint_velocity(q_pick, np.array([0.2, 0.0, 0.0]))
    a = plan_segment(
        JointState.at_rest(q0),
        unwrap_target(q0, q_pick, LIMITS, CFG.trajectory.wrap_joints),
        LIMITS,
        belt_qd,
    )
    held = hold_segment(a.end, CFG.cycle.pick_dwell)
    b = plan_segment(
        held.end, unwrap_target(held.end.q, q_place, LIMITS, CFG.trajectory.wrap_joints), LIMITS
    )
    got = planner.cycle_bound(q0, q_pick, belt_qd, CFG.cycle.pick_dwell, q_place)
    assert got == pytest.approx(a.duration + b.duration + dwells, abs=1e-12)
    b_now = plan_segment(
        a.end, unwrap_target(a.end.q, q_place, LIMITS, CFG.trajectory.wrap_joints), LIMITS
    )
    got = planner.lower_bound(q0, q_pick, q_place, pick_qd=belt_qd)
    assert got == pytest.approx(a.duration + b_now.duration, abs=1e-12)
