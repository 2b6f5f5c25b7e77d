"""Contract tests of the decision-level index maps (`envs.indexing`) on the cell of
``MosaicDecision6-v1`` (6 tiles of symmetry 4, 4, 2, round, 1, 1).

Each test resets the cell, lays the tiles where it needs them (`Cell.place_tiles`, exact
positions and yaws relative to the tile area's centre) and builds the `IndexMaps` it checks
with the orders it checks, so every expected index is worked out by hand. Each names the bug
it guards against.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest

import envs
from envs.indexing import IndexMaps, raster_order
from tests.presets import FAST_DISCRETE

N = 6
"""Tiles and slots of the cell."""
LAYOUT = np.array([[-0.1, 0.05], [0.1, -0.05], [0.1, 0.05], [0.0, 0.0], [-0.1, -0.05], [0.0, 0.05]])
"""Tile (x, y) relative to the tile area's centre [m]: belt order (largest x first, then
smallest y) 1, 2, 3, 5, 4, 0."""
BELT_ORDER = [1, 2, 3, 5, 4, 0]


@pytest.fixture
def cell(decision6_env):
    """The cell reset with seed 0, its tiles laid out as `LAYOUT` at yaw 0."""
    decision6_env.reset(seed=0)
    c = decision6_env.unwrapped.cell
    c.place_tiles(np.arange(N), np.column_stack([LAYOUT, np.zeros(N)]))
    return c


def _maps(env, cell, **orders: object) -> IndexMaps:
    return IndexMaps(cell, dataclasses.replace(env.unwrapped.config, **orders))


def _turn_tiles(cell, offsets: dict[int, float]) -> None:
    """Lay tile i at its slot's yaw plus ``offsets[i]`` [rad] (the others at yaw 0)."""
    yaw = np.zeros(N)
    slot_yaw = cell.slot_poses_world()[:, 2]
    for i, d in offsets.items():
        yaw[i] = slot_yaw[i] + d
    cell.place_tiles(np.arange(N), np.column_stack([LAYOUT, yaw]))


def test_raster_order_is_rows_from_the_top_then_left_to_right() -> None:
    """Rows by y descending (y rounded to the millimetre), each row by x ascending.

    Guards against rows ascending, x descending or y compared unrounded.
    """
    xy = np.array([[0.1, 0.0], [0.0, 0.0], [0.05, 0.1], [0.2, 0.1004], [0.0, 0.0996]])
    order = raster_order(xy)
    assert order.tolist() == [4, 2, 3, 1, 0]
    assert order.dtype.kind == "i"


def test_before_the_first_reset_the_maps_are_the_identity(decision6_env, cell) -> None:
    """A new IndexMaps names tile i and slot k as the cell's i and k.

    Guards against an uninitialised or shuffled first map.
    """
    maps = _maps(decision6_env, cell, tile_order="shuffled", slot_order="shuffled")
    assert maps.tiles.tolist() == list(range(N))
    assert maps.slots.tolist() == list(range(N))


def test_shuffled_orders_are_the_generators_permutations_tiles_first(decision6_env, cell) -> None:
    """tile_order and slot_order ``shuffled``: the tile permutation is drawn first, then the
    slot one, from the generator reset gets.

    Guards against another draw order, an unshuffled map, or one map's draw used twice.
    """
    maps = _maps(decision6_env, cell, tile_order="shuffled", slot_order="shuffled")
    maps.reset(np.random.default_rng(11))
    rng = np.random.default_rng(11)
    tiles, slots = rng.permutation(N), rng.permutation(N)
    assert maps.tiles.tolist() == tiles.tolist()
    assert maps.slots.tolist() == slots.tolist()
    assert tiles.tolist() != slots.tolist() != list(range(N))
    cell.park_tiles(np.array([0]))  # the shuffled order does not follow the belt
    maps.update()
    assert maps.tiles.tolist() == tiles.tolist()


def test_design_orders_are_the_identity_after_a_reset(decision6_env, cell) -> None:
    """tile_order and slot_order ``design``: index i is the cell's i, whatever the generator.

    Guards against a design order shuffled or following the belt.
    """
    maps = _maps(decision6_env, cell, tile_order="design", slot_order="design")
    maps.reset(np.random.default_rng(3))
    assert maps.tiles.tolist() == list(range(N))
    assert maps.slots.tolist() == list(range(N))
    maps.update()
    assert maps.tiles.tolist() == list(range(N))


@pytest.fixture(scope="module")
def grid_env() -> Iterator[gym.Env]:
    """The first 6 slots of square_grid: its design order is not the raster order on the mesh."""
    env = gym.make(envs.ENV_ID, **{**FAST_DISCRETE, "design": "square_grid", "max_slots": N})
    env.reset(seed=0)
    try:
        yield env
    finally:
        env.close()


def test_mesh_slot_order_is_the_raster_order_of_the_slots(grid_env) -> None:
    """slot_order ``mesh``: the raster order of the slots' world (x, y), the same every reset,
    on a design whose own slot order is another.

    Guards against the mesh order replaced by the design order or a draw.
    """
    cell = grid_env.unwrapped.cell
    maps = IndexMaps(cell, dataclasses.replace(grid_env.unwrapped.config, slot_order="mesh"))
    want = raster_order(cell.slot_poses_world()[:, :2]).tolist()
    assert want != list(range(N))
    for seed in (0, 1):
        maps.reset(np.random.default_rng(seed))
        assert maps.slots.tolist() == want
    design = IndexMaps(cell, dataclasses.replace(grid_env.unwrapped.config, slot_order="design"))
    design.reset(np.random.default_rng(0))
    assert design.slots.tolist() == list(range(N))


def test_belt_order_before_the_first_reset_keeps_the_rest_in_design_order(
    decision6_env, cell
) -> None:
    """update before any reset: tiles on the belt in belt order, the others after them in
    design order (no draw yet).

    Guards against a first map that cannot be updated before a reset.
    """
    maps = _maps(decision6_env, cell, tile_order="belt")
    cell.park_tiles(np.array([3, 0]))
    maps.update()
    assert maps.tiles.tolist() == [1, 2, 5, 4, 0, 3]


def test_belt_order_counts_from_the_downstream_end_then_the_rest_shuffled(
    decision6_env, cell
) -> None:
    """tile_order ``belt``: tiles on the input belt by x descending then y ascending; tiles off
    it after them, in the order the reset drew; recomputed by update.

    Guards against x ascending, y descending, the rest in design order, or no update.
    """
    maps = _maps(decision6_env, cell, tile_order="belt")
    maps.reset(np.random.default_rng(5))
    assert maps.tiles.tolist() == BELT_ORDER
    cell.park_tiles(np.array([2, 3, 0]))
    maps.update()
    rest = [int(i) for i in np.random.default_rng(5).permutation(N) if i in (0, 2, 3)]
    assert maps.tiles.tolist() == [1, 5, 4, *rest]
    assert rest != [0, 2, 3]  # the draw differs from the design order
    assert maps.tiles.dtype.kind == "i"


@pytest.mark.parametrize(
    "case",
    [
        # tile: the nearest slot-aligned pose over a full turn, whatever the shape
        ("tile", 4, {0: math.pi / 2 + 0.1, 3: math.pi + 0.1, 4: -math.pi / 2 - 0.1}, [1, 2, 3]),
        # shape: the offset taken modulo the figure's period (square: quarter turn; round: 0)
        ("shape", 4, {0: math.pi / 2 + 0.1, 3: math.pi + 0.1, 4: -math.pi / 2 - 0.1}, [0, 0, 3]),
        ("tile", 8, {2: 3 * math.pi / 4 + 0.05}, [3]),
        ("shape", 8, {2: 3 * math.pi / 4 + 0.05}, [7]),  # half-turn symmetry: -pi / 4
    ],
)
def test_rotation_zero_is_the_nearest_slot_aligned_pose_of_the_frame(
    decision6_env, cell, case: tuple[str, int, dict[int, float], list[int]]
) -> None:
    """decode(i, i, r) turns r steps from the frame's zero: under ``tile`` the slot-aligned pose
    nearest the tile's yaw, under ``shape`` the same modulo the figure's symmetry (a round
    tile's zero is its slot's yaw); encode is the inverse.

    Guards against the shape frame treated as the tile frame, the symmetry ignored, a round
    tile's period used as a divisor, or the steps counted the wrong way.
    """
    frame, bins, offsets, bases = case
    _turn_tiles(cell, offsets)
    maps = _maps(
        decision6_env,
        cell,
        tile_order="design",
        slot_order="design",
        rotation_frame=frame,
        rotation_bins=bins,
    )
    maps.reset(np.random.default_rng(0))
    for i, base in zip(offsets, bases, strict=True):
        for r in range(bins):
            got = maps.decode(np.array([i, i, r]))
            assert got.tolist() == [i, i, (r + base) % bins], (i, r)
            assert got.dtype == np.int64
            assert maps.encode(i, i, (r + base) % bins).tolist() == [i, i, r]


def test_slot_frame_counts_from_the_slots_yaw(decision6_env, cell) -> None:
    """rotation_frame ``slot``: rotation r is r steps from the slot's yaw, however the tile lies.

    Guards against the tile's yaw added in the slot frame.
    """
    _turn_tiles(cell, {0: math.pi / 2 + 0.1})
    maps = _maps(
        decision6_env, cell, tile_order="design", slot_order="design", rotation_frame="slot"
    )
    maps.reset(np.random.default_rng(0))
    assert maps.decode(np.array([0, 0, 3])).tolist() == [0, 0, 3]
    assert maps.encode(0, 0, 3).tolist() == [0, 0, 3]
    assert maps.encode(0, 0).tolist() == [0, 0, 0]


def test_decode_and_encode_go_through_the_maps(decision6_env, cell) -> None:
    """Agent (tile, slot) indices are looked up in the maps; encode finds them again.

    Guards against an index used directly, or tile and slot maps mixed up.
    """
    maps = _maps(
        decision6_env, cell, tile_order="shuffled", slot_order="shuffled", rotation_frame="slot"
    )
    maps.reset(np.random.default_rng(11))
    for a in ([0, 1, 2], [5, 0, 1], [3, 4, 0]):
        t, s = int(maps.tiles[a[0]]), int(maps.slots[a[1]])
        assert maps.decode(np.array(a)).tolist() == [t, s, a[2]]
        assert maps.encode(t, s, a[2]).tolist() == a
    out = maps.encode(int(maps.tiles[2]), int(maps.slots[3]), 1)
    assert out.dtype == np.int64 and out.tolist() == [2, 3, 1]


def test_permute_state_puts_flat_rows_in_agent_order(decision6_env, cell) -> None:
    """Flat ``state`` rows (n * d,) and (k * e,): row i of the result is the cell's row
    ``tiles[i]`` (``slots[i]``); the input is not changed.

    Guards against the rows not permuted, permuted by the wrong map or flattened wrongly.
    """
    maps = _maps(decision6_env, cell, tile_order="shuffled", slot_order="shuffled")
    maps.reset(np.random.default_rng(11))
    tiles = np.arange(N * 3, dtype=float)  # row i: 3i, 3i + 1, 3i + 2
    slots = np.arange(N * 2, dtype=float) + 100
    t, s = maps.permute_state(tiles.copy(), slots.copy())
    assert t.shape == (N * 3,) and s.shape == (N * 2,)
    np.testing.assert_array_equal(t.reshape(N, 3), tiles.reshape(N, 3)[maps.tiles])
    np.testing.assert_array_equal(s.reshape(N, 2), slots.reshape(N, 2)[maps.slots])
    assert t[:3].tolist() == [3 * maps.tiles[0], 3 * maps.tiles[0] + 1, 3 * maps.tiles[0] + 2]


def test_permute_state_keeps_the_padding_of_objects_rows(decision6_env, cell) -> None:
    """``objects`` rows (rows, D): the first n (k) rows permuted in place, padding rows kept.

    Guards against the padding permuted or dropped, or the arrays flattened.
    """
    maps = _maps(decision6_env, cell, tile_order="shuffled", slot_order="shuffled")
    maps.reset(np.random.default_rng(11))
    tiles = np.arange(8 * 2, dtype=float).reshape(8, 2)  # 6 tiles + 2 padding rows
    slots = -np.arange(7 * 3, dtype=float).reshape(7, 3)
    want_t = np.concatenate([tiles[:N][maps.tiles], tiles[N:]])
    want_s = np.concatenate([slots[:N][maps.slots], slots[N:]])
    t, s = maps.permute_state(tiles, slots)
    assert t is tiles and s is slots  # in place
    np.testing.assert_array_equal(t, want_t)
    np.testing.assert_array_equal(s, want_s)
