"""Thin tiles with sharp tips: centred by their slot's outline, picked where the pad holds."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import shapely.ops
from shapely.geometry import Polygon

from agents.scripted.centre_fit import fitted_centre, sharpest_corner_deg
from agents.scripted.grasp import best_hold, pad_area_on_tile
from qshape import Figure
from qshape.geometry import rotate

DART = np.array([[0.0, 0.0], [55.0, 8.7], [0.0, 17.4], [20.0, 8.7]])  # 17.9 deg tip [mm]


def _dense(poly: np.ndarray, step: float = 0.3) -> np.ndarray:
    ring = shapely.LinearRing(poly)
    n = int(ring.length / step)
    return np.array([ring.interpolate(k * step).coords[0] for k in range(n)])


@pytest.mark.parametrize("turn_deg", [0.0, 37.0, -120.0])
def test_a_blunted_tip_does_not_move_the_fitted_centre(turn_deg: float) -> None:
    slot = Figure.from_polygon(DART, [], (0.8, 0.2, 0.2))
    turn = math.radians(turn_deg)
    tile = rotate(DART - slot.centroid, -turn) + [300.0, 200.0]  # tile lies turned by -turn
    # The picture blunts the tip: the traced outline misses the tip's last 4 mm.
    blunt = shapely.Polygon(tile).difference(shapely.Point(tile[1]).buffer(4.0))
    traced = _dense(np.asarray(blunt.exterior.coords)[:-1])
    points_centre = np.asarray(blunt.centroid.coords[0])  # what relevant points would give
    fitted = fitted_centre(traced, slot, turn, points_centre, step_mm=0.25, iterations=12, trim=3.0)
    assert np.hypot(*(points_centre - [300.0, 200.0])) > 0.15  # the bias the fit removes
    assert np.hypot(*(fitted - [300.0, 200.0])) < 0.05
    # The barbs are sharper than the 17.9 deg tip: 14.5 deg.
    barb = math.degrees(math.atan2(8.7, 20.0) - math.atan2(8.7, 55.0))
    assert sharpest_corner_deg(slot) == pytest.approx(barb, abs=0.01)


def test_a_square_has_no_sharp_corner() -> None:
    square = Figure.from_polygon([[0, 0], [40, 0], [40, 40], [0, 40]], [], (1, 1, 1))
    assert sharpest_corner_deg(square) == pytest.approx(90.0)


def test_the_pad_goes_where_most_of_it_lies_on_a_thin_tile() -> None:
    tile = Polygon(DART / 1000.0)  # [m]
    centre = np.asarray(tile.centroid.coords[0])
    r = 0.0115
    best = best_hold(tile, centre, r, 0.002, 1e-4)
    pole = shapely.ops.polylabel(tile, tolerance=1e-5)
    pole = np.array([pole.x, pole.y])
    area = pad_area_on_tile(tile, np.array([best, pole, centre]), r)
    # The most pad on the tile, within the 0.5 % the rule trades for nearness to the centroid.
    assert area[0] >= 0.995 * max(area[1], area[2])
    assert tile.contains(shapely.Point(best))
    # No point nearby holds more of the pad.
    ring = best + 0.0005 * np.stack([np.cos(np.arange(8)), np.sin(np.arange(8))], axis=1)
    assert np.all(pad_area_on_tile(tile, ring, r) <= area[0] * 1.005)
