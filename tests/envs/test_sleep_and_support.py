"""Physics that simulates only what moves: tiles start asleep, rest on one support hull, and a
kinematic place sets the tile down."""

from __future__ import annotations

from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.scene import SUPPORT_CONTYPE
from envs.cell.tiles.shapes import basic_shapes
from envs.mosaic_env import MosaicAssemblyEnv

SHAPES = basic_shapes()
RING = [s.name for s in SHAPES].index("ring")
SQUARE = [s.name for s in SHAPES].index("square")


@pytest.fixture
def cell() -> Iterator[Cell]:
    c = Cell(None, SHAPES, seed=3)
    try:
        yield c
    finally:
        c.close()


def _trees(cell: Cell) -> np.ndarray:
    return cell.model.body_treeid[cell.ids.tile_body]


def _world_contacts(cell: Cell, tile: int) -> np.ndarray:
    """Geoms of ``tile`` in contact with a world geom (belts, sheet, floor) now."""
    m, d = cell.model, cell.data
    g = d.contact.geom[: d.ncon]
    body = m.geom_bodyid[g]
    mine = body == cell.ids.tile_body[tile]
    world = m.body_treeid[body] < 0
    return np.concatenate([g[mine[:, 0] & world[:, 1], 0], g[mine[:, 1] & world[:, 0], 1]])


def test_tiles_laid_at_rest_start_asleep_where_they_were_laid(cell: Cell) -> None:
    m = cell.model
    qpos0, policy = m.qpos0.copy(), m.tree_sleep_policy.copy()
    cell.reset(seed=5)
    laid = cell.tile_poses()
    assert np.all(cell.data.tree_asleep[_trees(cell)] >= 0)
    assert cell.time == 0.0
    np.testing.assert_allclose(cell.qpos, cell.cfg.robot.home, atol=1e-12)
    np.testing.assert_allclose(cell.data.ctrl[cell.ids.pos_actuators], cell.cfg.robot.home)
    # The model is as built: the sleep reset's qpos0 and sleep policies were put back.
    np.testing.assert_array_equal(m.qpos0, qpos0)
    np.testing.assert_array_equal(m.tree_sleep_policy, policy)
    cell.step(50)
    np.testing.assert_array_equal(cell.tile_poses().pos, laid.pos)  # asleep: not moved at all


def test_tiles_on_a_moving_belt_stay_awake_and_ride_it(cell: Cell) -> None:
    cell.belt_speed = 0.1
    cell.reset(seed=4)
    assert np.all(cell.data.tree_asleep[_trees(cell)[cell.on_stage]] < 0)
    before = cell.tile_poses().pos
    cell.step(100)  # 0.2 s
    moved = cell.tile_poses().pos[cell.on_stage, 0] - before[cell.on_stage, 0]
    assert np.all(moved > 0.01)  # ~2 cm along the belt (+x)


def test_a_sleeping_tile_whose_pose_is_written_wakes_and_falls(cell: Cell) -> None:
    q = cell.ids.tile_qpos[SQUARE]
    z0 = cell.tile_poses().pos[SQUARE, 2]
    cell.data.qpos[q + 2] += 0.005  # lifted 5 mm while asleep
    cell.step(150)
    assert cell.tile_poses().pos[SQUARE, 2] == pytest.approx(z0, abs=5e-5)  # fell back
    assert cell.data.tree_asleep[_trees(cell)[SQUARE]] >= 0  # and slept again


def test_a_holed_tile_rests_on_its_hull_and_stacks_on_its_pieces(cell: Cell) -> None:
    m = cell.model
    q = cell.ids.tile_qpos[RING]
    top = cell.geometry.input_centre[2] + cell.cfg.tiles.thickness / 2
    cell.data.qpos[q + 2] = top + 0.003  # dropped from 3 mm: wakes, lands, settles
    cell.step(250)
    assert cell.tile_poses().pos[RING, 2] == pytest.approx(top, abs=5e-5)
    up = cell.data.xmat[cell.ids.tile_body[RING]].reshape(3, 3)[2, 2]
    assert up > np.cos(np.radians(0.1))  # flat
    cell.data.qpos[q + 2] = top + 1e-4  # awake again, touching: count its contacts
    cell.step(3)
    geoms = _world_contacts(cell, RING)
    assert 0 < len(geoms) <= 8  # its ~40 convex pieces would give ~4 each
    assert np.all(m.geom_contype[geoms] == SUPPORT_CONTYPE)
    # The pieces still touch other tiles: the ring set on the square rests on top of it.
    sq = cell.tile_poses().pos[SQUARE]
    cell.data.qpos[q : q + 3] = [sq[0], sq[1], sq[2] + cell.cfg.tiles.thickness + 0.001]
    cell.step(250)
    assert cell.tile_poses().pos[RING, 2] == pytest.approx(
        sq[2] + cell.cfg.tiles.thickness, abs=2e-4
    )
    assert cell.warnings() == 0


def test_a_kinematic_place_sets_the_tile_down(kinematic_env: gym.Env) -> None:
    env: MosaicAssemblyEnv = kinematic_env.unwrapped
    cell = env.cell
    env.reset(seed=2)
    rest = cell.geometry.mesh_top + cell.cfg.tiles.thickness / 2
    trees = _trees(cell)
    for k in range(3):
        _, _, _, _, info = env.step(env.expert_action(k, k))
        assert not info["action_failed"]
        i = cell.events[-1].tile
        assert cell.events[-1].kind == "release"
        # At the step's end the tile lies on the sheet (not still dropping), nearly still.
        assert cell.tile_poses().pos[i, 2] == pytest.approx(rest, abs=3e-5)
        dof = cell.ids.tile_dof_index[i]
        assert np.abs(cell.data.qvel[dof[:3]]).max() < 5e-3
    assert info["evaluation"]["correct"] == 3
    # Tiles placed earlier sleep again (the one before last is due to at the next physics
    # step): a step simulates the arm, the new tile and little else.
    placed = np.array([e.tile for e in cell.events if e.kind == "release"])
    asleep = cell.data.tree_asleep[trees[placed]]
    assert np.all(asleep[:-2] >= 0) and asleep[-2] >= -1 and asleep[-1] < 0


def _speeds(cell: Cell) -> np.ndarray:
    """Largest speed component of each tile [m/s, rad/s x dof length], shape (n,)."""
    dof = cell.ids.tile_dof_index
    return (np.abs(cell.data.qvel[dof]) * cell.model.dof_length[dof]).max(axis=1)


def test_ending_countdowns_spares_tiles_moving_in_any_direction(cell: Cell) -> None:
    """Only tiles still in every degree of freedom have their sleep countdown ended.

    Tiles riding a moving belt move along x only; their countdown must keep running. Once the
    belt stops they come to rest one by one; then exactly the still ones are ended.
    """
    trees = _trees(cell)
    tol = cell.model.opt.sleep_tolerance
    cell.belt_speed = 0.1
    cell.reset(seed=4)
    cell.step(40)
    riding = cell.on_stage & (cell.data.tree_asleep[trees] < -1)
    assert riding.sum() >= 5
    assert np.all(_speeds(cell)[riding] > tol)  # riding: moving along the belt only
    cell.sleep_still_tiles()
    assert np.all(cell.data.tree_asleep[trees[riding]] < -1)  # countdowns untouched
    before = cell.tile_poses().pos
    cell.step(50)
    moved = cell.tile_poses().pos[riding, 0] - before[riding, 0]
    np.testing.assert_allclose(moved, 0.1 * 50 * cell.model.opt.timestep, rtol=0.05)
    cell.belt_speed = 0.0
    for _ in range(200):  # step until some tiles rest while others still move
        cell.step(1)
        counting = cell.data.tree_asleep[trees] < -1
        still = counting & (_speeds(cell) < tol)
        if still.any() and (counting & ~still).any():
            break
    else:
        pytest.fail("no moment with both still and moving tiles counting down")
    cell.sleep_still_tiles()
    asleep_now = cell.data.tree_asleep[trees]
    assert np.all(asleep_now[still] == -1)
    assert np.all(asleep_now[counting & ~still] < -1)
