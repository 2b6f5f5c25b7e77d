"""'On the input side': the belt test (`Cell.input_side`) and the midline test (`Cell.input_half`).

Both live on the `Cell`. They agree wherever a tile can rest in a v0 episode (on the input
belt, on the mesh, parked, lost); they differ for a tile lying between the belts or beyond the
input belt's outer edge, which only the midline test counts.
"""

from __future__ import annotations

import numpy as np
import pytest

from envs.cell.cell import Cell


@pytest.fixture(scope="module")
def cell():
    c = Cell(seed=0)
    yield c
    c.close()


def _put(cell: Cell, tile: int, world_y: float) -> None:
    """Tile ``tile`` laid flat at the tile area's x and at ``world_y`` [m]."""
    centre = cell.geometry.input_centre
    cell.place_tiles(np.array([tile]), np.array([[0.0, world_y - centre[1], 0.0]]))
    cell.step(1)


def test_the_predicates_agree_on_the_belt_and_off_stage(cell: Cell) -> None:
    cell.reset(seed=0)
    on = cell.on_stage.copy()
    assert on.any()
    np.testing.assert_array_equal(cell.input_side(), on)
    np.testing.assert_array_equal(cell.input_half(), on)
    cell.park_tiles(np.array([0]))
    assert not cell.input_side()[0] and not cell.input_half()[0]


def test_between_the_belts_only_the_midline_test_counts_a_tile(cell: Cell) -> None:
    cell.reset(seed=0)
    g, belt = cell.geometry, cell.cfg.input_belt
    edge = g.input_y - belt.width / 2 - cell.radii[0]  # beyond this the belt test says no
    assert g.midline_y < edge
    _put(cell, 0, (g.midline_y + edge) / 2)
    assert cell.input_half()[0] and not cell.input_side()[0]
    _put(cell, 0, g.midline_y - 0.01)
    assert not cell.input_half()[0] and not cell.input_side()[0]
    _put(cell, 0, g.input_y)
    assert cell.input_half()[0] and cell.input_side()[0]
