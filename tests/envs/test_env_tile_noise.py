"""Manufacturing noise is re-drawn at each reset from pre-built tile variants (tile_variants)."""

from __future__ import annotations

from collections.abc import Iterator

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


def test_hidden_variants_are_massless_without_contacts_and_invisible(
    env: MosaicAssemblyEnv,
) -> None:
    env.reset(seed=1)
    cell = env.cell
    env.step(env.expert_action(0, 0))
    m, ids, n = cell.model, cell.ids, len(cell.tiles)
    assert ids.variant_body.shape == (env.config.cell.tiles.variants, n)
    shown = ids.variant_body[cell.variant, np.arange(n)]
    hidden = np.setdiff1d(ids.variant_body, shown)
    assert len(hidden) == (env.config.cell.tiles.variants - 1) * n
    assert np.all(m.body_mass[hidden] == 0) and np.all(m.body_inertia[hidden] == 0)
    assert np.all(m.body_contype[hidden] == 0) and np.all(m.body_conaffinity[hidden] == 0)
    in_hidden = np.isin(m.geom_bodyid, hidden)
    assert np.all(m.geom_contype[in_hidden] == 0) and np.all(m.geom_conaffinity[in_hidden] == 0)
    visual = in_hidden & (m.geom_group == 2)
    assert visual.sum() == 2 * len(hidden) and np.all(m.geom_rgba[visual, 3] == 0)
    assert np.all(m.geom_rgba[ids.tile_visual.ravel(), 3] == 1)
    # The free body weighs what its shown shape does; the tile's body and geoms are that shape's.
    free = m.body_parentid[shown]
    assert np.all(m.body_jntnum[free] == 1) and np.all(m.body_jntnum[shown] == 0)
    np.testing.assert_allclose(m.body_subtreemass[free], m.body_mass[shown])
    np.testing.assert_array_equal(ids.tile_body, shown)
    assert np.all(m.geom_bodyid[ids.tile_geom_start] == shown)
    np.testing.assert_allclose(cell.data.xpos[shown], cell.data.xpos[free])  # one frame
    assert m.nv == 6 + 6 * n and cell.warnings() == 0  # no extra degrees of freedom


def test_variant_masses_match_the_single_variant_model() -> None:
    one = MosaicAssemblyEnv(obs_mode="state", max_slots=N_SLOTS, tile_variants=1)
    many = MosaicAssemblyEnv(obs_mode="state", max_slots=N_SLOTS)
    try:
        one.reset(seed=0)
        expected = one.cell.model.body_mass[one.cell.ids.tile_body]
        seed = next(s for s in range(100) if _variant_of_first_tile(many, s) == 0)
        many.reset(seed=seed)
        c = many.cell
        zero = c.variant == 0  # variant 0 is the single-variant model's tile
        mass = c.model.body_subtreemass[c.model.body_parentid[c.ids.tile_body]]
        np.testing.assert_allclose(mass[zero], expected[zero], rtol=1e-12)
        assert np.all(np.abs(mass / expected - 1) < 0.05)  # other variants: noise only
    finally:
        one.close()
        many.close()


def test_non_first_variant_is_picked_and_placed(env: MosaicAssemblyEnv) -> None:
    seed = next(s for s in range(100) if _variant_of_first_tile(env, s) > 0)
    env.reset(seed=seed)
    cell = env.cell
    body = int(cell.ids.tile_body[0])
    assert cell.variant[0] > 0 and body == cell.ids.variant_body[cell.variant[0], 0]
    assert cell.model.body_mass[body] > 0
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
        assert env.cell.ids.variant_body.shape == (1, len(env.cell.tiles))
    finally:
        env.close()


@pytest.mark.parametrize("bad", [0, -1, 2.5])
def test_tile_variants_must_be_a_positive_int(bad: object) -> None:
    with pytest.raises(EnvConfigError, match="tile_variants"):
        MosaicAssemblyEnv(tile_variants=bad)
