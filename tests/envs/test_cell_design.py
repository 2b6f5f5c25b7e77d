"""Adapter from qshape designs to cell tile shapes and slots."""

from __future__ import annotations

import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.config import load_cell_config
from envs.cell.tiles.shapes import tile_shapes_from_design
from envs.errors import CellError

design_mod = pytest.importorskip("qshape.design")


def test_paper_mixed_builds_and_matches_the_design() -> None:
    design = design_mod.Design.load("paper_mixed")
    shapes, slots = tile_shapes_from_design(design)
    assert len(shapes) == len(slots) == len(design.slots)
    for shape, slot, dslot in zip(shapes, slots, design.slots, strict=True):
        assert shape.area * 1e6 == pytest.approx(dslot.area, rel=0.01)
        assert shape.name == dslot.class_key and slot.name == dslot.name
        assert shape.symmetry == dslot.symmetry
        assert slot.pose[0] == pytest.approx((dslot.x - design.mesh_size[0] / 2) / 1000)
        assert slot.pose[2] == pytest.approx(np.radians(dslot.angle))
    cell = Cell(None, shapes, slots, seed=0)
    try:
        cell.step(250)
        assert cell.warnings() == 0 and cell.n_lost == 0
        assert np.allclose(cell.slot_poses_world()[:, 2], [s.pose[2] for s in slots])
    finally:
        cell.close()


def test_large_design_needs_stream_feeding() -> None:
    shapes, slots = tile_shapes_from_design(design_mod.Design.load("hexagon"))
    with pytest.raises(CellError, match="feed='stream'"):
        Cell(None, shapes, slots)
    cfg = load_cell_config(tiles={"feed": "stream", "stream_initial": 8})
    cell = Cell(cfg, shapes, slots, seed=0)
    try:
        assert cell.on_stage.sum() == 8
    finally:
        cell.close()
