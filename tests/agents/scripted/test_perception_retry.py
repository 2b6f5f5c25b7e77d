"""A tile whose figure matches no slot is simplified again: a bite on part of an edge."""

from __future__ import annotations

import dataclasses

import numpy as np

from agents.scripted.config import load_agents_config
from agents.scripted.perception import perceive_tiles, refigured, slot_targets
from qshape import ExtractParams, OutlineParams
from qshape.design import Design
from qshape.theory.assign import feasible_pairs
from qshape.theory.tolerances import default_tolerances
from tests.agents.scripted.cell_picture import four_slot_design, picture_of


def _bitten() -> Design:
    # Squares of 40 mm with a concave arc 20 mm wide and 6 mm deep in one edge (above the
    # smallest recognised arc, 5 x 20 mm), and plain squares.
    bite = {
        "kind": "polygon",
        "vertices": [[0, 0], [10, 0, -0.6], [30, 0], [40, 0], [40, 40], [0, 40]],
    }
    square = {"kind": "square", "size": 40}
    colors = ("#c0392b", "#c0392b", "#2e6fd1", "#2e6fd1")
    return four_slot_design(
        "bitten", (bite, square), colors, start_mm=40, pitch_mm=60, turn_deg=30.0
    )


def test_the_retry_recognises_the_bitten_tiles() -> None:
    pic = picture_of(_bitten())
    img, cam, z = pic.image, pic.camera, pic.tile_top_z
    slots = slot_targets(pic.slots)
    per = perceive_tiles(img, cam, z)
    assert len(per.tiles) == 4
    tol = default_tolerances()
    descs = [s.description for s in slots]

    def matched(tiles: list) -> set[int]:
        t, _, _, _ = feasible_pairs([x.description for x in tiles], descs, tol, True)
        return {int(k) for k in t}

    first = matched(list(per.tiles))
    cfg = load_agents_config()
    params = OutlineParams(
        **{**dataclasses.asdict(ExtractParams.load().outline), **cfg.perception.retry_outline}
    )
    again = [refigured(t, cam, z, params) for t in per.tiles]
    assert all(a is not None for a in again)
    bitten = [k for k, t in enumerate(per.tiles) if k not in first]
    plain = [k for k in range(4) if k in first]
    assert len(bitten) == 2 and len(plain) == 2
    for k in bitten:
        # The bundled parameters lose the bite (a square's 4 or 5 corners, no curve); the
        # retry's give the design's structure: 7 nodes, one concave curve point between two
        # corners. (Its labels beside the bite still differ from the design's: the edges
        # there sit at the equal-length band's edge, so it matches no slot yet.)
        t, a = per.tiles[k], again[k]
        assert a is not None and a.index == t.index
        assert not t.figure.outer.curve_mask.any() and len(t.figure.outer.points) <= 5
        assert len(a.figure.outer.points) == 7 and int(a.figure.outer.curve_mask.sum()) == 1
        np.testing.assert_allclose(a.centre, t.centre, atol=0.002)
    for k in plain:  # plain squares keep their figure and their match
        a = again[k]
        assert a is not None and len(a.figure.outer.points) == 4
    assert matched([a for a in again if a is not None]) >= set(plain)
