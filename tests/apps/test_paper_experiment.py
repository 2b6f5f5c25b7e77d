"""The paper's Figs. 5-6 experiment: who matches what, with and without colour, greedy/optimal."""

from __future__ import annotations

import pytest

from apps.paper_experiment import DESIGN_OBJECTS, TILES, run_experiment, table


@pytest.fixture(scope="module")
def result():
    return run_experiment()[0]


def test_every_tile_extracted_once(result):
    assert sorted(result.tile_numbers) == list(range(1, 9))


def test_shape_only_counts_as_in_the_paper(result):
    assert len(result.marked_by(2, False)) == 5
    assert len(result.marked_by(3, False)) == 3
    assert len(result.marked_by(5, False)) == 1
    assert len(result.marked_by(7, False)) == 1


def test_mark_as_matched_hides_tiles_8_and_6(result):
    # 1 and 8: same shape, different colour: both objects marked 1, tile 8 finds nothing.
    assert sorted(result.marked_by(1, False)) == ["square_a", "square_b"]
    assert result.marked_by(8, False) == []
    # The same for 4 and 6.
    assert sorted(result.marked_by(4, False)) == ["rect_big", "rect_small"]
    assert result.marked_by(6, False) == []


def test_shape_and_colour(result):
    found = {n for n in range(1, 9) if result.marked_by(n, True)}
    assert found == {2, 3, 4, 5, 6, 8}
    assert sorted(result.marked_by(2, True)) == ["tri_yellow_1", "tri_yellow_2"]
    assert result.marked_by(1, True) == [] and result.marked_by(7, True) == []


def test_greedy_versus_optimal(result):
    greedy, optimal = result.assign["greedy/shape"], result.assign["optimal/shape"]
    # Greedy gives tile 4 the first rectangle listed (the larger): tile 6 is left out.
    assert greedy[4] == "rect_big" and 6 not in greedy
    # Optimal places both.
    assert optimal[4] == "rect_small" and optimal[6] == "rect_big"
    assert len(optimal) == len(greedy) + 1 == 8
    # With colour both methods place the same tiles, each in a slot of its own colour
    # (among equal slots they may choose different ones: greedy the first, optimal the best fit).
    for key in ("greedy/shape+colour", "optimal/shape+colour"):
        placed = result.assign[key]
        assert set(placed) == {2, 3, 4, 5, 6, 8}
        for tile, slot in placed.items():
            assert COLOURS[slot] == TILES[tile - 1][1]


COLOURS = {name: color for name, _, color in DESIGN_OBJECTS}


def test_design_only_shapes_unmatched(result):
    assert "hexagon" not in result.marks_shape and "semicircle" not in result.marks_shape
    assert "design objects matched by no tile" in table(result)
