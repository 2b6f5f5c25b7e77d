"""`MosaicAssembly-v0` reset: on the 16-tile default design the tiles are laid out at rest and
kept apart; the same seed gives the same trajectory, reset randomises, and observations never
share memory."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

import envs
from envs.cell.scene import WAKE_FORCE, set_tile_rotation_lengths
from envs.cell.tiles.variants import CONST_BODY_FIELDS, CONST_DOF_FIELDS
from envs.mosaic_env import MosaicAssemblyEnv


@pytest.fixture(scope="module")
def env() -> Iterator[MosaicAssemblyEnv]:
    e = gym.make(envs.ENV_ID, obs_mode="state", action_mode="joint")
    try:
        yield e.unwrapped
    finally:
        e.close()


def _world_outlines(env: MosaicAssemblyEnv) -> list[Polygon]:
    cell = env.cell
    poses = cell.tile_poses()
    out = []
    for t, p, yaw in zip(cell.tiles, poses.pos, poses.yaw, strict=True):
        c, s = np.cos(yaw), np.sin(yaw)
        out.append(Polygon(t.outline @ np.array([[c, s], [-s, c]]) + p[:2]))
    return out


def test_reset_lays_every_tile_apart_inside_the_tile_area(env: MosaicAssemblyEnv) -> None:
    cell = env.cell
    gap = cell.cfg.tiles.min_gap
    c, half = cell.geometry.input_centre, np.asarray(cell.cfg.input_belt.tile_area) / 2
    for seed in range(3):
        env.reset(seed=seed)
        assert len(cell.tiles) == 16 and cell.on_stage.all()
        polys = _world_outlines(env)
        for a, p in enumerate(polys):
            x0, y0, x1, y1 = p.bounds
            assert x0 >= c[0] - half[0] - 1e-9 and x1 <= c[0] + half[0] + 1e-9
            assert y0 >= c[1] - half[1] - 1e-9 and y1 <= c[1] + half[1] + 1e-9
            assert np.all(shapely.distance(p, polys[a + 1 :]) >= gap - 1e-9)


def test_reset_needs_no_settling(env: MosaicAssemblyEnv) -> None:
    """Tiles laid at their contact height stay put under physics and fall asleep.

    They start asleep (`Cell.reset`); here they are woken for the check, as a touch would.
    """
    cell = env.cell
    env.reset(seed=5)
    assert cell.time == 0.0  # nothing simulated at reset
    before = cell.tile_poses()
    top = cell.geometry.input_centre[2] + cell.cfg.tiles.thickness / 2
    np.testing.assert_allclose(before.pos[:, 2], top, atol=1e-12)
    tiles = cell.model.body_treeid[cell.ids.tile_body]
    cell.data.xfrc_applied[cell.ids.tile_body, 2] = WAKE_FORCE
    cell.step(1)
    cell.data.xfrc_applied[cell.ids.tile_body, 2] = 0.0
    assert np.all(cell.data.tree_asleep[tiles] < 0)  # awake
    cell.step(150)  # 0.3 s holding the arm at home
    after = cell.tile_poses()
    assert np.abs(after.pos[:, :2] - before.pos[:, :2]).max() < 5e-6
    assert np.abs(after.pos[:, 2] - before.pos[:, 2]).max() < 1e-5
    assert np.abs(np.angle(np.exp(1j * (after.yaw - before.yaw)))).max() < 1e-4
    assert np.all(cell.data.tree_asleep[tiles] >= 0)  # at rest: asleep


def test_reset_settle_still_simulates_when_asked() -> None:
    e = gym.make(envs.ENV_ID, obs_mode="state", max_slots=3, reset_settle=0.02)
    try:
        e.reset(seed=0)
        assert e.unwrapped.cell.time == pytest.approx(0.02)
    finally:
        e.close()


def test_variant_swap_constants_equal_mj_setconst(env: MosaicAssemblyEnv) -> None:
    """The tabled mass-derived constants of the shown variants are mj_setConst's."""
    cell = env.cell
    assert cell.variants.count > 1  # configs/env.yaml builds several variants per tile
    fields = CONST_BODY_FIELDS + CONST_DOF_FIELDS + ("dof_length",)
    for seed in range(3):
        env.reset(seed=seed)
        ours = {f: getattr(cell.model, f).copy() for f in fields}
        mujoco.mj_setConst(cell.model, cell.data)
        set_tile_rotation_lengths(cell.model, cell.ids)
        for f in fields:
            np.testing.assert_allclose(ours[f], getattr(cell.model, f), rtol=1e-12, atol=0)


SMALL = {"max_slots": 3, "image_size": 48}


def _rollout(n: int, seed: int, **kw: Any) -> tuple[list[dict[str, Any]], list[float]]:
    env = gym.make(envs.ENV_ID, **{**SMALL, **kw})
    try:
        obs, _ = env.reset(seed=seed)
        env.action_space.seed(seed)
        observations, rewards = [obs], []
        for _ in range(n):
            obs, r, term, trunc, _ = env.step(env.action_space.sample())
            observations.append(obs)
            rewards.append(r)
            if term or trunc:
                break
        return observations, rewards
    finally:
        env.close()


def _same(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> bool:
    return len(a) == len(b) and all(
        all(np.array_equal(x[k], y[k]) for k in x) for x, y in zip(a, b, strict=True)
    )


def test_joint_state_200_steps_identical() -> None:
    kw = {"action_mode": "joint", "obs_mode": "state", "reward_mode": "dense"}
    o1, r1 = _rollout(200, 3, **kw)
    o2, r2 = _rollout(200, 3, **kw)
    assert len(o1) == 201
    assert _same(o1, o2) and r1 == r2
    assert any(r != 0.0 for r in r1)  # dense terms move
    o3, _ = _rollout(5, 4, **kw)
    assert not np.array_equal(o1[0]["tiles"], o3[0]["tiles"])


def test_joint_rgb_identical_images() -> None:
    o1, r1 = _rollout(10, 0, action_mode="joint", obs_mode="rgb")
    o2, r2 = _rollout(10, 0, action_mode="joint", obs_mode="rgb")
    assert _same(o1, o2) and r1 == r2


@pytest.mark.parametrize("execution", ["kinematic", "dynamic"])
def test_pick_place_few_steps_identical(execution: str) -> None:
    kw = {"action_mode": "pick_place_discrete", "obs_mode": "state", "execution": execution}
    o1, r1 = _rollout(3, 1, **kw)
    o2, r2 = _rollout(3, 1, **kw)
    assert _same(o1, o2) and r1 == r2


def test_reset_randomises_tile_poses_and_is_reproducible() -> None:
    env = gym.make(envs.ENV_ID, obs_mode="state", **SMALL)
    try:
        a, _ = env.reset(seed=0)
        b, _ = env.reset(seed=1)
        c, _ = env.reset()  # continues the generator
        a2, _ = env.reset(seed=0)
        assert not np.allclose(a["tiles"], b["tiles"])
        assert not np.allclose(b["tiles"], c["tiles"])
        np.testing.assert_array_equal(a["tiles"], a2["tiles"])
    finally:
        env.close()


def test_reset_randomises_colours_and_light_when_enabled() -> None:
    env = gym.make(
        envs.ENV_ID, color_randomization=0.1, light_randomization=0.2, obs_mode="rgb", **SMALL
    )
    try:
        m = env.unwrapped.cell.model
        env.reset(seed=0)
        rgba, light = m.geom_rgba.copy(), m.light_diffuse.copy()
        env.reset(seed=1)
        assert not np.allclose(rgba, m.geom_rgba) and not np.allclose(light, m.light_diffuse)
    finally:
        env.close()


def test_observations_do_not_share_memory() -> None:
    env = gym.make(envs.ENV_ID, action_mode="joint", obs_mode="rgb+state", **SMALL)
    try:
        first, _ = env.reset(seed=0)
        second, *_ = env.step(env.action_space.sample())
        third, *_ = env.step(env.action_space.sample())
        for k in first:
            assert not np.shares_memory(first[k], second[k]), k
            assert not np.shares_memory(second[k], third[k]), k
        kept = {k: v.copy() for k, v in second.items()}
        env.step(env.action_space.sample())
        for k, value in kept.items():
            np.testing.assert_array_equal(value, second[k])
    finally:
        env.close()
