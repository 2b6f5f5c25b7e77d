"""Observation contract of the ``state`` and ``robot`` keys (`envs.observations.spaces`), read
from the documented layout: per tile x, y, z [m], cos yaw, sin yaw, class index, present; per slot
x, y [m], cos yaw, sin yaw, class index, filled; ``robot`` joint positions [rad], velocities
[rad/s], tool position [m], tool yaw (cos, sin), vacuum on, tile held.
World frame, agent index order.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401 - registers the ids
from envs.observations.spaces import DEPTH_MAX, ROBOT_DIM, SLOT_DIM, TILE_DIM, Observer
from spatial.rotations import yaw_from_matrix


@pytest.fixture(scope="module")
def env() -> Iterator[gym.Env]:
    e = gym.make(
        "MosaicDecision6-v0",
        tile_order="shuffled",
        slot_order="shuffled",
        obs_mode="rgb+state",
        image_size=(24, 32),
        disable_env_checker=True,
    )
    yield e
    e.close()


def test_state_rows_in_world_metres_and_agent_order(env: gym.Env) -> None:
    """Guards against a column moved, cos and sin swapped, the slot yaw's angle misread, the
    class or present flags wrong, rows left in the cell's order instead of the agent's, or the
    rows not flattened into the documented 1-D vectors."""
    obs, _ = env.reset(seed=11)
    u: Any = env.unwrapped
    cell, task, index = u.cell, u.task, u.index
    assert (TILE_DIM, SLOT_DIM, ROBOT_DIM) == (7, 6, 19)
    n, k = len(cell.tiles), len(cell.slots)  # flat vectors, as the Dict space has them
    assert obs["tiles"].shape == (n * TILE_DIM,) and obs["tiles"].dtype == np.float32
    assert obs["slots"].shape == (k * SLOT_DIM,) and obs["slots"].dtype == np.float32
    assert env.observation_space.contains(obs)
    raw = u.observer.observe(np.random.default_rng(0), task.evaluate())  # before the agent order
    assert raw["slots"].shape == (k * SLOT_DIM,) and u.observer.space.contains(raw)
    tiles = obs["tiles"].reshape(-1, TILE_DIM).astype(float)
    slots = obs["slots"].reshape(-1, SLOT_DIM).astype(float)
    poses = cell.tile_poses()
    t = index.tiles
    np.testing.assert_allclose(tiles[:, :3], poses.pos[t], atol=1e-6)
    np.testing.assert_allclose(tiles[:, 3], np.cos(poses.yaw[t]), atol=1e-6)
    np.testing.assert_allclose(tiles[:, 4], np.sin(poses.yaw[t]), atol=1e-6)
    np.testing.assert_array_equal(tiles[:, 5], task.tile_class[t])
    np.testing.assert_array_equal(tiles[:, 6], 1.0)
    s = index.slots
    xyyaw = task.slot_xyyaw[s]
    np.testing.assert_allclose(slots[:, :2], xyyaw[:, :2], atol=1e-6)
    np.testing.assert_allclose(slots[:, 2], np.cos(xyyaw[:, 2]), atol=1e-6)
    np.testing.assert_allclose(slots[:, 3], np.sin(xyyaw[:, 2]), atol=1e-6)
    np.testing.assert_array_equal(slots[:, 4], task.slot_class[s])
    np.testing.assert_array_equal(slots[:, 5], 0.0)
    assert not np.array_equal(t, np.arange(len(t))) or not np.array_equal(s, np.arange(len(s)))
    # a placed tile: its slot's filled flag turns 1, its class still matches the slot's
    obs, _, _, _, info = env.step(u.expert_action(0, 0))
    slots = obs["slots"].reshape(-1, SLOT_DIM)
    filled = np.asarray(info["evaluation"]["slot_filled"], float)[index.slots]
    np.testing.assert_array_equal(slots[:, 5], filled)
    assert filled.sum() == 1


def test_robot_vector_fields(env: gym.Env) -> None:
    """Guards against the robot vector's order or units changed: joints [rad], joint velocities
    [rad/s], tool position [m], tool yaw as (cos, sin), vacuum, held."""
    obs, _ = env.reset(seed=11)
    u: Any = env.unwrapped
    cell = u.cell
    r = obs["robot"].astype(float)
    assert r.shape == (ROBOT_DIM,) and obs["robot"].dtype == np.float32
    np.testing.assert_allclose(r[:6], cell.qpos, atol=1e-6)
    np.testing.assert_allclose(r[6:12], cell.qvel, atol=1e-6)
    pos, rot = cell.tcp_pose()
    np.testing.assert_allclose(r[12:15], pos, atol=1e-6)
    yaw = yaw_from_matrix(rot)
    np.testing.assert_allclose(r[15:17], [np.cos(yaw), np.sin(yaw)], atol=1e-6)
    assert (r[17], r[18]) == (float(cell.vacuum_on), float(cell.tile_held))
    assert 0.1 < np.linalg.norm(pos[:2]) < 1.0  # metres: the tool within the arm's reach


def test_robot_vacuum_and_held_flags_follow_the_pad(env: gym.Env) -> None:
    """Guards against the vacuum flag written into the held flag's place (or left unwritten):
    vacuum on over nothing reads (1, 0), then off (0, 0), each read afresh."""
    env.reset(seed=12)
    u: Any = env.unwrapped
    rng = np.random.default_rng(0)
    flags = []
    for on in (True, False, True, False):
        u.cell.vacuum(on)
        assert not u.cell.tile_held  # the pad is at home, above nothing
        flags.append(u.observer.observe(rng, u.evaluate())["robot"][17:].tolist())
    assert flags == [[1.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.0, 0.0]]


def test_images_are_the_cameras_at_the_configured_size(env: gym.Env) -> None:
    """Guards against the camera keys swapped or the image size ignored."""
    obs, _ = env.reset(seed=11)
    for name in ("input_camera", "output_camera"):
        assert obs[name].shape == (24, 32, 3) and obs[name].dtype == np.uint8
        assert env.observation_space[name].contains(obs[name])
    u: Any = env.unwrapped
    np.testing.assert_array_equal(obs["input_camera"], u.cell.render("input_camera", 24, 32))
    assert not np.array_equal(obs["input_camera"], obs["output_camera"])
    assert env.observation_space.contains(obs)


def test_depth_images_are_metres_under_the_far_bound() -> None:
    """Guards against the depth keys misnamed, not clipped to `DEPTH_MAX` or in another unit:
    the input camera sees the belt top about its height above it [m]."""
    e = gym.make("MosaicDecision6-v0", obs_mode="rgb", depth=True, image_size=(24, 32))
    try:
        obs, _ = e.reset(seed=11)
        u: Any = e.unwrapped
        for name in ("input_depth", "output_depth"):
            d = obs[name]
            assert d.shape == (24, 32, 1) and d.dtype == np.float32
            assert e.observation_space[name].contains(d)
            assert 0.0 < float(d.min()) and float(d.max()) <= DEPTH_MAX
        raw = u.cell.render("input_camera", 24, 32, depth=True)
        np.testing.assert_allclose(obs["input_depth"][..., 0], np.clip(raw, 0.0, DEPTH_MAX))
        centre = float(obs["input_depth"][12, 16, 0])
        assert 0.05 < centre < 2.0  # metres from the camera to the belt
    finally:
        e.close()


def test_present_is_zero_for_tiles_not_yet_fed() -> None:
    """Guards against the ``present`` flag true for a tile not on the belts (fed and not lost,
    both required): at a ``stream`` episode's start the tiles not fed yet are absent."""
    env = gym.make("MosaicDecision6-v0", feed="stream", obs_mode="state", disable_env_checker=True)
    try:
        obs, _ = env.reset(seed=1000)
        u: Any = env.unwrapped
        tiles = obs["tiles"].reshape(-1, TILE_DIM).astype(float)
        fed = u.cell.on_stage[u.index.tiles]
        assert 0 < fed.sum() < len(fed)
        np.testing.assert_array_equal(tiles[:, 6], fed.astype(float))
    finally:
        env.close()


def test_joint_noise_is_the_generator_s_normal_draws_on_the_joint_positions(
    env: gym.Env,
) -> None:
    """Guards against ``obs_noise`` [rad] drawn from another generator than the one given, added
    with another scale or sign, or put on other fields than the joint positions: the robot
    vector's first 6 entries are the joints plus ``normal(0, obs_noise, 6)`` from the same seed,
    the rest as without noise; without noise the generator (the env's) is not drawn from. An
    ``rgb+state`` observer built afresh gives the pictures and the state vectors."""
    env.reset(seed=11)
    u: Any = env.unwrapped
    ev = u.task.evaluate()
    rng = np.random.default_rng(5)
    observer = Observer(u.cell, u.task, u.config)
    full = observer.observe(rng, ev)
    assert set(full) == {"input_camera", "output_camera", "robot", "tiles", "slots"}  # rgb+state
    picture = observer.space["input_camera"]
    assert picture.dtype == np.uint8 and picture.low.min() == 0 and picture.high.max() == 255
    assert observer.space.contains(full)
    clean = full["robot"]
    assert rng.random() == np.random.default_rng(5).random()  # nothing drawn without noise
    noisy_observer = Observer(u.cell, u.task, dataclasses.replace(u.config, obs_noise=0.01))
    noisy = noisy_observer.observe(np.random.default_rng(5), ev)["robot"]
    draws = np.random.default_rng(5).normal(0.0, 0.01, 6)
    np.testing.assert_allclose(noisy[:6], u.cell.qpos + draws, atol=1e-6)
    np.testing.assert_array_equal(noisy[6:], clean[6:])
    np.testing.assert_allclose(clean[:6], u.cell.qpos, atol=1e-6)
