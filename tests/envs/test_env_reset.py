"""`MosaicAssembly-v0` reset on the 16-tile default design: tiles laid out at rest, kept apart."""

from __future__ import annotations

from collections.abc import Iterator

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
