"""Manufacturing noise is re-drawn at each reset from pre-built tile variants (tile_variants)."""

from __future__ import annotations

from collections.abc import Iterator

import mujoco
import numpy as np
import pytest

from envs.env_config import EnvConfigError
from envs.mosaic_env import MosaicAssemblyEnv

N_SLOTS = 4
SEEDS = range(6)


@pytest.fixture(scope="module")
def env() -> Iterator[MosaicAssemblyEnv]:
    e = MosaicAssemblyEnv(
        action_mode="pick_place",
        execution="kinematic",
        obs_mode="state",
        max_slots=N_SLOTS,
    )
    yield e
    e.close()


def _geometry(env: MosaicAssemblyEnv) -> list[np.ndarray]:
    """Ground truth of each tile now: its glaze mesh's vertices as compiled [m]."""
    m = env.cell.model
    out = []
    for g in env.cell.ids.tile_visual[:, 1]:
        mesh = m.geom_dataid[g]
        start, count = m.mesh_vertadr[mesh], m.mesh_vertnum[mesh]
        out.append(m.mesh_vert[start : start + count].copy())
    return out


def _glaze(env: MosaicAssemblyEnv) -> np.ndarray:
    return env.cell.model.geom_rgba[env.cell.ids.tile_visual[:, 1]].copy()


def test_reset_redraws_outlines_and_colours(env: MosaicAssemblyEnv) -> None:
    shapes, colours = [], []
    for seed in SEEDS:
        env.reset(seed=seed)
        geometry = _geometry(env)
        for tile, verts in zip(env.cell.tiles, geometry, strict=True):
            # The episode's tile description is the body the model simulates.
            assert len(verts) == 2 * len(tile.outline) + 2 * sum(len(h) for h in tile.holes)
        shapes.append(geometry)
        colours.append(_glaze(env))
    for i in range(N_SLOTS):
        distinct = {shapes[k][i].tobytes() for k in range(len(SEEDS))}
        assert len(distinct) > 1, f"tile {i} kept one outline over {len(SEEDS)} seeds"
        assert not np.allclose(colours[0][i], colours[1][i])


def test_same_seed_same_noise(env: MosaicAssemblyEnv) -> None:
    env.reset(seed=3)
    shapes, colours, variant = _geometry(env), _glaze(env), env.cell.variant.copy()
    outlines = [t.outline.copy() for t in env.cell.tiles]
    env.reset(seed=4)
    env.reset(seed=3)
    np.testing.assert_array_equal(env.cell.variant, variant)
    for a, b in zip(shapes, _geometry(env), strict=True):
        np.testing.assert_array_equal(a, b)
    for a, t in zip(outlines, env.cell.tiles, strict=True):
        np.testing.assert_array_equal(a, t.outline)
    np.testing.assert_array_equal(colours, _glaze(env))
    other = MosaicAssemblyEnv(
        action_mode="pick_place", execution="kinematic", obs_mode="state", max_slots=N_SLOTS
    )
    try:
        other.reset(seed=3)
        for a, b in zip(shapes, _geometry(other), strict=True):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(colours, _glaze(other))
    finally:
        other.close()


def test_unused_variants_parked_hidden_asleep(env: MosaicAssemblyEnv) -> None:
    env.reset(seed=1)
    cell = env.cell
    env.step(env.expert_action(0, 0))
    pool = cell.pool_ids.tile_body
    unused = np.setdiff1d(pool, cell.ids.tile_body)
    assert len(pool) == env.config.tile_variants * len(cell.tiles)
    assert len(unused) == (env.config.tile_variants - 1) * len(cell.tiles)
    m, d = cell.model, cell.data
    assert np.all(d.body_awake[unused] == mujoco.mjtSleepState.mjS_ASLEEP)
    np.testing.assert_array_equal(d.xpos[unused], m.body_pos[unused])  # where built: parked
    assert np.all(np.linalg.norm(d.xpos[unused, :2] - cell.geometry.input_centre[:2], axis=1) > 3)
    assert np.all(m.body_contype[unused] == 0) and np.all(m.body_conaffinity[unused] == 0)
    hidden = np.isin(m.geom_bodyid, unused) & (m.geom_group == 2)
    assert hidden.sum() == 2 * len(unused) and np.all(m.geom_rgba[hidden, 3] == 0)
    shown = cell.ids.tile_visual.ravel()
    assert np.all(m.geom_rgba[shown, 3] == 1)


def test_non_first_variant_is_picked_and_placed(env: MosaicAssemblyEnv) -> None:
    seed = next(s for s in range(100) if _variant_of_first_tile(env, s) > 0)
    env.reset(seed=seed)
    cell = env.cell
    body = int(cell.ids.tile_body[0])
    assert body != int(cell.pool_ids.tile_body[0])  # not variant 0's body
    _, reward, _, _, info = env.step(env.expert_action(0, 0))
    ev = info["evaluation"]
    assert not info["action_failed"], info["action_error"]
    assert ev["correct"] == 1 and ev["slot_filled"][0]
    assert ev["misplaced"] == ev["dropped"] == ev["lost"] == 0
    assert reward == pytest.approx(env.config.reward_correct)
    assert [e.kind for e in cell.events] == ["grasp", "release"]
    slot_xy = cell.slot_poses_world()[0, :2]
    assert np.linalg.norm(cell.data.xpos[body, :2] - slot_xy) < env.config.position_tolerance
    assert cell.warnings() == 0


def _variant_of_first_tile(env: MosaicAssemblyEnv, seed: int) -> int:
    env.reset(seed=seed)
    return int(env.cell.variant[0])


def test_one_variant_keeps_the_build_noise() -> None:
    env = MosaicAssemblyEnv(obs_mode="state", max_slots=2, tile_variants=1)
    try:
        env.reset(seed=0)
        shapes, colours = _geometry(env), _glaze(env)
        env.reset(seed=1)
        for a, b in zip(shapes, _geometry(env), strict=True):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(colours, _glaze(env))
        assert len(env.cell.pool_ids.tile_body) == len(env.cell.tiles)
    finally:
        env.close()


@pytest.mark.parametrize("bad", [0, -1, 2.5])
def test_tile_variants_must_be_a_positive_int(bad: object) -> None:
    with pytest.raises(EnvConfigError, match="tile_variants"):
        MosaicAssemblyEnv(tile_variants=bad)
