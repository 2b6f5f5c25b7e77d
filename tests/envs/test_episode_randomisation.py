"""The episode set-up's domain randomisation at its edges (`MosaicTask.initialize_episode`).

Documented contract: tile colours are multiplied by ``1 + normal(0, color_randomization)`` and
lights by ``1 + normal(0, light_randomization)`` (one factor per light), each clipped to
[0, 1]; cameras move within ``camera_position_jitter`` [m] and turn within
``camera_angle_jitter_deg`` [deg]; each randomisation draws from the episode's generator only
when it is on. Each test names the bug it guards against; they build their `MosaicTask`
themselves (the mutation run credits code run in a shared fixture to the first test only).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import envs  # noqa: F401 - registers the ladder
from envs.task import SEED_BOUND, MosaicTask


@pytest.fixture(scope="module")
def env() -> Iterator[gym.Env]:
    e = gym.make("MosaicDecision6-v0", disable_env_checker=True)
    e.reset(seed=0)
    yield e
    e.close()


def _task(env: gym.Env, **changes: Any) -> MosaicTask:
    one = env.unwrapped
    off = {
        "color_randomization": 0.0,
        "light_randomization": 0.0,
        "camera_position_jitter": 0.0,
        "camera_angle_jitter_deg": 0.0,
        "reset_settle": 0.0,
    }
    return MosaicTask(one.cell, dataclasses.replace(one.config, **{**off, **changes}))


def _camera_pose(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    cell = env.unwrapped.cell
    mujoco.mj_forward(cell.model, cell.data)
    return cell.data.cam_xpos.copy(), cell.data.cam_xmat.copy()


@pytest.mark.parametrize(
    "changes",
    [{}, {"color_randomization": 0.1}],
    ids=["all-off", "colours-only"],
)
def test_an_off_randomisation_draws_nothing_from_the_generator(
    env: gym.Env, changes: dict[str, float]
) -> None:
    """Guards against a randomisation drawing while off (lights or cameras at 0): the set-up
    then takes exactly the layout's seed (and the colours' factors when on) from the episode's
    generator, so the generator's next number is the one after those draws; an extra draw
    would shift every later episode of a seeded run."""
    task = _task(env, **changes)
    nvis = len(env.unwrapped.cell.ids.tile_visual.ravel())
    for seed in (3, 4, 5):
        rng = np.random.default_rng(seed)
        task.initialize_episode(rng)
        ref = np.random.default_rng(seed)
        ref.integers(SEED_BOUND)
        if changes:
            ref.normal(0.0, 0.1, (nvis, 3))
        assert rng.random() == ref.random()


def test_camera_turn_alone_turns_the_cameras_and_keeps_their_places(env: gym.Env) -> None:
    """Guards against the camera jitter's switch missing an angle-only jitter (half a degree):
    the cameras turn within the bound and stay where they were; a shift alone moves them
    within its bound."""
    base_pos, base_mat = _camera_pose(env)
    _task(env, camera_angle_jitter_deg=0.5).initialize_episode(np.random.default_rng(7))
    pos, mat = _camera_pose(env)
    np.testing.assert_allclose(pos, base_pos, atol=1e-12)
    assert not np.allclose(mat, base_mat, atol=1e-6)
    cos_turn = np.einsum("cij,cij->c", mat.reshape(-1, 3, 3), base_mat.reshape(-1, 3, 3))
    turn_deg = np.degrees(np.arccos(np.clip((cos_turn - 1.0) / 2.0, -1.0, 1.0)))
    assert turn_deg.max() <= 0.5 * np.sqrt(3) + 1e-6  # within the bound about each axis
    _task(env, camera_position_jitter=0.004).initialize_episode(np.random.default_rng(7))
    pos, mat = _camera_pose(env)
    shift = np.abs(pos - base_pos)
    assert shift.max() <= 0.004 + 1e-12 and shift.max() > 0.0


def test_large_colour_randomisation_clips_to_both_ends(env: gym.Env) -> None:
    """Guards against the colour clip losing a bound: with a standard deviation of 1.5 some
    channels fall below 0 and some rise above 1 before the clip; after it every channel lies in
    [0, 1] and both ends are reached exactly."""
    cell = env.unwrapped.cell
    _task(env).initialize_episode(np.random.default_rng(11))
    visual = cell.ids.tile_visual.ravel()  # the episode's tile variants
    nominal = cell.model.geom_rgba[visual, :3].copy()
    _task(env, color_randomization=1.5).initialize_episode(np.random.default_rng(11))
    np.testing.assert_array_equal(cell.ids.tile_visual.ravel(), visual)  # the same episode
    rgb = cell.model.geom_rgba[visual, :3]
    assert rgb.min() == 0.0 and rgb.max() == 1.0
    rng = np.random.default_rng(11)
    rng.integers(SEED_BOUND)
    f = 1 + rng.normal(0.0, 1.5, (len(visual), 3))
    np.testing.assert_allclose(rgb, np.clip(nominal * f, 0.0, 1.0), atol=1e-6)
    assert (nominal * f).min() < 0.0 and (nominal * f).max() > 1.0


def test_large_light_randomisation_clips_to_both_ends(env: gym.Env) -> None:
    """Guards against the light clip losing a bound: over a few episodes with a standard
    deviation of 1.5 a light is driven below 0 and above 1 before the clip; every level lies in
    [0, 1] after it, both ends reached, each light's three channels scaled alike."""
    cell = env.unwrapped.cell
    task = _task(env, light_randomization=1.5)
    _task(env).initialize_episode(np.random.default_rng(0))
    base = cell.model.light_diffuse.copy()
    seen = []
    for seed in range(12):
        task.initialize_episode(np.random.default_rng(seed))
        light = cell.model.light_diffuse.copy()
        assert light.min() >= 0.0 and light.max() <= 1.0
        ratio = np.where(base > 0, light / np.where(base > 0, base, 1.0), 0.0)
        assert np.allclose(ratio, ratio[:, :1]) or light.max() in (0.0, 1.0)
        seen.append(light)
    levels = np.concatenate([s.ravel() for s in seen])
    assert levels.min() == 0.0 and levels.max() == 1.0
