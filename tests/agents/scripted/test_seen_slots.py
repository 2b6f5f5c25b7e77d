"""Rounded tiles in the cell: the slots' seen descriptions let the scripted agent place them."""

from __future__ import annotations

import math

import numpy as np

from agents.scripted.config import load_agents_config
from agents.scripted.perception import figure_to_world, perceive_tiles, slot_targets
from agents.scripted.placement import FeasiblePairs, plan_placements
from agents.scripted.seen_slots import camera_scale
from qshape import ExtractParams, Figure
from qshape.design import Design
from qshape.design.shape_maps import rounded_polygon_shape
from tests.agents.scripted.cell_picture import four_slot_design, picture_of


def _rounded_and_plain() -> Design:
    # Two 46 mm squares with two opposite corners rounded (17.5 mm arcs tangent to both edges:
    # above the smallest recognised arc) and two plain 40 mm squares, one colour.
    h = 23.0
    v = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
    rounded = rounded_polygon_shape(v, 17.5, np.array([True, False, True, False]))
    square = {"kind": "square", "size": 40}
    return four_slot_design(
        "rounded", (rounded, square), ("#c0392b",) * 4, start_mm=50, pitch_mm=100, turn_deg=25.0
    )


def test_rounded_tiles_match_their_slots_as_the_camera_sees_them() -> None:
    pic = picture_of(_rounded_and_plain())
    img, cam, z, ws = pic.image, pic.camera, pic.tile_top_z, pic.slots
    scale = camera_scale(cam, z)
    assert 1.5 < scale < 2.5  # [px/mm] the default input camera on the tile tops
    cfg = load_agents_config().perception
    plain = slot_targets(ws)
    seen = slot_targets(ws, seen=(ExtractParams.load().outline, scale, cfg.seen_turn_residual))
    # The rounded slots get a seen description (the design's vertices at the arcs' tangent
    # ends are not in any picture); the plain squares are seen as described.
    assert [s.seen is not None for s in seen] == [True, False, True, False]
    per = perceive_tiles(img, cam, z)
    assert len(per.tiles) == 4
    before = FeasiblePairs(per.tiles, plain)
    after = FeasiblePairs(per.tiles, seen)
    rounded_tiles = [k for k in range(4) if not before.slots_of(k, True)]
    assert len(rounded_tiles) == 2  # the design's own description matches no rounded tile
    for k in range(4):
        # No false match: a rounded tile matches only rounded slots, a square only squares.
        got = after.slots_of(k, True)
        assert got == ({0, 2} if k in rounded_tiles else {1, 3})
    plan = plan_placements(per.tiles, seen)
    assert len(plan.commands) == 4 and not plan.unplaced
    for c in plan.commands:
        tile = next(t for t in per.tiles if t.index == c.tile)
        assert tile.outline_px is not None
        traced = figure_to_world(cam, Figure.from_polygon(tile.outline_px, y_down=True), z)
        own = np.asarray(traced.centroid) / 1000.0  # [m] the traced outline's area centroid
        # The slot's centroid is the design's area centroid: the tile's own area centroid
        # (not its seen figure's, whose arcs through three points bulge) is what is placed
        # there, so the command's tile centre lies within 0.5 mm of the traced one.
        assert math.dist(c.pick[:2], own) < 5e-4
