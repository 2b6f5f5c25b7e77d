"""Action masks of ``pick_place_discrete`` and strict refusal of what they forbid.

The mask (sb3-contrib's convention: tile, slot and rotation masks concatenated) is what the env
can execute: every allowed action is accepted, every forbidden one is refused with `ActionError`
under ``invalid_actions="refuse"`` and fails (time and penalty) under ``fail``.
"""

from __future__ import annotations

from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sb3_contrib.common.maskable.utils import get_action_masks, is_masking_supported
from stable_baselines3.common.vec_env import DummyVecEnv

import envs
import envs.tasks
from envs.masks import action_mask, check_allowed, split_mask
from envs.mosaic_env import MosaicEnvError
from envs.task_spec import ActionError

TASK = "MosaicDecision6-v0"
SLOTS = 6
BINS = 4


@pytest.fixture(scope="module")
def refusing() -> Iterator[gym.Env]:
    """The 6-slot decision rung refusing forbidden actions."""
    env = gym.make(TASK, invalid_actions="refuse")
    yield env
    env.close()


@pytest.fixture(scope="module")
def failing() -> Iterator[gym.Env]:
    """The 6-slot decision rung as registered at -v0 (forbidden actions fail)."""
    env = gym.make(TASK)
    yield env
    env.close()


def masks(env: gym.Env) -> np.ndarray:
    return np.asarray(env.get_wrapper_attr("action_masks")(), bool)


def test_the_mask_opens_every_belt_tile_and_slot_at_reset_and_closes_what_is_used(failing):
    """Guards against a mask that is not the documented bool vector (a float tile, slot or
    rotation part makes the whole mask float), or entries closed or left open wrongly."""
    _, info = failing.reset(seed=1000)
    raw = failing.get_wrapper_attr("action_masks")()
    assert raw.dtype == bool and info["action_mask"].dtype == bool  # as returned, not cast
    mask = masks(failing)
    assert mask.shape == (SLOTS + SLOTS + BINS,) and mask.dtype == bool
    assert mask.all()
    np.testing.assert_array_equal(info["action_mask"], mask)
    unwrapped = failing.unwrapped
    _, _, _, _, info = failing.step(unwrapped.expert_action(0, 0))
    assert info["tiles_placed"] == 1
    tiles, slots, rotations = split_mask(info["action_mask"], failing.action_space.nvec)
    np.testing.assert_array_equal(info["action_mask"], masks(failing))
    assert tiles.sum() == SLOTS - 1 and slots.sum() == SLOTS - 1 and rotations.all()
    # the placed tile and its slot are the closed entries
    placed = unwrapped.expert_action(0, 0)
    assert not slots[placed[1]]
    assert 0 not in unwrapped.index.tiles[tiles]


def test_an_empty_input_belt_allows_every_tile_index_as_a_wait():
    env = gym.make("MosaicStream-v1", stream_initial=1, stream_period=30.0)
    try:
        env.reset(seed=1000)
        u = env.unwrapped
        first = int(np.flatnonzero(u.cell.input_half())[0])  # the one tile fed so far
        env.step(u.expert_action(first, first))
        assert not u.cell.input_half().any()
        tiles, _, _ = split_mask(masks(env), env.action_space.nvec)
        assert tiles.all()
        t0 = u.cell.time
        _, _, _, _, info = env.step(np.array([0, 1, 0]))
        assert info["action_failed"] and u.cell.time > t0
    finally:
        env.close()


def test_a_forbidden_action_fails_at_v0_and_costs_time(failing):
    failing.reset(seed=1001)
    u = failing.unwrapped
    _, _, _, _, info = failing.step(u.expert_action(1, 1))
    tiles, slots, _ = split_mask(info["action_mask"], failing.action_space.nvec)
    bad = np.array([int(np.flatnonzero(~tiles)[0]), int(np.flatnonzero(slots)[0]), 0])
    t0 = info["sim_time"]
    _, reward, _, _, info = failing.step(bad)
    assert info["action_failed"] and "not on the input belt" in info["action_error"]
    assert info["sim_time"] > t0 and reward < 0


def test_refuse_names_the_index_and_leaves_the_state_unchanged(refusing):
    _, info = refusing.reset(seed=1002)
    u = refusing.unwrapped
    _, _, _, _, info = refusing.step(u.expert_action(2, 2))
    _, slots, _ = split_mask(info["action_mask"], refusing.action_space.nvec)
    filled = int(np.flatnonzero(~slots)[0])
    tiles_before = u.cell.tile_poses().pos.copy()
    with pytest.raises(ActionError, match=rf"slot index {filled} is filled.*allowed now: slot in"):
        refusing.step(np.array([0, filled, 0]))
    np.testing.assert_array_equal(u.cell.tile_poses().pos, tiles_before)
    assert u.evaluate().correct == 1
    np.testing.assert_array_equal(masks(refusing), info["action_mask"])


def test_masks_are_found_through_a_vector_env_of_gym_make():
    vec = DummyVecEnv([lambda: gym.make(TASK)])
    vec.reset()
    assert is_masking_supported(vec)
    assert get_action_masks(vec).shape == (1, SLOTS + SLOTS + BINS)
    vec.close()


def test_action_masks_outside_the_discrete_mode_is_a_typed_error():
    env = gym.make(TASK, action_mode="pick_place")
    env.reset(seed=0)
    with pytest.raises(MosaicEnvError, match="needs pick_place_discrete"):
        env.get_wrapper_attr("action_masks")()
    env.close()


def test_action_masks_before_reset_is_a_typed_error():
    env = gym.make(TASK)
    with pytest.raises(MosaicEnvError, match="before reset"):
        env.get_wrapper_attr("action_masks")()
    env.close()


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 10_000),
    actions=st.lists(
        st.tuples(st.integers(0, SLOTS - 1), st.integers(0, SLOTS - 1), st.integers(0, BINS - 1)),
        min_size=1,
        max_size=5,
    ),
)
def test_the_mask_allows_exactly_what_the_env_accepts(refusing, seed, actions):
    refusing.reset(seed=seed)
    nvec = refusing.action_space.nvec
    for raw in actions:
        action = np.array(raw)
        mask = masks(refusing)
        tiles, slots, rotations = split_mask(mask, nvec)
        allowed = tiles[action[0]] and slots[action[1]] and rotations[action[2]]
        if not allowed:
            t0 = refusing.unwrapped.cell.time
            with pytest.raises(ActionError, match="allowed now"):
                refusing.step(action)
            assert refusing.unwrapped.cell.time == t0
            np.testing.assert_array_equal(masks(refusing), mask)
            continue
        waiting = not refusing.unwrapped.cell.input_half().any()
        _, _, terminated, _, info = refusing.step(action)
        assert waiting or "not on the input belt" not in info["action_error"]
        if terminated:
            break


def _rung_env(task_id: str) -> gym.Env:
    return gym.make(task_id, disable_env_checker=True)


@pytest.mark.parametrize("task_id", list(envs.tasks.bundled_tasks()))
def test_every_rung_masks_belt_tiles_open_slots_and_padding(task_id):
    """Guards against the mask read from the wrong index map (cell order instead of the agent's
    indices), a filled slot left open, padded indices allowed, or a rung without the mask.

    Decision rungs: tile ``i`` allowed iff the tile the agent's index ``i`` names lies on the
    input belt's side; slot ``j`` iff open; every rotation; indices past the episode's counts
    forbidden. The other rungs have no mask (a typed error)."""
    env = _rung_env(task_id)
    try:
        env.reset(seed=7)
        u = env.unwrapped
        if env.action_space.__class__.__name__ != "MultiDiscrete":
            with pytest.raises(MosaicEnvError, match="needs pick_place_discrete"):
                env.get_wrapper_attr("action_masks")()
            return
        nvec = env.action_space.nvec
        tiles, slots, rotations = split_mask(masks(env), nvec)
        n, k = len(u.index.tiles), len(u.index.slots)
        on_input = u.cell.input_half()[u.index.tiles]
        if on_input.any():
            np.testing.assert_array_equal(tiles[:n], on_input)
        else:
            assert tiles[:n].all()  # nothing to pick: every tile index is a wait
        assert not tiles[n:].any() and not slots[k:].any()
        filled = np.asarray(u.evaluate().slot_filled, bool)[u.index.slots]
        np.testing.assert_array_equal(slots[:k], ~filled)
        assert rotations.all() and len(rotations) == nvec[2]
    finally:
        env.close()


def test_the_mask_follows_the_agent_indices_not_the_cell_order():
    """Guards against ``index.tiles`` / ``index.slots`` dropped from the mask: with shuffled
    indices a tile taken off the belt and its filled slot close at their agent indices
    (`envs.masks.action_mask` of the state now; the env's mask is the one of the last step)."""
    env = gym.make(TASK, tile_order="shuffled", slot_order="shuffled")
    try:
        env.reset(seed=5)
        u = env.unwrapped
        cell_tile = 2
        u.cell.place_tiles(np.array([cell_tile]), np.array([[0.0, 0.0, 0.0]]))
        q = u.cell.ids.tile_qpos_index[cell_tile]
        x, y, yaw = u.task.slot_xyyaw[
            int(np.flatnonzero(u.task.slot_class == u.task.tile_class[cell_tile])[0])
        ]
        u.cell.data.qpos[q[:2]] = [x, y]
        u.cell.data.qpos[q[2]] = u.cell.geometry.mesh_top + u.cell.cfg.tiles.thickness / 2
        from spatial.rotations import quat_from_yaw  # noqa: PLC0415

        u.cell.data.qpos[q[3:]] = quat_from_yaw(yaw)
        import mujoco  # noqa: PLC0415

        mujoco.mj_forward(u.cell.model, u.cell.data)
        e = u.evaluate()
        filled_slot = int(np.flatnonzero(e.slot_filled)[0])
        nvec = env.action_space.nvec
        tiles, slots, _ = split_mask(action_mask(u.cell, u.index, e.slot_filled, nvec), nvec)
        agent_tile = int(np.flatnonzero(u.index.tiles == cell_tile)[0])
        agent_slot = int(np.flatnonzero(u.index.slots == filled_slot)[0])
        assert not tiles[agent_tile] and tiles.sum() == SLOTS - 1
        assert not slots[agent_slot] and slots.sum() == SLOTS - 1
    finally:
        env.close()


def test_split_and_check_allowed_on_a_hand_made_mask():
    """Guards against the cut points of the flat mask or the refusal test moved by one."""
    nvec = np.array([3, 2, 4])
    mask = np.array([1, 0, 1, 0, 1, 1, 1, 1, 1], bool)
    tiles, slots, rotations = split_mask(mask, nvec)
    assert tiles.tolist() == [True, False, True] and slots.tolist() == [False, True]
    assert rotations.tolist() == [True] * 4

    class Space:
        pass

    space = Space()
    space.nvec = nvec  # type: ignore[attr-defined]
    check_allowed(np.array([2, 1, 3]), mask, space, "refuse")
    check_allowed(np.array([1, 0, 0]), mask, space, "fail")  # fail: never refused here
    with pytest.raises(ActionError, match=r"tile index 1 is not on the input belt.*\[0, 2\]"):
        check_allowed(np.array([1, 1, 0]), mask, space, "refuse")
    with pytest.raises(ActionError, match=r"slot index 0 is filled already.*\[1\]"):
        check_allowed(np.array([0, 0, 0]), mask, space, "refuse")
