"""Placement on real renders of the cell: classes, place yaws modulo symmetry, bad input."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import qshape
from agents.scripted.config import PlacementConfig
from agents.scripted.perception import balance_colors, perceive_tiles, slot_targets
from agents.scripted.placement import plan_placements, wrap
from benchmarks.design_cell import build_design_cell, nearest_tile
from envs.cell.config import load_cell_config
from envs.task_spec import work_areas, world_slots
from qshape.design import Design
from spatial.angles import equivalent_yaws, yaw_error

YAW_TOL = math.radians(2.0)


@pytest.fixture(scope="module")
def scene(design):
    cell, _ = build_design_cell(design, seed=3)
    cell.step(100)
    cam = cell.camera_model("input_camera")
    slots = slot_targets(world_slots(cell, design))
    per = perceive_tiles(cell.render("input_camera"), cam, work_areas(cell)[0].tile_top_z)
    per, _ = balance_colors(per, np.array([s.color for s in slots]))
    yield cell, design, slots, per
    cell.close()


@pytest.mark.parametrize("method", ["optimal", "greedy"])
def test_every_tile_to_a_slot_of_its_class_with_the_right_yaw(scene, method):
    cell, design, slots, per = scene
    plan = plan_placements(per.tiles, slots, PlacementConfig(method=method))
    assert len(plan.commands) == len(design.slots)
    assert not plan.unplaced and not plan.open_slots
    truth = cell.tile_poses()
    for c in plan.commands:
        i, _ = nearest_tile(cell, np.array(c.pick[:2]))
        assert cell.tiles[i].shape.name == design.slots[c.slot].class_key
        # The tile turns by rotation: its final yaw must be the slot's modulo symmetry.
        sym = cell.tiles[i].shape.symmetry
        assert yaw_error(truth.yaw[i] + c.rotation, c.place[2], sym) < YAW_TOL, c.slot_name
        assert yaw_error(truth.yaw[i], c.pick[2], sym) < YAW_TOL
        assert math.isclose(wrap(c.place[2] - c.pick[2]), c.rotation, abs_tol=1e-9)
        for y in c.place_yaws:
            assert yaw_error(y, c.place[2], sym) < 1e-9


def test_rotation_sign_on_a_render(scene):
    """Image y points down: the rotation must be CCW seen from above (world), not mirrored."""
    cell, design, slots, per = scene
    plan = plan_placements(per.tiles, slots)
    truth = cell.tile_poses()
    asym = [c for c in plan.commands if c.symmetry == 1]
    # A mirrored rotation misses by 2 x rotation: told apart where that is 10 tolerances.
    telling = [c for c in asym if abs(wrap(2 * c.rotation)) > 10 * YAW_TOL]
    assert telling
    for c in asym:
        i, _ = nearest_tile(cell, np.array(c.pick[:2]))
        mirrored = yaw_error(truth.yaw[i] - c.rotation, c.place[2], 1)
        correct = yaw_error(truth.yaw[i] + c.rotation, c.place[2], 1)
        assert correct < YAW_TOL
        assert mirrored > 9 * YAW_TOL or c not in telling


def test_distractors_and_absent_shapes_are_never_placed(scene):
    _, design, slots, per = scene
    # Keep only half the slots: tiles of the missing classes must be reported, not placed.
    keep = [s for s in slots if s.index % 2 == 0]
    plan = plan_placements(per.tiles, keep)
    placed = {c.tile for c in plan.commands}
    assert len(placed) + len(plan.unplaced) == len(per.tiles)
    assert {c.slot for c in plan.commands} <= {s.index for s in keep}
    assert all(u.reason in ("shape_absent", "color_absent", "slots_taken") for u in plan.unplaced)


def test_shape_only_mixes_colours(scene):
    _, _, slots, per = scene
    plan = plan_placements(per.tiles, slots, PlacementConfig(use_color=False))
    assert len(plan.commands) == len(slots)


def test_equivalent_yaws():
    assert len(equivalent_yaws(0.3, 4, 12)) == 4
    assert len(equivalent_yaws(0.3, 0, 12)) == 12
    assert tuple(equivalent_yaws(0.3, 1, 12)) == (0.3,)
    assert equivalent_yaws(0.3, 4)[1] == 0.3 + math.pi / 2


def test_empty_inputs():
    plan = plan_placements([], [])
    assert plan.commands == () and plan.unplaced == ()
    _ = qshape  # the library stays importable without the simulator in this module's scope


def test_distractors_on_the_belt_are_never_placed(design: Design):
    full = design
    design = full.with_slots(full.slots[::2])
    base = load_cell_config()
    tiles = replace(base.tiles, distractor_rate=1.0, distractor_kinds=("color", "shape", "broken"))
    cell, _ = build_design_cell(design, replace(base, tiles=tiles), seed=0)
    try:
        cell.step(100)
        slots = slot_targets(world_slots(cell, design))
        per = perceive_tiles(
            cell.render("input_camera"),
            cell.camera_model("input_camera"),
            work_areas(cell)[0].tile_top_z,
        )
        per, _ = balance_colors(per, np.array([s.color for s in slots]))
        plan = plan_placements(per.tiles, slots)
        assert int(cell.is_distractor.sum()) == len(plan.unplaced) == len(design.slots)
        assert not plan.open_slots
        for c in plan.commands:
            i, _ = nearest_tile(cell, np.array(c.pick[:2]))
            assert not cell.is_distractor[i]
            assert cell.tiles[i].shape.name == design.slots[c.slot].class_key
        for u in plan.unplaced:
            i, _ = nearest_tile(cell, per.tiles[u.tile].centre)
            assert cell.is_distractor[i]
            assert u.reason in ("shape_absent", "color_absent")
    finally:
        cell.close()


def test_a_camera_that_sees_nothing_places_nothing(scene):
    cell, _, slots, _ = scene
    dark = np.zeros((492, 656, 3), np.uint8)
    per = perceive_tiles(dark, cell.camera_model("input_camera"), work_areas(cell)[0].tile_top_z)
    assert per.tiles == () and "not usable" in per.unrecognised[0]
    plan = plan_placements(per.tiles, slots)
    assert plan.commands == () and len(plan.open_slots) == len(slots)
