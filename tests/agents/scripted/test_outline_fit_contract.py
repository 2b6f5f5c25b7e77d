"""The outline fit's contract on exact outlines: sampling, centroids, turns, refusals, pairs."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from agents.scripted.config import PlacementConfig
from agents.scripted.outline_fit import (
    TileOutline,
    area_centroid,
    boundary_points,
    fit_outline,
    fit_unmatched,
)
from agents.scripted.perception import PerceivedTile, SlotTarget
from qshape import Figure, describe
from spatial.angles import yaw_error
from tests.agents.scripted.polygons import BLUE, ELL, RED, SQUARE, turned

CFG = PlacementConfig(fit_max_residual=0.03, fit_margin=1.3)


def _slot(
    points: np.ndarray,
    symmetry: int,
    class_name: str,
    color: tuple[float, float, float] = RED,
    index: int = 0,
) -> SlotTarget:
    fig = Figure.from_polygon(points, color=color)
    pose = np.array([0.4, 0.1, 0.0])
    return SlotTarget(
        index, f"s{index}", fig, describe(fig), pose, symmetry, color, None, class_name
    )


def _outline(points: np.ndarray, color: tuple[float, float, float] = RED) -> TileOutline:
    return TileOutline(points, (), color)


def test_boundary_points_sample_every_edge_at_most_spacing_apart() -> None:
    """Guards against the spacing ignored or a boundary dropped: a 40 mm square sampled every
    10 mm has its 4 corners, 3 points inside each edge and the closing corner (17 points)."""
    pts = boundary_points([SQUARE], 10.0)
    assert pts.shape == (17, 2)
    np.testing.assert_allclose(pts[:5], [[0, 0], [10, 0], [20, 0], [30, 0], [40, 0]])
    assert np.max(np.linalg.norm(np.diff(pts, axis=0), axis=1)) <= 10.0
    assert boundary_points([SQUARE, SQUARE[:3]], 10.0).shape == (17 + 15, 2)


def test_area_centroid_takes_out_the_holes_and_mends_a_crossed_outline() -> None:
    """Guards against the holes ignored, or a self-crossing traced outline used as it is (its
    signed areas cancel): the centroid of the region actually enclosed."""
    hole = SQUARE / 2 + 5  # a 20 mm hole with its centroid at (15, 15)
    np.testing.assert_allclose(area_centroid(SQUARE, [hole]), [65 / 3, 65 / 3], atol=1e-12)
    np.testing.assert_allclose(area_centroid(SQUARE, []), [20.0, 20.0], atol=1e-12)
    # Two triangles meeting at (4/3, 4/3): areas 4/3 and 16/3.
    bow = np.array([[0, 0], [4, 4], [4, 0], [0, 2]], float)
    np.testing.assert_allclose(area_centroid(bow, []), [1392 / 540, 888 / 540], atol=1e-9)


def test_a_tile_outline_is_its_traced_one_with_the_figure_s_holes() -> None:
    """Guards against a tile with no traced outline fitted, or its figure's holes dropped."""
    hole = SQUARE / 4 + 15
    fig = Figure.from_polygon(SQUARE, holes=[hole], color=RED)
    c = np.asarray(fig.centroid) / 1000
    t = PerceivedTile(0, fig, fig, describe(fig), c, c, c, RED, 1e-3, None, SQUARE + 1.0)
    outline = TileOutline.of(t)
    assert outline is not None
    np.testing.assert_array_equal(outline.outer, SQUARE + 1.0)
    assert len(outline.holes) == 1 and outline.color == RED
    np.testing.assert_allclose(outline.holes[0], fig.holes[0].dense())
    t = PerceivedTile(0, fig, fig, describe(fig), c, c, c, RED, 1e-3, None, None)
    assert TileOutline.of(t) is None


@pytest.mark.parametrize("turn_deg", [-150.0, -20.0, 20.0, 45.0, 100.0, 179.0])
def test_the_fit_finds_every_turn_of_an_asymmetric_tile(turn_deg: float) -> None:
    """Guards against turns of the circle left untried (the scan starting past 0) or the turn
    taken with the wrong sign: an L turned by -t needs +t, wherever t lies."""
    f = fit_outline(_outline(turned(ELL, -turn_deg)), _slot(ELL, 1, "l"), CFG, 1.0)
    assert yaw_error(f.rotation, math.radians(turn_deg), 1) < math.radians(0.1)
    assert -math.pi <= f.rotation < math.pi
    np.testing.assert_allclose(f.centre, [250.0, -80.0], atol=1e-9)
    assert f.residual < 0.5 * CFG.fit_max_residual
    assert f.runner_up > 10.0


def test_a_round_slot_has_no_runner_up_and_a_wide_window_neither() -> None:
    """Guards against the runner-up measured on a continuous slot, or at turns the window
    counts as symmetries: with every turn inside the window there is no rival turn."""
    circle = 20.0 * np.column_stack(
        [
            np.cos(np.linspace(0, 2 * math.pi, 90, endpoint=False)),
            np.sin(np.linspace(0, 2 * math.pi, 90, endpoint=False)),
        ]
    )
    f = fit_outline(_outline(circle + 100.0), _slot(circle, 0, "o"), CFG, 1.0)
    assert math.isinf(f.runner_up) and f.residual < CFG.fit_max_residual
    wide = PlacementConfig(fit_max_residual=0.03, fit_turn_window_deg=180.0)
    f = fit_outline(_outline(turned(ELL, 30.0)), _slot(ELL, 1, "l"), wide, 1.0)
    assert math.isinf(f.runner_up)
    # A square's quarter turns are its own: its runner-up is the turns between them.
    f = fit_outline(_outline(turned(SQUARE, 30.0)), _slot(SQUARE, 4, "q"), CFG, 1.0)
    assert yaw_error(f.rotation, math.radians(-30.0), 4) < math.radians(0.1)
    assert 1.3 < f.runner_up < math.inf


def test_unmatched_tiles_nothing_to_fit_gives_nothing() -> None:
    """Guards against an empty input reaching the assignment."""
    assert fit_unmatched([], [_slot(ELL, 1, "l")], CFG, 0.2, 1.0) == []
    assert fit_unmatched([_outline(turned(ELL, 10.0))], [], CFG, 0.2, 1.0) == []


def test_a_tile_fitting_two_classes_is_left_and_the_next_tile_still_fitted() -> None:
    """Guards against an ambiguous tile ending the search: a 40.5 mm square fits the 40 and
    41 mm square slots (two classes) alike and is left; the L after it still gets its slot."""
    slots = [_slot(SQUARE, 4, "a"), _slot(SQUARE * 41 / 40, 4, "b"), _slot(ELL, 1, "l")]
    tiles = [_outline(turned(SQUARE * 40.5 / 40, 12.0)), _outline(turned(ELL, 33.0))]
    found = fit_unmatched(tiles, slots, CFG, 0.2, 1.0)
    assert [(i, j) for i, j, _ in found] == [(1, 2)]
    assert math.degrees(found[0][2].rotation) == pytest.approx(-33.0, abs=0.1)
    # The square alone against one class is placed.
    found = fit_unmatched(tiles[:1], slots[:1], CFG, 0.2, 1.0)
    assert [(i, j) for i, j, _ in found] == [(0, 0)]


def test_colour_is_matched_only_when_asked() -> None:
    """Guards against the colour check inverted or applied without ``use_color``."""
    tile = _outline(turned(ELL, 33.0), RED)
    blue = [_slot(ELL, 1, "l", BLUE)]
    assert fit_unmatched([tile], blue, CFG, 0.2, 1.0) == []
    assert [(i, j) for i, j, _ in fit_unmatched([tile], blue, CFG, 1.0, 1.0)] == [(0, 0)]
    shape_only = PlacementConfig(fit_max_residual=0.03, use_color=False)
    assert [(i, j) for i, j, _ in fit_unmatched([tile], blue, shape_only, 0.2, 1.0)] == [(0, 0)]


def test_tiles_go_to_slots_of_one_class_by_least_residual() -> None:
    """Guards against the assignment ignoring the residuals: two L tiles and two L slots of one
    class, 40 and 44 mm; each tile goes to the slot of its size, in tile order."""
    big = ELL * 1.1
    slots = [_slot(big, 1, "l", index=0), _slot(ELL, 1, "l", index=1)]
    tiles = [_outline(turned(ELL, 15.0)), _outline(turned(big, -25.0))]
    loose = PlacementConfig(fit_max_residual=0.2, fit_margin=1.3)
    found = fit_unmatched(tiles, slots, loose, 0.2, 1.0)
    assert [(i, j) for i, j, _ in found] == [(0, 1), (1, 0)]
    assert math.degrees(found[1][2].rotation) == pytest.approx(25.0, abs=0.1)
    # A fit over the residual allowed is refused.
    tight = PlacementConfig(fit_max_residual=1e-6)
    assert fit_unmatched(tiles, slots, tight, 0.2, 1.0) == []


def test_a_tile_on_a_tried_turn_is_fitted_exactly_and_quietly() -> None:
    """Guards against the refinement's answer taken although the tried turn fits better, and
    against a misspelt solver option (scipy warns of it): an L turned by exactly 20 deg, one
    of the 2 deg turns tried, gets exactly 20 deg, with no warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        f = fit_outline(_outline(turned(ELL, -20.0)), _slot(ELL, 1, "l"), CFG, 1.0)
    assert f.rotation == pytest.approx(math.radians(20.0), abs=1e-12)


def test_a_colour_at_exactly_the_distance_allowed_is_the_same_colour() -> None:
    """Guards against the colour bound made strict, and against a slot of another colour
    ending the search over the slots: the red L skips the blue slot and fits the red one; a
    grey tile 0.25 from a slot's colour fits it at a colour distance of exactly 0.25."""
    tile = _outline(turned(ELL, 33.0), RED)
    slots = [_slot(ELL, 1, "l", BLUE, index=0), _slot(ELL, 1, "l", RED, index=1)]
    assert [(i, j) for i, j, _ in fit_unmatched([tile], slots, CFG, 0.2, 1.0)] == [(0, 1)]
    grey = _outline(turned(ELL, 33.0), (0.5, 0.5, 0.5))
    slot = [_slot(ELL, 1, "l", (0.5, 0.5, 0.75))]
    assert [(i, j) for i, j, _ in fit_unmatched([grey], slot, CFG, 0.25, 1.0)] == [(0, 0)]
    assert fit_unmatched([grey], slot, CFG, 0.2499, 1.0) == []


def test_a_tile_that_fits_nothing_leaves_the_next_tile_fitted() -> None:
    """Guards against a tile no slot fits ending the search over the tiles."""
    triangle = np.array([[0, 0], [40, 0], [20, 30]], float)
    tiles = [_outline(turned(triangle, 10.0)), _outline(turned(ELL, 33.0))]
    found = fit_unmatched(tiles, [_slot(ELL, 1, "l")], CFG, 0.2, 1.0)
    assert [(i, j) for i, j, _ in found] == [(1, 0)]


def test_the_fit_bounds_admit_a_fit_at_their_edges() -> None:
    """Guards against ``fit_max_residual`` or ``fit_margin`` made strict: a fit whose residual
    is exactly the largest allowed and whose runner-up is exactly the margin is kept."""
    tile = _outline(turned(ELL, 33.0))
    slot = _slot(ELL, 1, "l")
    f = fit_outline(tile, slot, CFG, 1.0)
    edge = PlacementConfig(fit_max_residual=f.residual, fit_margin=f.runner_up)
    assert [(i, j) for i, j, _ in fit_unmatched([tile], [slot], edge, 0.2, 1.0)] == [(0, 0)]
    below = PlacementConfig(fit_max_residual=f.residual * 0.999, fit_margin=f.runner_up)
    assert fit_unmatched([tile], [slot], below, 0.2, 1.0) == []
    above = PlacementConfig(fit_max_residual=f.residual, fit_margin=f.runner_up * 1.001)
    assert fit_unmatched([tile], [slot], above, 0.2, 1.0) == []


def test_the_best_slot_is_the_least_residual_one_and_rivals_are_measured_against_it() -> None:
    """Guards against the best slot taken by position instead of residual, or the rival bound
    divided instead of multiplied: a 40 mm square fits a 41.5 mm square slot (class a, first)
    loosely and a 40 mm one (class b) tightly, more than ``fit_margin`` times better; it goes
    to the 40 mm slot, with no rival."""
    slots = [_slot(SQUARE * 41.5 / 40, 4, "a", index=0), _slot(SQUARE, 4, "b", index=1)]
    tile = _outline(turned(SQUARE, 12.0))
    loose, tight = (fit_outline(tile, s, CFG, 1.0).residual for s in slots)
    assert tight * CFG.fit_margin < loose < CFG.fit_max_residual
    assert [(i, j) for i, j, _ in fit_unmatched([tile], slots, CFG, 0.2, 1.0)] == [(0, 1)]


def test_a_slot_of_another_class_exactly_margin_times_worse_is_no_rival() -> None:
    """Guards against the rival bound made inclusive: another class's slot fitting exactly
    ``fit_margin`` times worse than the best is no rival ("at least fit_margin times worse"),
    one fitting a hair better than that is."""
    slots = [_slot(SQUARE * 40.6 / 40, 4, "a", index=0), _slot(SQUARE, 4, "b", index=1)]
    tile = _outline(turned(SQUARE, 12.0))
    fits = [fit_outline(tile, s, CFG, 1.0) for s in slots]
    margin = fits[0].residual / fits[1].residual
    assert margin * fits[1].residual == fits[0].residual  # exactly at the edge
    assert min(f.runner_up for f in fits) > margin
    edge = PlacementConfig(fit_max_residual=0.03, fit_margin=margin)
    assert [(i, j) for i, j, _ in fit_unmatched([tile], slots, edge, 0.2, 1.0)] == [(0, 1)]
    past = PlacementConfig(fit_max_residual=0.03, fit_margin=float(np.nextafter(margin, 10.0)))
    assert fit_unmatched([tile], slots, past, 0.2, 1.0) == []


def test_a_turn_exactly_the_window_away_is_no_rival_turn() -> None:
    """Guards against the window bound made inclusive: the rival turns are those *farther* than
    ``fit_turn_window_deg`` from the fit's; an L fitted at exactly 0 deg, whose tried turn 5 x
    2 deg lies exactly 10 deg away, has the same runner-up with a 10 deg window as with an 11
    deg one (its nearest rivals at +-12 deg), and a lower one with a 9 deg window."""
    tile, slot = _outline(turned(ELL, 0.0)), _slot(ELL, 1, "l")
    tried = 5 * math.radians(CFG.fit_step_deg)
    window = math.degrees(tried)
    assert math.radians(window) == tried  # exactly the tried turn
    ups = {
        w: fit_outline(tile, slot, dataclasses.replace(CFG, fit_turn_window_deg=w), 1.0)
        for w in (window, window + 1.0, window - 1.0)
    }
    assert ups[window].rotation == 0.0
    assert ups[window].runner_up == ups[window + 1.0].runner_up
    assert ups[window - 1.0].runner_up < ups[window].runner_up
