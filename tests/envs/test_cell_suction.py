"""Vacuum pad: seal check, sensors, holding-force limit and drops."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.config import CellConfig, SuctionConfig
from envs.cell.tiles.shapes import basic_shapes
from tests.envs.cell_motion import ArmIK, ArmIKFor, move, pick, tool_down, world_grasp

SHAPES = {s.name: s for s in basic_shapes()}


def _cell(**suction: float) -> Cell:
    cfg = CellConfig(suction=SuctionConfig(**suction))
    return Cell(cfg, [SHAPES["square"], SHAPES["ring"]], seed=1)


@pytest.fixture
def rig(arm_ik: ArmIKFor) -> Iterator[tuple[Cell, ArmIK]]:
    """The default cell (a square and a ring) and its arm IK; closed after the test."""
    cell = _cell()
    try:
        yield cell, arm_ik(cell)
    finally:
        cell.close()


def _hover(
    cell: Cell, ik: ArmIK, i: int, height: float, *, tilt_deg: float = 0.0, at_origin: bool = False
) -> None:
    p, yaw = world_grasp(cell, i)
    if at_origin:
        p = cell.tile_poses().pos[i] + [0, 0, cell.cfg.tiles.thickness / 2]
    t = np.radians(tilt_deg)
    tilt = np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])
    q = ik.solve(p + [0, 0, 0.05], tool_down(yaw), cell.qpos)
    move(cell, q)
    move(cell, ik.solve(p + [0, 0, height], tilt @ tool_down(yaw), q), speed_scale=0.3)


def test_sensors_and_seal_only_when_close_and_flat(rig: tuple[Cell, ArmIK]) -> None:
    cell, ik = rig
    assert not cell.vacuum_on and not cell.tile_held
    _hover(cell, ik, 0, height=0.01)  # 10 mm above: no seal
    assert cell.vacuum(True) is None
    cell.step(5)
    assert cell.vacuum_on and not cell.tile_held
    cell.vacuum(False)
    _hover(cell, ik, 0, height=0.0005, tilt_deg=12.0)  # close but tilted: no seal
    cell.vacuum(True)
    cell.step(5)
    assert not cell.tile_held
    cell.vacuum(False)
    _hover(cell, ik, 0, height=0.0005)  # close and flat: seal
    ev = cell.vacuum(True)
    assert ev is not None and ev.kind == "grasp" and ev.tile == 0
    assert cell.tile_held and cell.held_tile == 0
    ev = cell.vacuum(False)
    assert ev is not None and ev.kind == "release"
    assert not cell.tile_held


def test_no_seal_over_a_hole(rig: tuple[Cell, ArmIK]) -> None:
    cell, ik = rig
    _hover(cell, ik, 1, height=0.0005, at_origin=True)  # ring: centroid is in the hole
    cell.vacuum(True)
    cell.step(5)
    assert not cell.tile_held
    cell.vacuum(False)
    assert pick(cell, ik, 1)  # at its grasp point on the material it seals


def test_descending_with_vacuum_on_seals_on_contact(rig: tuple[Cell, ArmIK]) -> None:
    cell, ik = rig
    _hover(cell, ik, 0, height=0.02)
    cell.vacuum(True)
    assert not cell.tile_held
    p, yaw = world_grasp(cell, 0)
    move(cell, ik.solve(p + [0, 0, 0.0005], tool_down(yaw), cell.qpos), speed_scale=0.2)
    assert cell.held_tile == 0


def test_over_limit_acceleration_drops_the_tile_and_is_reported(arm_ik: ArmIKFor) -> None:
    # 300 Pa x 23 mm pad = 0.125 N: holds the 4.8 g tile (0.047 N) at rest and in a slow move,
    # not through a full-speed move.
    cell = _cell(vacuum_pressure=300.0)
    ik = arm_ik(cell)
    try:
        assert cell.suction.holding_force == pytest.approx(0.1246, abs=1e-3)
        assert pick(cell, ik, 0)
        q_slow = cell.qpos + [0.25, 0, 0, 0, 0, 0]
        move(cell, q_slow, speed_scale=0.05)
        assert cell.tile_held and cell.n_dropped == 0
        target = ik.solve(cell.geometry.output_centre + [0, 0, 0.06], tool_down(0.0), cell.qpos)
        move(cell, target, speed_scale=1.0)
        assert cell.n_dropped == 1
        assert not cell.tile_held and cell.vacuum_on  # valve still open, tile gone
        drop = [e for e in cell.events if e.kind == "drop"]
        assert len(drop) == 1 and drop[0].tile == 0
        limit = cell.suction.holding_force
        assert drop[0].pull > limit or drop[0].shear > 0.5 * (limit - drop[0].pull)
        cell.step(500)
        assert cell.warnings() == 0
    finally:
        cell.close()


def test_default_vacuum_holds_through_full_speed(rig: tuple[Cell, ArmIK]) -> None:
    cell, ik = rig
    assert pick(cell, ik, 0)
    target = ik.solve(cell.geometry.output_centre + [0, 0, 0.06], tool_down(0.0), cell.qpos)
    move(cell, target, speed_scale=1.0)
    assert cell.held_tile == 0 and cell.n_dropped == 0
    assert 0 < cell.suction.pull + cell.suction.shear < cell.suction.holding_force


def test_the_seal_check_reaches_a_tile_s_corner_at_the_largest_gap(
    rig: tuple[Cell, ArmIK],
) -> None:
    """Guards against a seal check that leaves out a tile it must test (it looks only at the
    tiles within reach of the pad): the pad over the material farthest from the tile's centroid
    (a corner, at the tile's bounding radius) at the largest allowed gap seals; a little beyond
    the corner or higher, it does not."""
    cell, _ = rig
    d, i, site = cell.data, 0, cell.ids.tcp_site
    outline = np.asarray(cell.tiles[i].outline)
    corner = outline[np.argmax(np.hypot(outline[:, 0], outline[:, 1]))]
    assert np.hypot(*corner) == pytest.approx(cell.tiles[i].radius)
    centre = d.xpos[cell.ids.tile_body[i]].copy()
    rot = d.xmat[cell.ids.tile_body[i]].reshape(3, 3).copy()
    gap = cell.cfg.suction.seal_max_gap
    top = cell.cfg.tiles.thickness / 2

    def candidate(scale: float, height: float) -> int:
        d.site_xpos[site] = centre + rot @ [*(corner * scale), top + height]
        d.site_xmat[site] = np.diag([1.0, -1.0, -1.0]).ravel()  # pad axis down the face normal
        return cell.suction.seal_candidate(d)

    assert candidate(0.999, 0.999 * gap) == i
    assert candidate(0.999, 0.0) == i
    assert candidate(1.01, 0.5 * gap) == -1
    assert candidate(0.999, 1.01 * gap) == -1
