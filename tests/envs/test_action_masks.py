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

import envs  # noqa: F401 - registers the ids
from envs.masks import split_mask
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
    _, info = failing.reset(seed=1000)
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
