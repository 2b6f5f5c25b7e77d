"""Tiles: convex decomposition, noise, mass, distractors, layout; manufacturing noise re-drawn at
each reset from pre-built tile variants (tile_variants)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from envs.cell.cell import Cell
from envs.cell.config import TileConfig, load_cell_config
from envs.cell.layout import sample_layout
from envs.cell.scene import extrusion
from envs.cell.tiles.decompose import convex_decomposition
from envs.cell.tiles.shapes import basic_shapes
from envs.cell.tiles.tile import jitter_colors, make_tile, make_tile_pool, make_tiles
from envs.env_config import EnvConfigError
from envs.mosaic_env import MosaicAssemblyEnv

SHAPES = basic_shapes()


def _convex(poly: np.ndarray, tol: float) -> bool:
    d1 = np.roll(poly, -1, axis=0) - poly
    d2 = np.roll(d1, -1, axis=0)
    return bool(np.all(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0] >= -tol))


@pytest.mark.parametrize("shape", SHAPES, ids=[s.name for s in SHAPES])
def test_decomposition_is_convex_and_covers_the_shape(shape) -> None:
    points, pieces = convex_decomposition(shape.outline, shape.holes)
    polys = [Polygon(points[p]) for p in pieces]
    assert all(_convex(points[p], 1e-12) for p in pieces)
    assert sum(p.area for p in polys) == pytest.approx(shape.area, rel=1e-9)
    union = shapely.union_all(polys)
    assert union.symmetric_difference(shape.polygon).area < 1e-12
    expect_one = shape.name in ("square", "rectangle", "triangle", "circle", "semicircle")
    assert (len(pieces) == 1) == expect_one


def test_noise_mass_and_colour() -> None:
    cfg = TileConfig(vertex_jitter=0.0003, color_jitter=0.03)
    rng = np.random.default_rng(0)
    sq = SHAPES[0]
    tiles = [make_tile(sq, cfg, rng) for _ in range(20)]
    areas = np.array([t.area for t in tiles])
    assert np.all(np.abs(areas - sq.area) < 0.1 * sq.area) and areas.std() > 0
    colours = np.array([t.color for t in tiles])
    assert np.all(np.abs(colours - sq.color) < 0.15) and colours.std(axis=0).max() > 0.01
    for t in tiles:  # centred on the area centroid
        c = Polygon(t.outline, t.holes).centroid
        assert abs(c.x) < 1e-9 and abs(c.y) < 1e-9
    cell = Cell(None, SHAPES, seed=0)
    try:
        mass = cell.model.body_mass[cell.ids.tile_body]
        expected = np.array([t.area for t in cell.tiles]) * 0.005 * 2400.0
        assert np.allclose(mass, expected, rtol=0.02)
    finally:
        cell.close()


def test_distractors_rate_and_kinds() -> None:
    cfg = TileConfig(distractor_rate=0.5)
    tiles = make_tiles(SHAPES * 20, cfg, np.random.default_rng(1))
    kinds = [t.distractor for t in tiles[len(SHAPES) * 20 :]]
    assert all(t.distractor == "" for t in tiles[: len(SHAPES) * 20])
    assert 50 <= len(kinds) <= 90 and set(kinds) == {"color", "broken", "shape"}
    for t in tiles[len(SHAPES) * 20 :]:
        if t.distractor == "broken":
            assert t.area < 0.95 * t.shape.area
        if t.distractor == "shape":
            assert abs(t.area / t.shape.area - 1) > 0.3
        if t.distractor == "color":
            assert np.linalg.norm(np.subtract(t.color, t.shape.color)) > 0.2
    assert make_tiles(SHAPES, TileConfig(), np.random.default_rng(1))[-1].distractor == ""


def test_tile_pool_variants_share_shape_and_kind() -> None:
    cfg = TileConfig(distractor_rate=0.5, variants=3)
    pool = make_tile_pool(SHAPES, cfg, np.random.default_rng(2))
    first = make_tiles(SHAPES, cfg, np.random.default_rng(2))
    assert len(pool) == 3 and all(len(v) == len(first) for v in pool)
    for a, b in zip(pool[0], first, strict=True):  # variant 0 is make_tiles' draw
        np.testing.assert_array_equal(a.outline, b.outline)
        assert a.color == b.color
    for i in range(len(first)):
        variants = [pool[v][i] for v in range(3)]
        assert len({t.shape.name for t in variants}) == 1
        assert len({t.distractor for t in variants}) == 1
        assert len({t.outline.tobytes() for t in variants}) == 3


def test_jitter_colors_redraws_around_the_base_colour() -> None:
    cfg = TileConfig(color_jitter=0.03)
    tiles = make_tiles(SHAPES, cfg, np.random.default_rng(0))
    a = jitter_colors(tiles, cfg.color_jitter, np.random.default_rng(1))
    b = jitter_colors(tiles, cfg.color_jitter, np.random.default_rng(1))
    assert [t.color for t in a] == [t.color for t in b]
    assert [t.color for t in a] != [t.color for t in tiles]
    base = np.array([t.base_color for t in tiles])
    np.testing.assert_allclose([t.color for t in a], base, atol=0.15)
    assert all(t.outline is u.outline for t, u in zip(a, tiles, strict=True))
    assert all(
        t.color == tuple(t.base_color) for t in jitter_colors(tiles, 0.0, np.random.default_rng())
    )


def test_layout_is_seeded_and_non_overlapping() -> None:
    radii = np.random.default_rng(0).uniform(0.01, 0.02, 25)
    a = sample_layout(radii, (0.3, 0.26), 0.006, 400, np.random.default_rng(7))
    b = sample_layout(radii, (0.3, 0.26), 0.006, 400, np.random.default_rng(7))
    assert np.array_equal(a, b)
    d = np.linalg.norm(a[:, None, :2] - a[None, :, :2], axis=2)
    need = radii[:, None] + radii[None, :] + 0.006
    np.fill_diagonal(d, np.inf)
    assert np.all(d >= need)
    assert np.all(np.abs(a[:, 0]) + radii <= 0.15 + 1e-12)
    assert np.all(np.abs(a[:, 1]) + radii <= 0.13 + 1e-12)


def test_cell_reset_is_deterministic() -> None:
    c1, c2 = Cell(None, SHAPES, seed=4), Cell(None, SHAPES, seed=4)
    try:
        assert np.array_equal(c1.tile_poses().pos, c2.tile_poses().pos)
        c1.reset(seed=9)
        c2.reset(seed=9)
        assert np.array_equal(c1.tile_poses().pos, c2.tile_poses().pos)
        c1.step(50)
        c2.step(50)
        assert np.array_equal(c1.data.qpos, c2.data.qpos)
    finally:
        c1.close()
        c2.close()


def test_exact_layout_packs_40_tiles_without_overlap() -> None:
    tiles = make_tiles((SHAPES * 6)[:40], TileConfig(), np.random.default_rng(0))
    outlines = [t.outline for t in tiles]
    radii = np.array([t.radius for t in tiles])
    poses = sample_layout(
        radii, (0.3, 0.26), 0.004, 400, np.random.default_rng(2), outlines=outlines
    )
    polys = []
    for o, (x, y, yaw) in zip(outlines, poses, strict=True):
        c, s = np.cos(yaw), np.sin(yaw)
        polys.append(Polygon(o @ np.array([[c, s], [-s, c]]) + [x, y]))
    for a in range(len(polys)):
        x0, y0, x1, y1 = polys[a].bounds
        assert -0.15 <= x0 and x1 <= 0.15 and -0.13 <= y0 and y1 <= 0.13
        for b in range(a):
            assert polys[a].distance(polys[b]) >= 0.004 - 1e-12


@pytest.mark.parametrize("kind", ["", "broken", "shape"])
def test_noisy_tiles_always_mesh(kind: str) -> None:
    """Jitter on a short edge (a ring broken next to its hole) must never fold the outline."""
    cfg = load_cell_config().tiles
    for shape in basic_shapes():
        for seed in range(40 if shape.name == "ring" else 8):
            tile = make_tile(shape, cfg, np.random.default_rng(seed), kind)
            assert Polygon(tile.outline, tile.holes).is_valid, (shape.name, seed)
            verts, faces = extrusion(tile.outline, tile.holes, 0.0, cfg.thickness)
            assert len(faces) > 0 and np.isfinite(verts).all()


def test_tiles_with_variants_fall_asleep_like_plain_tiles() -> None:
    """A tile dropped 3 mm onto the belt sleeps as soon with 4 variants as with one.

    (With its shapes in child bodies MuJoCo measured the tile's rotational dof length to the
    world origin, ~6 m, and a tile needed to be ~200x stiller to sleep.)
    """
    steps = {}
    for variants in (1, 4):
        cfg = load_cell_config(tiles={"variants": variants})
        cell = Cell(cfg, basic_shapes(), seed=2)
        try:
            m, d = cell.model, cell.data
            lengths = m.dof_length[cell.ids.tile_dof_index[:, 3:]]
            assert np.all(lengths < 0.1), "rotational dof lengths: the tile's size [m]"
            counts = []
            for i in range(len(cell.tiles)):
                d.qpos[cell.ids.tile_qpos_index[i, 2]] += 0.003
                cell._wake[i] = True
                tree = m.body_treeid[cell.ids.tile_body[i]]
                n = 0
                while d.tree_asleep[tree] < 0 and n < 1000:
                    cell.step(1)
                    n += 1
                counts.append(n)
            steps[variants] = np.array(counts)
        finally:
            cell.close()
    assert np.all(steps[1] < 200)
    assert np.all(steps[4] < 2 * steps[1] + 20)


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
