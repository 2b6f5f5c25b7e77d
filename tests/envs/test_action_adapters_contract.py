"""Contract tests of the action adapters (`envs.actions`) on a real one-tile cell.

The cell, its IK and its areas come from ``MosaicOneTile-v1`` (built once per module); each
test builds the adapter it checks itself, so the adapter's own construction runs inside the
test, and resets the cell to seed 0 first. Each test names the bug it guards against.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import envs  # noqa: F401 - registers the ids
from envs.actions import (
    ActionError,
    CartesianActions,
    DiscretePickPlaceActions,
    JointActions,
    PickPlaceActions,
    PickPlaceExecutor,
    transfer_poses,
)
from envs.mosaic_env import MosaicAssemblyEnv
from envs.task_spec import RANGE_SLACK, PickPlaceCodec
from planners.config import load_planner_config
from planners.robot import joint_ranges
from spatial.angles import wrap_angle

SEAL_PRESS = 0.0005
"""Pad target below the tile's top face when sealing on it [m]."""


@pytest.fixture(scope="module")
def one_tile() -> Iterator[MosaicAssemblyEnv]:
    """``MosaicOneTile-v1`` (one red 40 mm square, tile 0; cartesian actions), unwrapped."""
    env = gym.make("MosaicOneTile-v1")
    env.reset(seed=0)
    try:
        yield env.unwrapped
    finally:
        env.close()


@pytest.fixture
def u(one_tile: MosaicAssemblyEnv) -> MosaicAssemblyEnv:
    """The one-tile env reset with seed 0 (the arm at home, the tile on the belt)."""
    one_tile.reset(seed=0)
    return one_tile


def _cartesian(u: MosaicAssemblyEnv, **overrides: object) -> CartesianActions:
    cfg = dataclasses.replace(u.config, **overrides) if overrides else u.config
    return CartesianActions(u.cell, cfg, u.ik, u.pick_area, u.place_area)


def _discrete(u: MosaicAssemblyEnv, **overrides: object) -> DiscretePickPlaceActions:
    cfg = dataclasses.replace(u.config, **overrides) if overrides else u.config
    pcfg = load_planner_config(cfg.planner)
    ex = PickPlaceExecutor(u.cell, cfg, pcfg, u.ik, pick=u.pick_area, place=u.place_area)
    return DiscretePickPlaceActions(u.cell, cfg, ex)


def _pad_on_tile(u: MosaicAssemblyEnv) -> None:
    """Put the arm (kinematically) with the pad just pressed onto tile 0's top face."""
    cell = u.cell
    poses = cell.tile_poses()
    p, yaw = poses.pos[0], float(poses.yaw[0])
    target = np.array([p[0], p[1], u.task_spec.pick.tile_top_z - SEAL_PRESS])
    cell.set_qpos(u.ik.solve(target, yaw, seed=cell.qpos).q)


def _period(u: MosaicAssemblyEnv) -> float:
    dt = float(u.cell.model.opt.timestep)
    return max(1, round(u.config.control_dt / dt)) * dt


# ------------------------------------------------------------------------------ validate


def test_validate_names_a_wrong_shape_and_the_expected_one(u) -> None:
    """A (4,) action for Box(5): the message names both shapes, the adapter and the space.

    Guards against a wrong shape passed on (it would index past the action's end).
    """
    ad = _cartesian(u)
    msg = f"action has shape (4,); CartesianActions expects (5,) ({ad.space})"
    with pytest.raises(ActionError, match=f"^{re.escape(msg)}$"):
        ad.validate(np.zeros(4))
    with pytest.raises(ActionError, match=re.escape("action has shape (); CartesianActions")):
        ad.validate(0.0)


@pytest.mark.parametrize(
    ("action", "dtype"),
    [
        (np.array([True, False, True, False, True]), "bool"),
        (np.array(["a", "b", "c", "d", "e"]), "<U1"),
        (np.array([0, 0, 0, 0, 1j]), "complex128"),
    ],
)
def test_validate_refuses_non_real_values(u, action: np.ndarray, dtype: str) -> None:
    """Booleans, strings and complex numbers are refused, naming the dtype.

    Guards against a complex or non-numeric action reaching the IK.
    """
    msg = f"action must be real numeric values (not complex), got dtype {dtype}"
    with pytest.raises(ActionError, match=f"^{re.escape(msg)}$"):
        _cartesian(u).validate(action)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_validate_refuses_non_finite_values(u, bad: float) -> None:
    """NaN and +-inf are refused, the message listing the action.

    Guards against a NaN reaching the servo targets.
    """
    a = [0.0, bad, 0.0, 0.0, 0.0]
    msg = f"action must be finite (no NaN/inf), got {a}"
    with pytest.raises(ActionError, match=f"^{re.escape(msg)}$"):
        _cartesian(u).validate(np.array(a))


def test_validate_box_allows_the_slack_exactly_and_clips_to_float64(u) -> None:
    """Values exactly RANGE_SLACK past -1 or +1 are accepted and clipped; the result is float64.

    Guards against the slack's edge refused (``<=`` for ``<``, ``>=`` for ``>``) or an
    unclipped or float32 result.
    """
    ad = _cartesian(u)
    low = ad.space.low - RANGE_SLACK  # the edges as validate computes them
    high = ad.space.high + RANGE_SLACK
    a = np.array([low[0], high[1], 0.5, -0.25, 1.0])
    out = ad.validate(a)
    assert out.dtype == np.float64
    assert out.tolist() == [-1.0, 1.0, 0.5, -0.25, 1.0]
    assert ad.validate(np.array([1, -1, 0, 0, 1])).tolist() == [1.0, -1.0, 0.0, 0.0, 1.0]


@pytest.mark.parametrize("index", [0, 4])
@pytest.mark.parametrize("value", [-1.0 - 2 * RANGE_SLACK, 1.0 + 2 * RANGE_SLACK, 3.0, -7.0])
def test_validate_box_refuses_values_past_the_slack(u, index: int, value: float) -> None:
    """Any entry more than RANGE_SLACK past [-1, 1] is refused, naming the action and the space.

    Guards against one side of the range check lost.
    """
    ad = _cartesian(u)
    a = np.zeros(5)
    a[index] = value
    msg = f"action {a.tolist()} outside [-1, 1] ({ad.space})"
    with pytest.raises(ActionError, match=f"^{re.escape(msg)}$"):
        ad.validate(a)


def test_validate_multidiscrete_accepts_integers_below_nvec(u) -> None:
    """MultiDiscrete((1, 1, 4)): whole numbers in [0, nvec) pass as int64, floats included.

    Guards against the top index refused or the result left float.
    """
    ad = _discrete(u)
    assert isinstance(ad.space, spaces.MultiDiscrete)
    assert ad.space.nvec.tolist() == [1, 1, 4]
    for a in ([0, 0, 3], np.array([0.0, 0.0, 3.0]), np.array([0, 0, 0], np.int8)):
        out = ad.validate(a)
        assert out.dtype == np.int64
        assert out.tolist() == [0, 0, int(np.asarray(a)[2])]


@pytest.mark.parametrize(
    "a", [[0, 0, 4], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, 0, -1], [0, 0, 1.5]]
)
def test_validate_multidiscrete_refuses_outside_or_fractional_indices(u, a: list) -> None:
    """nvec itself, a negative index and a fraction are refused, naming the allowed ranges.

    Guards against ``>`` for ``>=`` (nvec let through), the negative check lost, or rounding
    a fraction silently.
    """
    ad = _discrete(u)
    msg = f"action {np.asarray(a).tolist()} must be integers in [0, [1, 1, 4])"
    with pytest.raises(ActionError, match=f"^{re.escape(msg)}$"):
        ad.validate(np.asarray(a))


# ------------------------------------------------------------------------------ noisy


def test_noisy_adds_the_configured_gaussian_noise_clipped_to_the_box(u) -> None:
    """Box action + N(0, action_noise) drawn from the given generator, clipped to [-1, 1].

    Guards against the noise dropped, a wrong clip bound or a result that is not the action.
    """
    ad = _cartesian(u, action_noise=0.75)
    a = np.array([1.0, -1.0, 0.0, 0.5, -0.5])
    out = ad.noisy(a, np.random.default_rng(3))
    want = np.clip(a + np.random.default_rng(3).normal(0.0, 0.75, 5), -1.0, 1.0)
    np.testing.assert_array_equal(out, want)
    assert out.min() == -1.0 and out.max() == 1.0  # the draw pushes entries past both ends
    assert not np.array_equal(out, a)


def test_noisy_without_noise_or_on_a_discrete_space_returns_the_action(u) -> None:
    """No noise configured, or a MultiDiscrete space: the action is returned unchanged and the
    generator not drawn from.

    Guards against ``or`` for ``and`` (a discrete action noised and clipped to [-1, 1]) and
    ``>= 0`` (a draw from the env's generator that changes every later random event).
    """
    a = np.array([0.25, -0.5, 0.0, 1.0, -1.0])
    rng = np.random.default_rng(5)
    assert _cartesian(u).noisy(a, rng) is a
    assert rng.random() == np.random.default_rng(5).random()
    d = np.array([0, 0, 3], np.int64)
    rng = np.random.default_rng(5)
    out = _discrete(u, action_noise=0.5).noisy(d, rng)
    assert out is d and out.tolist() == [0, 0, 3]
    assert rng.random() == np.random.default_rng(5).random()


# ------------------------------------------------------------------------------ joint


def test_joint_full_action_moves_each_target_by_its_speed_limit_times_the_period(u) -> None:
    """Box(7); action 1 moves joint i's target by max_joint_speed[i] x control period, with
    that velocity as feed-forward.

    Guards against a wrong scale or a feed-forward that is not the move over the period.
    """
    cell = u.cell
    ad = JointActions(cell, u.config)
    assert ad.space == spaces.Box(-1.0, 1.0, (7,), np.float32)
    period = _period(u)
    np.testing.assert_allclose(ad.max_step, cell.max_joint_speed * period, rtol=1e-12)
    q0 = cell.qpos
    action = np.array([0.5, -0.5, 0.25, 0.0, 0.0, 1.0, -1.0])
    res = ad.apply(action)
    assert res.failed is False and res.reason == "" and res.grasped == -1
    want = q0 + action[:6] * cell.max_joint_speed * period
    np.testing.assert_allclose(ad.target, want, atol=1e-12)
    np.testing.assert_allclose(cell.data.ctrl[cell.ids.pos_actuators], want, atol=1e-12)
    ff = cell.data.ctrl[cell.ids.vel_actuators]
    np.testing.assert_allclose(ff, action[:6] * cell.max_joint_speed, atol=1e-9)
    assert cell.vacuum_on is False  # action[6] <= 0: off


def test_joint_targets_stop_at_both_ends_of_the_joint_ranges(u) -> None:
    """A held +1 (then -1) on the wrist's last axis stops its target at the upper (lower) range.

    Guards against either clip bound lost (a target past the joint's range).
    """
    cell = u.cell
    ad = JointActions(cell, u.config)
    lo, hi = joint_ranges(cell.model)
    steps = math.ceil((hi[5] - lo[5]) / ad.max_step[5]) + 2
    for sign, end in ((1.0, hi[5]), (-1.0, lo[5])):
        action = np.zeros(7)
        action[5] = sign
        for _ in range(steps):
            ad.apply(action)
        assert ad.target[5] == end
    ad.reset()
    np.testing.assert_array_equal(ad.target, cell.qpos)


def test_joint_apply_reports_the_grasp_once_for_tile_zero(u) -> None:
    """Vacuum on with the pad on tile 0: that step reports grasped 0, the next ones -1.

    Guards against tile 0 not counted as a grasp (``>= 1``) or a held tile reported again.
    """
    _pad_on_tile(u)
    ad = JointActions(u.cell, u.config)
    on = np.array([0, 0, 0, 0, 0, 0, 1.0])
    assert ad.apply(on).grasped == 0
    assert u.cell.held_tile == 0 and u.cell.vacuum_on
    assert ad.apply(on).grasped == -1  # still held: no new grasp
    assert ad.apply(np.zeros(7)).grasped == -1  # released
    assert u.cell.held_tile == -1 and not u.cell.vacuum_on


# ------------------------------------------------------------------------------ cartesian


def test_cartesian_space_steps_and_box(u) -> None:
    """Box(5) in [-1, 1]; a full action moves (tool_speed, tool_speed, tool_speed, yaw_rate) x
    period; the box spans both areas, the home position and the configured heights.

    Guards against a wrong space bound, step scale (period divided, not multiplied) or box.
    """
    cfg, cell = u.config, u.cell
    ad = _cartesian(u)
    assert ad.space == spaces.Box(-1.0, 1.0, (5,), np.float32)
    period = _period(u)
    speed, rate = cfg.tool_speed * period, cfg.tool_yaw_rate * period
    np.testing.assert_allclose(ad.max_step, [speed, speed, speed, rate], rtol=1e-12)
    pick, place = u.pick_area, u.place_area
    home, _ = cell.tcp_pose()
    lo, hi = ad.box
    z0 = pick.surface_z
    np.testing.assert_array_equal(lo[:2], np.minimum(np.minimum(pick.lo, place.lo), home[:2]))
    np.testing.assert_array_equal(hi[:2], np.maximum(np.maximum(pick.hi, place.hi), home[:2]))
    assert lo[2] == min(z0 + cfg.tool_z_range[0], home[2])
    assert hi[2] == max(z0 + cfg.tool_z_range[1], home[2])
    lo[:] = 0.0  # box returns copies
    assert ad.box[0][2] != 0.0
    tall = _cartesian(u, tool_z_range=(0.125, 0.5))  # its top above the home height
    lo, hi = tall.box
    assert (lo[2], hi[2]) == (z0 + 0.125, z0 + 0.5)
    assert hi[2] > home[2]


def test_cartesian_full_action_moves_the_target_and_servos_over_the_period(u) -> None:
    """One step of (-1, 1, -1, 1): the tool target moves by one step each way, the joints'
    feed-forward velocity is their move over the control period.

    Guards against a wrong step or a feed-forward scaled by the period instead of divided.
    """
    cell = u.cell
    ad = _cartesian(u)
    start, q0 = ad.pose.copy(), ad.q.copy()
    res = ad.apply(np.array([-1.0, 1.0, -1.0, 1.0, 0.0]))
    assert res == type(res)(False, "", -1)
    np.testing.assert_allclose(ad.pose, start + [-1, 1, -1, 1] * ad.max_step, atol=1e-12)
    ff = cell.data.ctrl[cell.ids.vel_actuators]
    np.testing.assert_allclose(ff, (ad.q - q0) / _period(u), atol=1e-9)
    assert np.abs(ff).max() > 0.01  # a real move  # noqa: PLR2004
    assert not cell.vacuum_on


def test_cartesian_target_stays_in_its_box_and_its_yaw_wraps(u) -> None:
    """Pushing past the box's top and the home x keeps the target on the box's faces; a yaw
    turned past pi wraps into [-pi, pi).

    Guards against the box clip dropped or the yaw left unwrapped.
    """
    ad = _cartesian(u)
    lo, hi = ad.box
    ad.apply(np.array([1.0, 0.0, 1.0, 0.0, 0.0]))
    assert ad.pose[0] == hi[0] and ad.pose[2] == hi[2]
    yaw = float(ad.pose[3])
    n = math.ceil((math.pi - yaw) / ad.max_step[3]) + 1
    for _ in range(n):
        res = ad.apply(np.array([0.0, 0.0, -1.0, 1.0, 0.0]))
        assert not res.failed, res.reason
    assert -math.pi <= ad.pose[3] < math.pi
    assert ad.pose[3] == pytest.approx(float(wrap_angle(yaw + n * ad.max_step[3])), abs=1e-9)
    assert ad.pose[3] < 0  # wrapped round
    assert np.all(ad.pose[:3] >= lo) and np.all(ad.pose[:3] <= hi)


def test_cartesian_unreachable_target_keeps_the_last_one_and_says_why(u) -> None:
    """Moving to the box's far corner (+x, -y, top) fails in the IK: that step is a failed
    action with the IK's reason, the target and the joint targets stay where they were.

    Guards against the reason lost or the unreachable pose kept as the target.
    """
    ad = _cartesian(u)
    res = None
    for _ in range(60):
        before, q = ad.pose.copy(), ad.q.copy()
        res = ad.apply(np.array([0.0, -1.0, 0.0, 0.0, 0.0]))
        if res.failed:
            break
    assert res is not None and res.failed
    assert res.reason.startswith("IK: tool-down pose at "), res.reason
    assert "out of reach" in res.reason
    assert res.grasped == -1
    np.testing.assert_array_equal(ad.pose, before)
    np.testing.assert_array_equal(ad.q, q)


def test_cartesian_apply_reports_the_grasp_once_for_tile_zero(u) -> None:
    """Vacuum on with the pad on tile 0: grasped 0 on that step, -1 while it stays held.

    Guards against the grasp never reported, tile 0 not counted, a held tile reported again
    (``or`` for ``and``) or +1 for "nothing grasped".
    """
    ad = _cartesian(u)
    assert ad.apply(np.zeros(5)).grasped == -1  # nothing under the pad
    on = np.array([0.0, 0.0, 0.0, 0.0, 1.0])
    _pad_on_tile(u)
    ad.reset()
    first = ad.apply(on)
    assert (first.failed, first.reason, first.grasped) == (False, "", 0)
    assert u.cell.held_tile == 0
    assert ad.apply(on).grasped == -1
    assert ad.apply(np.array([0.0, 0.0, 1.0, 0.0, 1.0])).grasped == -1  # lifted, still held
    assert u.cell.held_tile == 0


def test_cartesian_reset_takes_the_current_tool_pose_and_joints(u) -> None:
    """After the arm moved, reset makes the tool target the tool's pose (x, y, z, yaw) now.

    Guards against a stale target (the next action would jump back to it).
    """
    ad = _cartesian(u)
    _pad_on_tile(u)
    ad.reset()
    pos, rot = u.cell.tcp_pose()
    np.testing.assert_array_equal(ad.pose[:3], pos)
    assert ad.pose[3] == pytest.approx(math.atan2(rot[1, 0], rot[0, 0]), abs=1e-12)
    np.testing.assert_array_equal(ad.q, u.cell.qpos)


@pytest.mark.parametrize(("control_dt", "substeps"), [(0.04, 20), (0.0413, 21), (0.0005, 1)])
def test_an_adapter_steps_a_whole_number_of_physics_steps(
    u, control_dt: float, substeps: int
) -> None:
    """The control period is control_dt rounded to whole physics steps, at least one; a joint
    action's full step is the speed limit times that period.

    Guards against the rounding or the floor of one step lost, or the timestep misread.
    """
    ad = JointActions(u.cell, dataclasses.replace(u.config, control_dt=control_dt))
    assert ad.dt == float(u.cell.model.opt.timestep) == 0.002  # noqa: PLR2004
    assert ad.substeps == substeps
    np.testing.assert_allclose(ad.max_step, u.cell.max_joint_speed * substeps * 0.002)
    t0 = u.cell.time
    ad.apply(np.zeros(7))
    assert u.cell.time == pytest.approx(t0 + substeps * 0.002, abs=1e-12)


# ------------------------------------------------------------------------------ pick and place

GRASPED = 4
"""The Decision6 tile whose grasp point is off its origin (about 4.2 mm along -x)."""


def _lay(cell, yaw: float) -> None:
    """Tiles of the Decision6 cell on a grid on the belt, tile GRASPED turned by ``yaw``."""
    xy = np.array([[-0.1, 0.05], [0.1, -0.05], [0.1, 0.05], [0.0, 0.0], [-0.1, -0.05], [0, 0.05]])
    yaws = np.zeros(6)
    yaws[GRASPED] = yaw
    cell.place_tiles(np.arange(6), np.column_stack([xy, yaws]))


def test_transfer_poses_put_the_pad_on_the_grasp_point_at_both_ends(decision6_env) -> None:
    """Pick: the tile's centre plus its grasp point turned by the tile's yaw; place: the slot's
    centre plus the grasp point turned by the slot's yaw plus the extra turn; the rotation is
    the wrapped difference of the two yaws.

    Guards against the grasp offset dropped, turned by the wrong yaw or the extra turn lost.
    """
    decision6_env.reset(seed=0)
    cell = decision6_env.unwrapped.cell
    _lay(cell, 0.7)
    g = cell.tiles[GRASPED].grasp
    assert np.linalg.norm(g) > 0.004  # noqa: PLR2004 - a real offset
    poses = cell.tile_poses()
    yaw = float(poses.yaw[GRASPED])
    assert yaw == pytest.approx(0.7, abs=1e-12)

    def turned(a: float) -> np.ndarray:
        return np.array(
            [g[0] * math.cos(a) - g[1] * math.sin(a), g[0] * math.sin(a) + g[1] * math.cos(a)]
        )

    sx, sy, syaw = cell.slot_poses_world()[2]
    cmd = transfer_poses(cell, GRASPED, 2, 2.5)
    np.testing.assert_allclose(cmd.pick_xy, poses.pos[GRASPED, :2] + turned(yaw), atol=1e-12)
    np.testing.assert_allclose(cmd.place_xy, np.array([sx, sy]) + turned(syaw + 2.5), atol=1e-12)
    assert cmd.pick_yaw == yaw
    assert cmd.rotation == pytest.approx(float(wrap_angle(syaw + 2.5 - yaw)), abs=1e-12)
    plain = transfer_poses(cell, 0, 1)  # no grasp offset, no extra turn
    np.testing.assert_allclose(plain.pick_xy, poses.pos[0, :2], atol=1e-15)
    np.testing.assert_allclose(plain.place_xy, cell.slot_poses_world()[1, :2], atol=1e-15)
    assert plain.rotation == pytest.approx(float(wrap_angle(cell.slot_poses_world()[1, 2])))
    assert all(type(v) is float for v in (*cmd.pick_xy, *cmd.place_xy))


def test_discrete_actions_move_the_chosen_tile_into_the_chosen_slot(decision6_env) -> None:
    """MultiDiscrete((tiles, slots, bins)); rotation r turns r steps from the slot's yaw; the
    cycle puts the tile in the slot and reports its grasp; a tile no longer on the input belt
    is a failed action that costs the executor's failure time.

    Guards against the space's sizes, the rotation's turn, the tile and slot swapped, or the
    off-belt or slot-range check lost (a slot past the cell's is a failed action too).
    """
    env = decision6_env
    env.reset(seed=0)
    u = env.unwrapped
    cell = u.cell
    ad = _discrete(u, rotation_bins=8)
    assert ad.space.nvec.tolist() == [6, 6, 8]
    assert ad.codec.nvec == (6, 6, 8)
    want = transfer_poses(cell, GRASPED, 3, 3 * math.pi / 4)
    got = ad.poses(GRASPED, 3, 3)
    assert got.pick_xy == want.pick_xy and got.place_xy == want.place_xy
    assert got.rotation == pytest.approx(want.rotation, abs=1e-12)
    res = ad.apply(np.array([GRASPED, GRASPED, 0]))
    assert (res.failed, res.reason, res.grasped) == (False, "", GRASPED)
    pose = cell.tile_poses()
    np.testing.assert_allclose(
        pose.pos[GRASPED, :2], cell.slot_poses_world()[GRASPED, :2], atol=1e-3
    )
    assert not cell.input_half()[GRASPED]
    t0 = cell.time
    res = ad.apply(np.array([GRASPED, 0, 0]))
    assert (res.failed, res.reason) == (True, f"tile {GRASPED} is not on the input belt")
    assert cell.time == pytest.approx(t0 + ad.executor.fail_steps * ad.dt, abs=1e-12)
    t0 = cell.time
    res = ad.apply(np.array([0, 6, 0]))  # no slot 6: a failed action, not a crash
    assert res.failed and res.grasped == -1
    assert cell.input_half()[0]  # tile 0 stays on the belt
    assert cell.time == pytest.approx(t0 + ad.executor.fail_steps * ad.dt, abs=1e-12)


@pytest.mark.parametrize("pick_yaw", [True, False])
def test_pick_place_actions_decode_with_their_codec_and_run_the_cycle(
    decision6_env, pick_yaw: bool
) -> None:
    """Box(codec.size) in [-1, 1]; an action is decoded by the codec and run as one cycle.

    Guards against a space of the wrong layout or an action run undecoded.
    """
    env = decision6_env
    env.reset(seed=0)
    u = env.unwrapped
    cell = u.cell
    codec = PickPlaceCodec(u.pick_area, u.place_area, pick_yaw)
    pcfg = load_planner_config(u.config.planner)
    ex = PickPlaceExecutor(cell, u.config, pcfg, u.ik, pick=u.pick_area, place=u.place_area)
    ad = PickPlaceActions(cell, u.config, ex, codec)
    assert ad.space == spaces.Box(-1.0, 1.0, (6 if pick_yaw else 5,), np.float32)
    ad.reset()
    res = ad.apply(codec.encode(transfer_poses(cell, GRASPED, 1)))
    assert (res.failed, res.grasped) == (False, GRASPED)
    np.testing.assert_allclose(
        cell.tile_poses().pos[GRASPED, :2], cell.slot_poses_world()[1, :2], atol=1e-3
    )
