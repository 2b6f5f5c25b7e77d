"""The ``objects`` observation: entity rows without class ids (`envs.observations.objects`)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest
from shapely.geometry import LinearRing, Point, Polygon

import envs  # noqa: F401 - registers the ids
from envs.cell.cell import Cell
from envs.cell.tiles.tile import SlotSpec, TileShape
from envs.env_config import EnvConfigError, load_env_config
from envs.observations.objects import (
    OBJECT_DIM,
    OBJECT_FIELDS,
    OVERSAMPLE,
    ObjectRows,
    as_xy,
    entity_geometry,
    object_fields,
    oriented_points,
)
from envs.observations.spaces import Observer
from envs.task import MosaicTask

F = OBJECT_FIELDS
SEED = 3
ON_OUTLINE_MM = 1e-3
"""Points lie on the built outline within this [mm] (float32 rows)."""


@pytest.fixture(scope="module")
def env() -> Iterator[gym.Env]:
    e = gym.make("MosaicDecision6-v0", obs_mode="objects")
    yield e
    e.close()


def _points(row: np.ndarray, fields: dict[str, slice] = F) -> np.ndarray:
    return row[fields["points"]].reshape(-1, 2).astype(float)


def _turn(p: np.ndarray, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return p @ np.array([[c, s], [-s, c]])


def test_layout_is_a_table_of_named_slices() -> None:
    assert OBJECT_DIM == 75
    assert F["rgb"] == slice(0, 3) and F["valid"] == slice(10, 11)
    assert F["points"] == slice(11, 75)
    assert object_fields(8)["points"] == slice(11, 27)
    covered = sorted(i for s in F.values() for i in range(s.start, s.stop))
    assert covered == list(range(OBJECT_DIM))  # no gap, no overlap


def test_space_shape_dtype_and_rows_follow_the_action_indices(env: gym.Env) -> None:
    obs, _ = env.reset(seed=SEED)
    space = env.observation_space
    assert set(space.spaces) == {"robot", "tiles", "slots"}
    for key in ("tiles", "slots"):
        assert space[key].shape == (6, OBJECT_DIM) and space[key].dtype == np.float32
        assert obs[key].shape == (6, OBJECT_DIM) and obs[key].dtype == np.float32
    assert space.contains(obs)
    u = env.unwrapped
    pos = u.cell.tile_poses().pos[:, :2]
    np.testing.assert_allclose(obs["tiles"][:, F["xy"]], pos[u.index.tiles], atol=1e-6)
    slots = u.cell.slot_poses_world()[:, :2]
    np.testing.assert_allclose(obs["slots"][:, F["xy"]], slots[u.index.slots], atol=1e-6)
    np.testing.assert_array_equal(obs["tiles"][:, F["flag"]].ravel(), u.cell.input_half())
    assert np.all(obs["tiles"][:, F["valid"]] == 1)


def test_points_lie_on_the_turned_outline_and_start_at_the_smallest_polar_angle() -> None:
    rect = np.array([[-20.0, -10.0], [20.0, -10.0], [20.0, 10.0], [-20.0, 10.0]]) / 1000
    geometry = entity_geometry([rect], [[]], [(0.5, 0.5, 0.5)], 16)
    samples = geometry.fine[0, : OVERSAMPLE * 16]
    ring = LinearRing(rect * 1000)
    for yaw in (0.0, 0.3, math.pi / 2, 2.0, -2.5, 7.0):
        turn = np.exp(1j * np.array([yaw]))
        z = oriented_points(geometry, turn, np.array([yaw]), 16)[0]
        pts = as_xy(z[None])[0].reshape(-1, 2)
        back = _turn(pts, -yaw)  # into the body frame
        assert max(ring.distance(Point(p)) for p in back) < 1e-9
        angles = np.angle(samples * turn) % (2 * math.pi)
        assert np.angle(z[0]) % (2 * math.pi) == pytest.approx(angles.min(), abs=1e-12)
        steps = np.linalg.norm(np.diff(np.vstack([pts, pts[:1]]), axis=0), axis=1)
        assert np.all(steps <= ring.length / 16 + 1e-9)  # equal arc length (chords <= arcs)
        nxt = np.roll(pts, -1, axis=0)
        assert np.sum(pts[:, 0] * nxt[:, 1] - pts[:, 1] * nxt[:, 0]) > 0  # counter-clockwise
    # a half turn of a rectangle shows the same points (start included)
    half, none = (
        oriented_points(geometry, np.exp(1j * np.array([y])), np.array([y]), 16)
        for y in (math.pi, 0.0)
    )
    np.testing.assert_allclose(as_xy(half), as_xy(none), atol=1e-9)


def test_turning_a_tile_turns_its_points(env: gym.Env) -> None:
    env.reset(seed=SEED)
    u = env.unwrapped
    rng = np.random.default_rng(0)
    rows = []
    for yaw in (0.0, 0.7):
        u.cell.place_tiles(np.array([0]), np.array([[0.0, 0.0, yaw]]))
        obs_tiles, _ = u.observer.objects.observe(rng, u.task.evaluate())  # cell order
        rows.append(obs_tiles[0].astype(float))
    assert rows[1][F["yaw"]] == pytest.approx([math.cos(0.7), math.sin(0.7)], abs=1e-6)
    ring = LinearRing(u.cell.tiles[0].outline * 1000.0)  # body frame, about the centroid [mm]
    for yaw, row in zip((0.0, 0.7), rows, strict=True):
        assert max(ring.distance(Point(p)) for p in _turn(_points(row), -yaw)) < ON_OUTLINE_MM
    assert not np.allclose(_points(rows[0]), _points(rows[1]), atol=1.0)
    np.testing.assert_allclose(_points(rows[1]).mean(axis=0), 0.0, atol=1.0)  # about centroid


def test_padded_rows_are_zero_and_invalid() -> None:
    e = gym.make("MosaicDecision6-v0", obs_mode="objects", objects_rows=10)
    obs, _ = e.reset(seed=SEED)
    assert e.observation_space["tiles"].shape == (10, OBJECT_DIM)
    u = e.unwrapped
    tile, slot = next(i for i in range(6) if u.cell.input_half()[i]), 0
    obs, *_ = e.step(u.expert_action(tile, slot))
    for key in ("tiles", "slots"):
        assert obs[key].shape == (10, OBJECT_DIM)
        np.testing.assert_array_equal(obs[key][:, F["valid"]].ravel(), [1] * 6 + [0] * 4)
        assert not obs[key][6:].any()
        assert np.all(obs[key][:6, F["area"]] > 0)
    assert e.observation_space.contains(obs)
    e.close()


@pytest.mark.parametrize(
    ("key", "value", "allowed"),
    [
        ("objects_points", 4, "[8, 256]"),
        ("objects_points", 300, "[8, 256]"),
        ("objects_noise_mm", -0.1, ">= 0"),
        ("objects_source", "camera", "perception"),
        ("objects_rows", 0, ">= 1"),
        ("obs_mode", "entities", "objects"),
    ],
)
def test_bad_options_are_typed_errors_naming_what_is_allowed(
    key: str, value: object, allowed: str
) -> None:
    with pytest.raises(EnvConfigError, match=key) as err:
        load_env_config(**{"obs_mode": "objects", key: value})
    assert allowed in str(err.value)


def test_too_few_rows_for_the_episode_is_an_error() -> None:
    with pytest.raises(EnvConfigError, match=r"objects_rows 3 .*>= 6"):
        gym.make("MosaicDecision6-v0", obs_mode="objects", objects_rows=3)


def test_no_class_id_equal_shapes_and_colours_give_equal_rows() -> None:
    """Two classes of the same shape and colour: rows equal apart from pose (and flags)."""
    cfg = load_env_config(
        obs_mode="objects", vertex_jitter=0.0, tile_color_jitter=0.0, tile_variants=1
    )
    outline = np.array([[0.0, 0.0], [0.04, 0.0], [0.04, 0.02], [0.01, 0.03]])
    a = TileShape(outline, color=(0.2, 0.5, 0.7), name="a")
    b = TileShape(outline, color=(0.2, 0.5, 0.7), name="b")
    slots = (SlotSpec(a, (-0.05, 0.0, 0.4)), SlotSpec(b, (0.05, 0.0, 0.4)))
    cell = Cell(cfg.cell, (a, b), slots, seed=SEED)
    task = MosaicTask(cell, cfg)
    assert list(task.tile_class) == [0, 1] and list(task.slot_class) == [0, 1]
    obs = Observer(cell, task, cfg).observe(np.random.default_rng(0), task.evaluate())
    tiles, slot_rows = obs["tiles"], obs["slots"]
    shape_cols = [F["rgb"], F["area"], F["hole_area"], F["points"]]
    for col in shape_cols:
        np.testing.assert_array_equal(slot_rows[0, col], slot_rows[1, col])
    for col in (F["rgb"], F["area"], F["hole_area"]):
        np.testing.assert_allclose(tiles[0, col], tiles[1, col], rtol=1e-6)
    yaw = np.arctan2(tiles[:, F["yaw"].start + 1], tiles[:, F["yaw"].start])
    ring = LinearRing(cell.tiles[0].outline * 1000.0)  # about the centroid [mm]
    for i in range(2):  # both rows: the same outline, turned as each tile lies
        body = _turn(_points(tiles[i]), -float(yaw[i]))
        assert max(ring.distance(Point(p)) for p in body) < ON_OUTLINE_MM


@pytest.mark.parametrize("task_id", ["MosaicDecision6-v0", "MosaicDecision16-v0"])
def test_no_column_equals_the_class_index(task_id: str) -> None:
    e = gym.make(task_id, obs_mode="objects")
    obs, _ = e.reset(seed=SEED)
    u = e.unwrapped
    tile_class = u.task.tile_class[u.index.tiles]
    slot_class = u.task.slot_class[u.index.slots]
    for rows, classes in ((obs["tiles"], tile_class), (obs["slots"], slot_class)):
        for col in range(rows.shape[1]):
            assert not np.array_equal(rows[:, col], classes.astype(np.float32)), col
    e.close()


def test_a_privileged_step_fills_a_slot_and_its_flag_turns_one(env: gym.Env) -> None:
    obs, _ = env.reset(seed=SEED)
    u = env.unwrapped
    assert not obs["slots"][:, F["flag"]].any()
    tile = next(i for i in range(6) if u.cell.input_half()[i])
    action = u.expert_action(tile, tile)  # cell tile i is made for design slot i
    obs, reward, *_ = env.step(action)
    assert reward > 0
    row = int(action[1])
    assert obs["slots"][row, F["flag"].start] == 1
    assert obs["slots"][:, F["flag"]].sum() == 1
    assert obs["tiles"][:, F["flag"]].sum() == 5  # the placed tile left the input belt


def test_outline_noise_is_seeded_and_only_on_tiles() -> None:
    def rows(noise: float) -> dict[str, np.ndarray]:
        e = gym.make("MosaicDecision6-v0", obs_mode="objects", objects_noise_mm=noise)
        obs, _ = e.reset(seed=SEED)
        e.close()
        return obs

    clean, noisy, again = rows(0.0), rows(0.5), rows(0.5)
    np.testing.assert_array_equal(noisy["tiles"], again["tiles"])
    np.testing.assert_array_equal(noisy["slots"], clean["slots"])
    d = noisy["tiles"][:, F["points"]] - clean["tiles"][:, F["points"]]
    assert 0.3 < float(np.std(d)) < 0.7
    np.testing.assert_array_equal(
        noisy["tiles"][:, : F["points"].start], clean["tiles"][:, : F["points"].start]
    )


def test_objects_keys_leave_the_state_observation_alone() -> None:
    actions = [np.array([0, 1, 2]), np.array([1, 0, 0]), np.array([0, 3, 1])]

    def rollout(**kw: object) -> list[np.ndarray]:
        e = gym.make("MosaicDecision6-v0", **kw)
        obs, _ = e.reset(seed=SEED)
        out = [obs["tiles"], obs["slots"], obs["robot"]]
        for a in actions:
            obs, *_ = e.step(a)
            out += [obs["tiles"], obs["slots"], obs["robot"]]
        e.close()
        return out

    changed = rollout(objects_noise_mm=1.0, objects_points=64, objects_rows=9)
    for a, b in zip(rollout(), changed, strict=True):
        np.testing.assert_array_equal(a, b)


KNOWN_AREAS_CM2 = {
    "square": 40.0 * 40.0 / 100,  # paper_mixed: 40 mm squares
    "rect": 48.0 * 24.0 / 100,  # 48 x 24 mm
    "circle": math.pi * 21.0**2 / 100,  # radius 21 mm (the built outline is a polygon)
    "right": 46.0 * 34.0 / 200,  # right triangle 46 x 34 mm
    "iso": 44.0 * 40.0 / 200,  # isosceles triangle, base 44 mm, height 40 mm
}


def test_area_is_in_square_centimetres_for_known_tiles(env: gym.Env) -> None:
    """Guards against the area changing unit (mm^2, m^2) unnoticed: the first six slots of
    paper_mixed are two 40 mm squares (16 cm^2), a 48 x 24 mm rectangle, a 21 mm disc, a
    46 x 34 mm right triangle and a 44 x 40 mm isosceles triangle; no holes."""
    obs, _ = env.reset(seed=SEED)
    u = env.unwrapped
    expected = [KNOWN_AREAS_CM2[k] for k in ("square", "square", "rect", "circle", "right", "iso")]
    cell_slots = np.empty(6)
    cell_slots[u.index.slots] = obs["slots"][:, F["area"]].ravel()
    np.testing.assert_allclose(cell_slots, expected, rtol=0.005)
    assert np.all(obs["slots"][:, F["hole_area"]] == 0.0)
    # tiles: the built outlines carry 0.2 mm noise, within 3 % of their class's slot
    by_class = {s.shape.name: a for s, a in zip(u.cell.slots, expected, strict=True)}
    tile_area = np.empty(6)
    tile_area[u.index.tiles] = obs["tiles"][:, F["area"]].ravel()
    for t, a in zip(u.cell.tiles, tile_area, strict=True):
        assert a == pytest.approx(by_class[t.shape.name], rel=0.03)


def test_hole_area_is_subtracted_and_reported_in_square_centimetres() -> None:
    """Guards against the hole area in another unit or not subtracted from the area."""
    square = np.array([[0.0, 0.0], [0.04, 0.0], [0.04, 0.04], [0.0, 0.04]])
    hole = np.array([[0.01, 0.01], [0.02, 0.01], [0.02, 0.02], [0.01, 0.02]])
    g = entity_geometry([square], [[hole]], [(0.2, 0.4, 0.6)], 8)
    assert g.area[0] == pytest.approx(16.0 - 1.0)
    assert g.hole_area[0] == pytest.approx(1.0)
    np.testing.assert_allclose(g.rgb, [[0.2, 0.4, 0.6]])
    # points about the area centroid of the outline with its hole (off-centre hole: shifted)
    pts = as_xy(oriented_points(g, np.ones(1, complex), np.zeros(1), 8))[0].reshape(-1, 2)
    c = np.array([20.0, 20.0]) - (np.array([15.0, 15.0]) - 20.0) * 1.0 / 15.0  # [mm]
    assert pts.min(axis=0) == pytest.approx(-c, abs=1e-9)
    assert pts.max(axis=0) == pytest.approx(40.0 - c, abs=1e-9)


def test_slot_rows_hold_the_slot_pose_and_filled_flag(env: gym.Env) -> None:
    """Guards against the slot rows' xy [m], yaw (cos, sin) or filled flag taken from the wrong
    column or frame, and tile rows' yaw not being the tile's world yaw."""
    obs, _ = env.reset(seed=SEED)
    u = env.unwrapped
    xyyaw = u.task.slot_xyyaw[u.index.slots]
    np.testing.assert_allclose(obs["slots"][:, F["xy"]], xyyaw[:, :2], atol=1e-6)
    np.testing.assert_allclose(
        obs["slots"][:, F["yaw"]],
        np.column_stack([np.cos(xyyaw[:, 2]), np.sin(xyyaw[:, 2])]),
        atol=1e-6,
    )
    assert not obs["slots"][:, F["flag"]].any()
    yaw = u.cell.tile_poses().yaw[u.index.tiles]
    np.testing.assert_allclose(
        obs["tiles"][:, F["yaw"]], np.column_stack([np.cos(yaw), np.sin(yaw)]), atol=1e-6
    )
    colours = np.array([t.color for t in u.cell.tiles])[u.index.tiles]
    np.testing.assert_allclose(obs["tiles"][:, F["rgb"]], colours, atol=1e-6)
    # a tile set into its slot: the slot's flag turns 1, the tile's (pickable) 0
    obs, _, _, _, info = env.step(u.expert_action(0, 0))
    filled = np.asarray(info["evaluation"]["slot_filled"], float)[u.index.slots]
    assert filled.sum() == 1
    np.testing.assert_array_equal(obs["slots"][:, F["flag"]].ravel(), filled)
    np.testing.assert_array_equal(
        obs["tiles"][:, F["flag"]].ravel(), u.cell.input_half()[u.index.tiles]
    )
    assert obs["tiles"][:, F["flag"]].sum() == 5


def test_fresh_slot_rows_hold_the_slot_yaw_and_its_turned_outline(env: gym.Env) -> None:
    """Guards against the slot rows' (cos, sin) or points turned by another angle than the slot's
    yaw (e.g. twice it) when the rows are built for a design: rows built afresh from the cell
    and task hold (cos, sin) of each slot's yaw and its outline turned by that yaw."""
    env.reset(seed=SEED)
    u = env.unwrapped
    rows = ObjectRows(u.cell, u.task, u.config)
    _, slots = rows.observe(np.random.default_rng(0), u.task.evaluate())  # cell order
    yaw = u.task.slot_xyyaw[:, 2]
    assert len(set(np.round(np.mod(yaw, 2 * np.pi), 3))) > 1  # not all one yaw
    np.testing.assert_allclose(
        slots[:, F["yaw"]], np.column_stack([np.cos(yaw), np.sin(yaw)]), atol=1e-6
    )
    for j, slot in enumerate(u.cell.slots):
        outline = slot.shape.outline - np.asarray(Polygon(slot.shape.outline).centroid.coords[0])
        ring = LinearRing(_turn(outline * 1000.0, yaw[j]))  # world-oriented, about the centroid
        assert max(ring.distance(Point(p)) for p in _points(slots[j])) < ON_OUTLINE_MM


def test_outline_noise_adds_the_generator_s_normal_draws_and_only_when_asked(
    env: gym.Env,
) -> None:
    """Guards against the noise subtracted, drawn with a non-zero mean, or drawn at all when
    ``objects_noise_mm`` is 0 (the env's generator must not move then): the noisy points are the
    clean ones plus ``normal(0, noise, shape)`` from the same seed."""
    env.reset(seed=SEED)
    u = env.unwrapped
    ev = u.task.evaluate()
    clean_rows = ObjectRows(u.cell, u.task, u.config)
    rng = np.random.default_rng(7)
    clean, _ = clean_rows.observe(rng, ev)
    assert rng.random() == np.random.default_rng(7).random()  # nothing drawn at 0 mm
    noisy_rows = ObjectRows(u.cell, u.task, dataclasses.replace(u.config, objects_noise_mm=0.5))
    noisy, _ = noisy_rows.observe(np.random.default_rng(7), ev)
    n = len(u.cell.tiles)
    draws = np.random.default_rng(7).normal(0.0, 0.5, (n, 2 * noisy_rows.points))
    expected = clean[:n, F["points"]].astype(float) + draws
    np.testing.assert_allclose(noisy[:n, F["points"]], expected, atol=1e-4)


def test_the_start_point_is_the_smallest_polar_angle_at_every_yaw_of_a_turn() -> None:
    """Guards against the sorted body angles' wrap-around entry off (not the smallest angle
    plus a full turn, another entry shifted, or the wrong sample appended): at 4096 yaws over a
    turn (steps of 0.09 deg, finer than the 0.7 deg between samples, so the world +x ray also
    falls between the body's last and first sample) the first point is the sample of smallest
    world polar angle, for a rectangle and a disc."""
    rect = np.array([[-20.0, -10.0], [20.0, -10.0], [20.0, 10.0], [-20.0, 10.0]]) / 1000
    k = np.arange(40) + 0.3  # no vertex on the body's +x axis
    disc = 0.021 * np.column_stack([np.cos(2 * np.pi * k / 40), np.sin(2 * np.pi * k / 40)])
    geometry = entity_geometry([rect, disc], [[], []], [(0.5, 0.5, 0.5)] * 2, 32)
    count = OVERSAMPLE * 32
    samples = geometry.fine[:, :count]
    for yaw in np.linspace(0.0, 2 * math.pi, 4096, endpoint=False) + 1e-4:  # no sample on the ray
        yaws = np.array([yaw, -yaw])
        turn = np.exp(1j * yaws)
        first = oriented_points(geometry, turn, yaws, 32)[:, 0]
        smallest = np.argmin(np.angle(samples * turn[:, None]) % (2 * math.pi), axis=1)
        np.testing.assert_allclose(first, samples[[0, 1], smallest] * turn, atol=1e-12)


def test_exactly_as_many_rows_as_the_episode_needs_are_accepted(env: gym.Env) -> None:
    """Guards against ``objects_rows`` equal to the episode's larger count refused (the allowed
    values are None or an int >= max(tiles, slots)): 6 rows for 6 tiles and 6 slots build rows
    with no padding, 5 are refused."""
    env.reset(seed=SEED)
    u = env.unwrapped
    assert len(u.cell.tiles) == len(u.cell.slots) == 6
    rows = ObjectRows(u.cell, u.task, dataclasses.replace(u.config, objects_rows=6))
    tiles, slots = rows.observe(np.random.default_rng(0), u.task.evaluate())
    assert tiles.shape == slots.shape == (6, OBJECT_DIM)
    assert np.all(tiles[:, F["valid"]] == 1) and np.all(slots[:, F["valid"]] == 1)
    with pytest.raises(EnvConfigError, match=r"objects_rows 5 .*>= 6"):
        ObjectRows(u.cell, u.task, dataclasses.replace(u.config, objects_rows=5))
