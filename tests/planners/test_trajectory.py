"""Ruckig trajectories: limits respected when sampled, unwrapping, blending, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from configs import ConfigError
from planners.config import JointLimits, PlannerConfig, load_planner_config
from planners.errors import InvalidTargetError, LimitError, PlannerError, TrajectoryError
from planners.joints import JointState, unwrap_target
from planners.limit_checks import limit_report, validate
from planners.trajectory import (
    Piecewise,
    chain,
    hold_segment,
    join,
    plan_segment,
    superpose,
    window,
)

LIMITS = load_planner_config().limits
DT = 0.002


def _random_config(rng: np.random.Generator, limits: JointLimits) -> np.ndarray:
    lo, hi = np.asarray(limits.lower), np.asarray(limits.upper)
    return rng.uniform(lo * 0.9, hi * 0.9)


def test_bundled_config_matches_defaults() -> None:
    cfg = load_planner_config()
    default = PlannerConfig()
    np.testing.assert_allclose(cfg.limits.max_velocity, default.limits.max_velocity, rtol=1e-6)
    np.testing.assert_allclose(
        cfg.limits.max_acceleration, default.limits.max_acceleration, rtol=1e-6
    )
    np.testing.assert_allclose(cfg.limits.lower, default.limits.lower, rtol=1e-6)
    assert cfg.cycle == default.cycle
    assert cfg.trajectory == default.trajectory


def test_axis_speeds_are_the_datasheet_values() -> None:
    np.testing.assert_allclose(
        np.degrees(LIMITS.max_velocity), [200, 200, 260, 360, 360, 450], rtol=1e-6
    )


@pytest.mark.parametrize("seed", range(6))
def test_sampled_chain_respects_every_limit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    start = JointState.at_rest(_random_config(rng, LIMITS))
    targets = []
    for k in range(3):
        q = _random_config(rng, LIMITS)
        qd = None if k == 2 else rng.uniform(-0.3, 0.3, 6) * np.asarray(LIMITS.max_velocity)
        targets.append((q, qd, f"s{k}"))
    pw = chain(start, targets, LIMITS)
    traj = pw.sample(DT)
    rep = limit_report(traj, LIMITS)
    tol = 1.0 + 1e-3
    assert np.all(rep.velocity <= tol)
    assert np.all(rep.acceleration <= tol)
    assert np.all(rep.jerk <= tol)
    assert rep.in_range
    validate(traj, LIMITS)
    # Time-optimal: the slowest joint saturates at least one limit.
    assert max(rep.velocity.max(), rep.acceleration.max(), rep.jerk.max()) > 0.99
    # Ends where asked, at rest; continuity of the samples.
    np.testing.assert_allclose(traj.q[-1], pw.end.q, atol=1e-9)
    np.testing.assert_allclose(traj.qd[-1], 0.0, atol=1e-9)
    assert np.max(np.abs(np.diff(traj.q, axis=0))) <= max(LIMITS.max_velocity) * DT * tol


def test_at_interpolates_between_samples() -> None:
    start = JointState.at_rest(np.zeros(6))
    pw = chain(start, [(np.full(6, 0.5), None, "move")], LIMITS)
    traj = pw.sample(DT)
    t = 0.1234
    q, qd, _ = traj.at(t)
    q_exact, qd_exact, _ = pw.segments[0].state(t)
    np.testing.assert_allclose(q, q_exact, atol=1e-7)
    np.testing.assert_allclose(qd, qd_exact, atol=1e-2)
    np.testing.assert_allclose(traj.at(1e3)[0], traj.q[-1])


def test_blending_through_a_via_point_is_faster_than_stopping() -> None:
    a = np.array([0.0, 0.0, 0.0, 0.0, 1.5, 0.0])
    b = np.array([1.0, 0.1, -0.1, 0.0, 1.5, 0.0])
    c = np.array([2.0, 0.0, 0.0, 0.0, 1.5, 0.0])
    start = JointState.at_rest(a)
    stop = chain(start, [(b, None, "ab"), (c, None, "bc")], LIMITS)
    via_qd = np.array([2.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    blend = chain(start, [(b, via_qd, "ab"), (c, None, "bc")], LIMITS)
    assert blend.duration < stop.duration - 0.1
    traj = blend.sample(DT)
    validate(traj, LIMITS)
    # Through the via point itself (interpolated at its time, not at the nearest sample).
    np.testing.assert_allclose(traj.at(blend.end_time("ab"))[0], b, atol=1e-5)


def test_target_velocity_is_reached() -> None:
    qd = np.array([0.2, -0.1, 0.05, 0.0, 0.0, 0.3])
    seg = plan_segment(JointState.at_rest(np.zeros(6)), np.full(6, 0.3), LIMITS, qd)
    _, v, a = seg.state(seg.duration)
    np.testing.assert_allclose(v, qd, atol=1e-9)
    np.testing.assert_allclose(a, 0.0, atol=1e-9)
    cruise = hold_segment(seg.end, 0.05)
    np.testing.assert_allclose(cruise.end.q, seg.end.q + qd * 0.05)


def test_joined_and_superposed_segments_sample_as_their_pieces() -> None:
    # A pulse at full jerk then a time-optimal stop (the planner's counter-swing), joined; a
    # window of it superposed on a belt-like constant velocity. `states` (arrays) equals
    # `state` (one time) everywhere, clamped outside the segment.
    jerk = np.zeros(6)
    jerk[0] = -LIMITS.max_jerk[0]
    p = 0.01
    pulse = plan_segment(
        JointState.at_rest(np.zeros(6)),
        jerk * p**3 / 6,
        LIMITS,
        jerk * p**2 / 2,
        target_qdd=jerk * p,
        label="swing",
    )
    assert pulse.duration == pytest.approx(p, abs=1e-6)  # the pulse is time-optimal
    stop = plan_segment(pulse.end, np.full(6, 0.4), LIMITS, label="stop")
    joined = join([pulse, stop], "bridge")
    assert joined.duration == pytest.approx(pulse.duration + stop.duration)
    np.testing.assert_allclose(joined.state(0.5 * p)[0], pulse.state(0.5 * p)[0])
    np.testing.assert_allclose(joined.state(p + 0.1)[0], stop.state(0.1)[0])
    drift = hold_segment(JointState(np.zeros(6), np.full(6, 0.05)), 0.3)
    mixed = superpose([(window(joined, 0.005, 0.3), 0.0), (drift, 0.0)], 0.2, np.zeros(6), "m")
    taus = np.linspace(-0.01, 0.35, 97)
    for seg in (pulse, stop, joined, drift, mixed):
        q, qd, qdd = seg.states(taus)
        for k, t in enumerate(taus):
            one = seg.state(float(t))
            np.testing.assert_allclose(q[k], one[0], atol=1e-12)
            np.testing.assert_allclose(qd[k], one[1], atol=1e-12)
            np.testing.assert_allclose(qdd[k], one[2], atol=1e-12)
    sampled = Piecewise((joined,)).sample(DT)
    validate(sampled, LIMITS)
    assert sampled.q[:, 0].min() < 0.0  # it turned away first


def test_join_rejects_pieces_that_do_not_meet() -> None:
    a = plan_segment(JointState.at_rest(np.zeros(6)), np.full(6, 0.1), LIMITS, label="a")
    b = plan_segment(JointState.at_rest(np.full(6, 0.2)), np.full(6, 0.3), LIMITS, label="b")
    with pytest.raises(TrajectoryError, match="'b' starts"):
        join([a, b], "ab")
    with pytest.raises(TrajectoryError, match="at least one"):
        join([], "none")


def test_unwrap_picks_nearest_equivalent_angle_inside_range() -> None:
    q_from = np.array([0, 0, 0, 3.0, 0, 6.5])
    q_to = np.array([0, 0, 0, -3.0, 0, 0.1])
    out = unwrap_target(q_from, q_to, LIMITS)
    assert out[3] == pytest.approx(-3.0 + 2 * math.pi)
    assert out[5] == pytest.approx(0.1 + 2 * math.pi)
    # Nearest equivalent would be outside the range: the nearest one inside is used.
    q_from = np.array([0, 0, 0, 0, 0, 6.9])
    q_to = np.array([0, 0, 0, 0, 0, 0.2 - 2 * math.pi])
    out = unwrap_target(q_from, q_to, LIMITS)
    assert out[5] == pytest.approx(0.2 + 2 * math.pi)
    assert out[5] <= LIMITS.upper[5]


def test_unwrapping_shortens_the_wrist_move() -> None:
    start = JointState.at_rest(np.array([0, 0, 0, 3.0, 1.0, 3.0]))
    target = np.array([0, 0, 0, -3.0, 1.0, -3.0])
    wrapped = chain(start, [(target, None, "m")], LIMITS)
    raw = chain(start, [(target, None, "m")], LIMITS, wrap_joints=())
    assert wrapped.duration < raw.duration


@pytest.mark.parametrize(
    "field, value",
    [
        ("max_velocity", (0.0, 1, 1, 1, 1, 1)),
        ("max_acceleration", (1, -1.0, 1, 1, 1, 1)),
        ("max_jerk", (1, 1, float("nan"), 1, 1, 1)),
        ("max_velocity", (1, 1, 1)),
    ],
)
def test_bad_limits_raise_typed_errors(field: str, value: tuple[float, ...]) -> None:
    with pytest.raises(LimitError, match=field):
        JointLimits(**{field: value})


def test_bad_scale_and_config_keys() -> None:
    with pytest.raises(LimitError, match="speed"):
        LIMITS.scaled(speed=0.0)
    with pytest.raises(ConfigError, match="unknown"):
        load_planner_config(cycle={"approach_hieght": 0.1})
    with pytest.raises(LimitError, match="pick_dwell"):
        load_planner_config(cycle={"pick_dwell": -0.1})


def test_bad_targets_raise_typed_errors() -> None:
    start = JointState.at_rest(np.zeros(6))
    with pytest.raises(InvalidTargetError, match="finite"):
        plan_segment(start, [0, 0, float("nan"), 0, 0, 0], LIMITS)
    with pytest.raises(InvalidTargetError, match="shape"):
        plan_segment(start, [0, 0, 0], LIMITS)
    with pytest.raises(LimitError, match="joint 2"):
        plan_segment(start, [0, 2.5, 0, 0, 0, 0], LIMITS)
    with pytest.raises(LimitError, match="velocity of joint 1"):
        plan_segment(start, np.zeros(6), LIMITS, [10.0, 0, 0, 0, 0, 0])
    with pytest.raises(PlannerError):
        hold_segment(start, -1.0)
    assert issubclass(PlannerError, ValueError)
