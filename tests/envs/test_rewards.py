"""Reward contract of every ``reward_mode`` (`envs.task.MosaicTask.rewards`, `envs.rewards`).

Written from the documented terms (``configs/env.yaml``, the `EnvConfig` fields, the staged
reward's module docstring): each term is its weight times the change since the previous call,
penalties are negative, dense and staged terms are 0 in the other modes. The evaluations are
the task's own with counts changed (`dataclasses.replace`), so each term is checked alone.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import envs
from envs.actions import transfer_poses
from envs.errors import CellError
from envs.rewards import STAGES, StagedReward, StagedRewardConfig, load_staged_config
from envs.task import REWARD_TERMS
from spatial.rotations import quat_from_yaw


def _make(mode: str) -> gym.Env:
    return gym.make(
        envs.ENV_ID,
        action_mode="pick_place",
        execution="kinematic",
        obs_mode="state",
        max_slots=4 if mode == "sparse" else 0,  # dense: the full design, two slots of a class
        reward_mode=mode,
        tile_variants=1,
        disable_env_checker=True,
    )


@pytest.fixture(scope="module")
def sparse() -> Iterator[gym.Env]:
    e = _make("sparse")
    yield e
    e.close()


@pytest.fixture(scope="module")
def dense() -> Iterator[gym.Env]:
    e = _make("dense")
    yield e
    e.close()


@pytest.fixture(scope="module")
def one_tile() -> Iterator[gym.Env]:
    e = gym.make("MosaicOneTile-v0", disable_env_checker=True)
    yield e
    e.close()


def _terms(u: Any, failed: bool = False, **change: Any) -> dict[str, float]:
    """Reward terms of a step whose evaluation differs from the last one by ``change``."""
    u.task.reset()
    e = dataclasses.replace(u.task.last_evaluation, **change)
    return u.task.rewards(e, failed)


@pytest.mark.parametrize(
    ("change", "failed", "expected"),
    [
        ({"correct": 2}, False, {"correct": 2.0}),
        ({"correct": 1, "success": True}, False, {"correct": 1.0, "success": 5.0}),
        ({"misplaced": 3}, False, {"misplaced": -1.5}),
        ({"dropped": 2}, False, {"dropped": -1.0}),
        ({"lost": 1}, False, {"lost": -0.5}),
        ({"distractors_placed": 2}, False, {"distractor": -1.0}),
        ({}, True, {"failed_action": -0.1}),
    ],
)
def test_sparse_terms_are_weights_times_changes(
    sparse: gym.Env, change: dict[str, Any], failed: bool, expected: dict[str, float]
) -> None:
    """Guards against a term with the wrong weight (``configs/env.yaml``: correct 1, success 5,
    penalties 0.5, failed action 0.1), sign, or read from the wrong count."""
    sparse.reset(seed=0)
    terms = _terms(sparse.unwrapped, failed, **change)
    assert set(terms) == set(REWARD_TERMS)
    for name in REWARD_TERMS:
        assert terms[name] == pytest.approx(expected.get(name, 0.0)), name


def test_sparse_terms_pay_only_the_change_since_the_last_call(sparse: gym.Env) -> None:
    """Guards against terms paid on the totals (or the sum of the last and the new count)
    instead of the change, a success paid at every step, or a misplaced tile set right being
    paid back (the penalty counts increases only)."""
    sparse.reset(seed=0)
    u = sparse.unwrapped
    base = u.task.last_evaluation
    first = dataclasses.replace(
        base, correct=3, misplaced=2, success=True, distractors_placed=1, dropped=1, lost=1
    )
    assert u.task.rewards(first, False)["success"] == 5.0
    again = u.task.rewards(first, False)
    assert all(v == 0.0 for v in again.values())  # dropped and lost too: counted once
    better = dataclasses.replace(first, misplaced=0, distractors_placed=0, correct=4)
    terms = u.task.rewards(better, False)
    assert terms["misplaced"] == 0.0 and terms["distractor"] == 0.0 and terms["correct"] == 1.0
    assert terms["success"] == 0.0
    worse = dataclasses.replace(better, correct=2)
    assert u.task.rewards(worse, False)["correct"] == -2.0  # a filled slot undone costs it back


def test_dense_reach_is_minus_the_tool_distance_to_the_nearest_wanted_tile(dense: gym.Env) -> None:
    """Guards against the reach term using the farthest tile, an unwanted tile or the wrong
    weight (``dense_reach`` 0.5 per m); grasp and carry stay 0 while nothing is held."""
    dense.reset(seed=0)
    u = dense.unwrapped
    terms = _terms(u)
    tool = u.cell.tcp_pose()[0]
    wanted = np.flatnonzero(u.task.wanted_tiles(u.task.last_evaluation))
    assert len(wanted) == 16
    d = np.linalg.norm(u.cell.tile_poses().pos[wanted] - tool, axis=1).min()
    assert terms["reach"] == pytest.approx(-0.5 * d)
    assert terms["grasp"] == 0.0 and terms["carry"] == 0.0
    assert set(terms) == set(REWARD_TERMS)
    # a tile whose class's slots are all filled is not wanted any more
    filled = dataclasses.replace(u.task.last_evaluation, slot_filled=(True,) * 16, correct=16)
    assert not u.task.wanted_tiles(filled).any()


def _hold(u: Any, tile: int, slot: int) -> None:
    """Put the pad on ``tile`` (kinematically) and seal."""
    cmd = transfer_poses(u.cell, tile, slot)
    q = u.ik.solve(np.array([*cmd.pick_xy, u.pick_area.tile_top_z]), cmd.pick_yaw).q
    u.cell.set_qpos(q)
    u.cell.vacuum(True)
    assert u.cell.held_tile == tile


def test_dense_grasp_and_carry_while_holding_a_wanted_tile(dense: gym.Env) -> None:
    """Guards against carry measured to a filled slot or a slot of another class, or grasp paid
    for a tile no open slot wants (``dense_grasp`` 0.2, ``dense_carry`` 0.5 per m)."""
    dense.reset(seed=0)
    u = dense.unwrapped
    task = u.task
    tile = 0
    _hold(u, tile, int(np.flatnonzero(task.slot_class == task.tile_class[tile])[0]))
    terms = _terms(u)
    free = np.flatnonzero(task.slot_class == task.tile_class[tile])
    assert len(free) == 2  # the nearest of two slots: a minimum, not a norm of both
    xy = u.cell.tile_poses().pos[tile, :2]
    d = np.linalg.norm(task.slot_xyyaw[free, :2] - xy, axis=1).min()
    assert terms["grasp"] == pytest.approx(0.2)
    assert terms["carry"] == pytest.approx(-0.5 * d)
    assert terms["reach"] == 0.0
    assert set(terms) == set(REWARD_TERMS)
    # its class's slots all filled: holding it earns nothing
    filled = tuple(bool(task.slot_class[j] == task.tile_class[tile]) for j in range(16))
    u.task.reset()
    e = dataclasses.replace(u.task.last_evaluation, slot_filled=filled)
    t2 = u.task.rewards(e, False)
    assert (t2["grasp"], t2["carry"], t2["reach"]) == (0.0, 0.0, 0.0)
    assert set(t2) == set(REWARD_TERMS)


def test_sparse_and_dense_modes_leave_the_staged_terms_zero(dense: gym.Env) -> None:
    """Guards against the staged terms leaking into the other modes."""
    dense.reset(seed=0)
    terms = _terms(dense.unwrapped, correct=1)
    assert all(terms[f"stage_{s}"] == 0.0 for s in STAGES)


def test_staged_potentials_follow_the_documented_formulas(one_tile: gym.Env) -> None:
    """Guards against a stage's potential off its documented formula: reach 1 - tanh(d / 0.3 m),
    lift the height over 0.03 m clipped and latched, transport lift x (1 - tanh(d / 0.3 m)),
    align (1 - d / 0.02 m) x (1 - yaw error / half the symmetry period), release the fraction
    filled, every other stage f + (1 - f) x progress."""
    one_tile.reset(seed=1)
    u = one_tile.unwrapped
    st = u.task.staged
    cfg: StagedRewardConfig = st.cfg
    assert (cfg.reach_scale, cfg.lift_height, cfg.transport_scale, cfg.align_distance) == (
        0.3,
        0.03,
        0.3,
        0.02,
    )
    e = u.evaluate()
    pot = st.potentials(e)
    cell = u.cell
    tool = cell.tcp_pose()[0]
    pose = cell.tile_poses()
    g = np.array(cell.tiles[0].grasp[:2])
    c, s = math.cos(pose.yaw[0]), math.sin(pose.yaw[0])
    grasp = pose.pos[0].copy()
    grasp[:2] += [c * g[0] - s * g[1], s * g[0] + c * g[1]]
    assert pot["reach"] == pytest.approx(1 - math.tanh(np.linalg.norm(grasp - tool) / 0.3))
    assert pot["seal"] == pot["lift"] == pot["transport"] == pot["align"] == 0.0
    assert pot["release"] == 0.0
    # held and lifted half the lift height, then a full lift height: latched at 1
    _hold(u, 0, 0)
    rest = cell.tile_poses().pos[0, 2]
    q = cell.ids.tile_qpos_index[0]
    slot = u.task.slot_xyyaw[0]
    sym = int(u.task.symmetry[0])
    for h, lift in ((0.015, 0.5), (0.03, 1.0), (0.01, 1.0)):
        cell.data.qpos[q[2]] = rest + h
        mujoco.mj_forward(cell.model, cell.data)
        pot = st.potentials(u.evaluate())
        assert pot["seal"] == 1.0 and pot["reach"] == 1.0
        assert pot["lift"] == pytest.approx(lift, abs=1e-6), h
        d = np.linalg.norm(slot[:2] - cell.tile_poses().pos[0, :2])
        assert pot["transport"] == pytest.approx(lift * (1 - math.tanh(d / 0.3)), abs=1e-6)
        assert d > 0.02 and pot["align"] == 0.0  # farther than align_distance from the slot
    # over the slot, 10 mm off and turned by a quarter of the half period
    turn = (math.pi / sym) / 4 if sym > 0 else 0.0
    cell.data.qpos[q[:2]] = slot[:2] + [0.01, 0.0]
    cell.data.qpos[q[3:]] = quat_from_yaw(slot[2] + turn)
    mujoco.mj_forward(cell.model, cell.data)
    pot = st.potentials(u.evaluate())
    expect = 0.5 * (0.75 if sym > 0 else 1.0)
    assert pot["align"] == pytest.approx(expect, abs=1e-6)
    cell.data.qpos[q[:2]] = slot[:2]  # right on the slot: only the turn is left
    mujoco.mj_forward(cell.model, cell.data)
    assert st.potentials(u.evaluate())["align"] == pytest.approx(0.75 if sym > 0 else 1.0)
    # the slot filled: release 1, every other stage 1 (f + (1 - f) x progress)
    done = dataclasses.replace(u.evaluate(), correct=1, slot_filled=(True,))
    assert all(v == pytest.approx(1.0) for v in st.potentials(done).values())


def test_staged_terms_are_weights_times_potential_changes(one_tile: gym.Env) -> None:
    """Guards against a stage's weight swapped (``configs/rewards.yaml``: transport 2, release 4,
    the others 1) or a term paid on the potential instead of its change."""
    one_tile.reset(seed=1)
    u = one_tile.unwrapped
    st = u.task.staged
    e = u.evaluate()
    st.reset(e)
    assert all(v == 0.0 for v in st.terms(e).values())
    done = dataclasses.replace(e, correct=1, slot_filled=(True,))
    before = st.potentials(e)
    terms = st.terms(done)
    weights = {"reach": 1, "seal": 1, "lift": 1, "transport": 2, "align": 1, "release": 4}
    for s in STAGES:
        assert terms[f"stage_{s}"] == pytest.approx(weights[s] * (1.0 - before[s])), s
    assert all(v == 0.0 for v in st.terms(done).values())  # no change, no reward


@pytest.mark.parametrize(("order", "expected"), [(1, 0.75), (2, 0.5), (0, 1.0)])
def test_staged_align_divides_the_yaw_error_by_half_the_symmetry_period(
    dense: gym.Env, order: int, expected: float
) -> None:
    """Guards against the symmetry order's special cases moved (0: any yaw aligns; 1: the half
    period is pi): a tile held on its slot, turned by pi / 4, aligns 1 - (pi / 4) / (pi / order)."""
    dense.reset(seed=0)
    u = dense.unwrapped
    task = u.task
    tile = int(np.flatnonzero(task.symmetry == order)[0])
    slot = int(np.flatnonzero(task.slot_class == task.tile_class[tile])[0])
    _hold(u, tile, slot)
    staged = StagedReward(task, load_staged_config())
    cell = u.cell
    q = cell.ids.tile_qpos_index[tile]
    x, y, yaw = task.slot_xyyaw[slot]
    cell.data.qpos[q[:2]] = [x, y]
    cell.data.qpos[q[3:]] = quat_from_yaw(yaw + math.pi / 4)
    mujoco.mj_forward(cell.model, cell.data)
    e = dataclasses.replace(u.evaluate(), slot_filled=(False,) * 16, correct=0)
    assert staged.potentials(e)["align"] == pytest.approx(expected, abs=1e-6)


def test_staged_release_is_the_fraction_of_slots_filled(dense: gym.Env) -> None:
    """Guards against the filled fraction computed against the wrong count (times instead of
    over the slots): 4 of 16 slots filled is a release potential of 0.25, and every other stage
    starts from it."""
    dense.reset(seed=0)
    u = dense.unwrapped
    staged = StagedReward(u.task, load_staged_config())
    e = u.evaluate()
    filled = dataclasses.replace(e, correct=4)  # the count only: the same wanted tiles
    pot = staged.potentials(filled)
    assert pot["release"] == pytest.approx(0.25)
    assert all(0.25 <= v <= 1.0 for v in pot.values())
    assert pot["seal"] == pytest.approx(0.25)  # nothing held: no progress past the filled part
    reach = staged.potentials(e)["reach"]  # nothing filled: the reach progress alone
    assert 0.0 < reach < 1.0
    assert pot["reach"] == pytest.approx(0.25 + 0.75 * reach)


def test_staged_config_loads_overrides_and_refuses_non_positive_scales(tmp_path) -> None:
    """Guards against the overrides or the file name dropped by `load_staged_config`, a zero
    scale accepted (every scale must be > 0 m), and the refusal not saying it is the staged
    reward's setting."""
    assert load_staged_config(reach_scale=0.5).reach_scale == 0.5
    path = tmp_path / "rewards.yaml"
    path.write_text("transport: 3.0\n", encoding="utf-8")
    assert load_staged_config(str(path)).transport == 3.0
    with pytest.raises(CellError, match=r"^staged reward: reach_scale must be > 0, got 0.0$"):
        StagedRewardConfig(reach_scale=0.0)


def test_staged_progress_stops_when_the_held_tiles_slots_are_filled(dense: gym.Env) -> None:
    """Guards against the filled slots ignored by the staged progress: holding a tile whose
    class's slots are all filled is no progress (only the filled fraction counts)."""
    dense.reset(seed=0)
    u = dense.unwrapped
    task = u.task
    tile = 0
    mine = np.flatnonzero(task.slot_class == task.tile_class[tile])
    _hold(u, tile, int(mine[0]))
    staged = StagedReward(task, load_staged_config())
    filled = tuple(bool(j in mine) for j in range(16))
    e = dataclasses.replace(u.evaluate(), correct=len(mine), slot_filled=filled)
    pot = staged.potentials(e)
    done = len(mine) / 16
    for stage in ("seal", "lift", "transport", "align"):  # reach turns to the wanted tiles
        assert pot[stage] == pytest.approx(done), stage
    open_ = dataclasses.replace(e, correct=0, slot_filled=(False,) * 16)
    assert staged.potentials(open_)["seal"] == 1.0


@pytest.fixture(scope="module")
def procedural() -> Iterator[gym.Env]:
    """A procedural 6-slot design (seed 1): two slots of one asymmetric class at 10 and 119 deg."""
    e = gym.make(
        envs.ENV_ID,
        action_mode="pick_place",
        execution="kinematic",
        obs_mode="state",
        design_source="procedural",
        max_slots=6,
        reward_mode="staged",
        tile_variants=1,
        disable_env_checker=True,
    )
    yield e
    e.close()


def test_staged_transport_and_align_aim_at_the_nearest_open_slot_of_the_class(
    procedural: gym.Env,
) -> None:
    """Guards against the target slot of a held tile taken as the first open slot of its class
    instead of the nearest (its yaw then decides the align), or the distance to it taken as a
    norm over all the class's open slots: a tile held 10 mm off the second of two slots,
    turned pi / 8 from it, transports 1 - tanh(0.01 / 0.3) and aligns 0.5 x (1 - 1 / 8)."""
    procedural.reset(seed=1)
    u = procedural.unwrapped
    task, cell = u.task, u.cell
    cls = int(np.flatnonzero(np.bincount(task.slot_class) == 2)[0])
    first, second = np.flatnonzero(task.slot_class == cls)
    tile = int(np.flatnonzero(task.tile_class == cls)[0])
    assert int(task.symmetry[tile]) == 1  # asymmetric: the two slots' yaws differ for it
    assert abs(task.slot_xyyaw[first, 2] - task.slot_xyyaw[second, 2]) > 1.5
    _hold(u, tile, int(second))
    staged = StagedReward(task, load_staged_config())
    q = cell.ids.tile_qpos_index[tile]
    x, y, yaw = task.slot_xyyaw[second]
    cell.data.qpos[q[2]] += 0.03  # a full lift height: lift 1
    cell.data.qpos[q[:2]] = [x + 0.01, y]
    cell.data.qpos[q[3:]] = quat_from_yaw(yaw + math.pi / 8)
    mujoco.mj_forward(cell.model, cell.data)
    open_ = dataclasses.replace(u.evaluate(), slot_filled=(False,) * 6, correct=0)
    pot = staged.potentials(open_)
    assert pot["lift"] == 1.0
    assert pot["transport"] == pytest.approx(1 - math.tanh(0.01 / 0.3), abs=1e-6)
    assert pot["align"] == pytest.approx(0.5 * (1 - 1 / 8), abs=1e-6)


def test_staged_reach_is_to_the_nearest_grasp_point_of_the_wanted_tiles(dense: gym.Env) -> None:
    """Guards against the grasp point's offset from the tile's centroid subtracted instead of
    added (turned by the tile's yaw), or the reach distance taken as a norm over all the wanted
    tiles instead of the nearest one: the pad 5 cm above the grasp point of a tile whose grasp
    point is 18 mm off its centroid reaches 1 - tanh(0.05 / 0.3)."""
    dense.reset(seed=0)
    u = dense.unwrapped
    cell = u.cell
    offsets = [float(np.linalg.norm(t.grasp)) for t in cell.tiles]
    tile = int(np.argmax(offsets))
    assert offsets[tile] > 0.015
    pose = cell.tile_poses()
    grasp = pose.pos[tile].copy()
    c, s = math.cos(pose.yaw[tile]), math.sin(pose.yaw[tile])
    g = cell.tiles[tile].grasp
    grasp[:2] += [c * g[0] - s * g[1], s * g[0] + c * g[1]]
    above = grasp + [0.0, 0.0, 0.05]
    cell.set_qpos(u.ik.solve(above, 0.0).q)
    assert cell.held_tile < 0
    tool = cell.tcp_pose()[0]
    assert np.linalg.norm(tool - above) < 1e-4
    staged = StagedReward(u.task, load_staged_config())
    pot = staged.potentials(u.evaluate())
    d = np.linalg.norm(grasp - tool)
    assert pot["reach"] == pytest.approx(1 - math.tanh(d / 0.3), abs=1e-9)


def test_staged_lift_stays_at_zero_below_the_resting_height(one_tile: gym.Env) -> None:
    """Guards against the lift potential's lower clip dropped (every potential is in [0, 1]): a
    held tile pressed 5 mm below its resting height has lift 0 and transport 0, not negative."""
    one_tile.reset(seed=1)
    u = one_tile.unwrapped
    cell = u.cell
    _hold(u, 0, 0)
    q = cell.ids.tile_qpos_index[0]
    cell.data.qpos[q[2]] -= 0.005
    mujoco.mj_forward(cell.model, cell.data)
    pot = u.task.staged.potentials(u.evaluate())
    assert pot["seal"] == 1.0
    assert pot["lift"] == 0.0 and pot["transport"] == 0.0
    assert all(0.0 <= v <= 1.0 for v in pot.values())


def test_staged_mode_pays_the_stage_terms_in_the_task_s_rewards(one_tile: gym.Env) -> None:
    """Guards against the staged terms left out of the task's rewards in ``staged`` mode (or
    computed from another evaluation than the step's): filling the one slot pays
    ``stage_release`` 4 x (1 - 0) and the other stages their rest up to 1."""
    one_tile.reset(seed=1)
    u = one_tile.unwrapped
    task = u.task
    task.reset()
    before = task.staged.potentials(task.last_evaluation)
    done = dataclasses.replace(task.last_evaluation, correct=1, slot_filled=(True,))
    terms = task.rewards(done, False)
    assert set(terms) == set(REWARD_TERMS)
    assert terms["stage_release"] == pytest.approx(4.0)
    weights = {"reach": 1, "seal": 1, "lift": 1, "transport": 2, "align": 1, "release": 4}
    for s in STAGES:
        assert terms[f"stage_{s}"] == pytest.approx(weights[s] * (1.0 - before[s])), s
