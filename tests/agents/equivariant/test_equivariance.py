"""agents.equivariant: the scores turn with the picture; fine turns and rotation indices."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from agents.equivariant.config import EquivariantConfig, EquivariantConfigError
from agents.equivariant.network import build_network
from agents.equivariant.turns import right_turns, rotation_of_turns, turn_maps

CFG = EquivariantConfig(grid=16, turns=12, width=4, features=4)


def _crops(seed: int) -> tuple[torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    tiles = torch.rand(1, 3, 4, CFG.grid, CFG.grid, generator=g)
    slots = torch.rand(1, 2, CFG.slot_channels, CFG.grid, CFG.grid, generator=g)
    return tiles, slots


def test_a_quarter_turn_of_the_tile_pictures_shifts_the_scores_by_a_quarter() -> None:
    """Fails if the encoders were plain convolutions (not averaged over turned copies) or
    the fine turns were not exact quarter turns of each other."""
    net = build_network(CFG).eval()
    tiles, slots = _crops(0)
    with torch.no_grad():
        base = net(tiles, slots)
        turned = net(torch.rot90(tiles, 1, dims=(-2, -1)), slots)
        both = net(torch.rot90(tiles, 1, dims=(-2, -1)), torch.rot90(slots, 1, dims=(-2, -1)))
    quarter = CFG.turns // 4
    # the tile already turned a quarter needs a quarter less: score k then is score k + quarter
    torch.testing.assert_close(turned, torch.roll(base, -quarter, dims=-1), atol=1e-5, rtol=0)
    torch.testing.assert_close(both, base, atol=1e-5, rtol=0)


def test_turn_maps_turn_counter_clockwise_and_quarter_turns_exactly() -> None:
    x = torch.zeros(1, 1, 8, 8)
    x[0, 0, 0, 3:5] = 1  # a bar at the top
    out = turn_maps(x, 8)
    torch.testing.assert_close(out[:, 2], torch.rot90(x, 1, dims=(-2, -1)))
    left = out[0, 2, 0].nonzero()[:, 1].float().mean()  # after a quarter: the left column
    assert left < 1


def test_rotation_indices_of_fine_turns_per_frame() -> None:
    """``tile``: the bin of the turn; ``shape``: a hexagon's turns all name index 0 (its
    offset modulo 60 deg rounds to no step); ``slot``: always 0."""
    r = rotation_of_turns(36, 4, "tile", 1)
    assert r[0] == 0 and r[9] == 1 and r[18] == 2 and r[27] == 3  # 0, 90, 180, 270 deg
    assert r[4] == 0 and r[5] == 1  # 40 deg rounds down, 50 deg up
    assert set(rotation_of_turns(36, 4, "shape", 6)) == {0}
    rect = rotation_of_turns(36, 4, "shape", 2)  # period 180 deg
    assert rect[9] in (1, 3) and rect[0] == 0
    assert set(rotation_of_turns(36, 4, "slot", 1)) == {0}


def test_right_turns_follow_the_figures_symmetry() -> None:
    tol = math.radians(6)
    one = right_turns(math.radians(90), 1, 36, tol)
    assert np.flatnonzero(one).tolist() == [9]
    square = right_turns(math.radians(90), 4, 36, tol)
    assert np.flatnonzero(square).tolist() == [0, 9, 18, 27]
    assert right_turns(0.3, 0, 36, tol).all()  # a round tile: any turn


def test_turns_must_contain_the_quarter_turns() -> None:
    with pytest.raises(EquivariantConfigError, match="multiple of 4"):
        EquivariantConfig(turns=30)
