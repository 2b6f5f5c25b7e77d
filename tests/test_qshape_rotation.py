"""The rotation of a match: curve points weigh less than corners."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qshape import Figure, Tolerances, match


def _semicircle(turn_deg: float, apex_shift_deg: float = 0.0) -> Figure:
    """A 20 mm semicircle turned by ``turn_deg``; its arc's apex slid along the arc."""
    a = math.radians(90.0 + apex_shift_deg)
    pts = np.array([[10.0, 0.0], [10.0 * math.cos(a), 10.0 * math.sin(a)], [-10.0, 0.0]])
    t = math.radians(turn_deg)
    rot = np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])
    return Figure.from_polygon(pts @ rot.T, curve_mask=[False, True, False])


@pytest.mark.parametrize("shift", [-6.0, 6.0])
def test_an_apex_slid_along_its_arc_barely_turns_the_match(shift):
    ref = _semicircle(0.0)
    cand = _semicircle(30.0, apex_shift_deg=shift)
    truth = math.radians(-30.0)
    errs = {}
    for w in (1.0, 0.25):
        m = match(ref, cand, Tolerances(curve_point_weight=w))
        assert m is not None
        errs[w] = abs(math.degrees(m.rotation - truth))
    # Equal weights: the slid apex (6 deg about the centre) turns the fit by over 1 deg.
    assert errs[1.0] > 1.0
    assert errs[0.25] < 0.5 * errs[1.0]


def test_polygons_keep_their_rotation():
    sq = Figure.from_polygon([[0, 0], [20, 0], [20, 20], [0, 20]])
    turned = Figure.from_polygon(
        np.array([[0, 0], [20, 0], [20, 20], [0, 20]])
        @ np.array([[math.cos(0.3), math.sin(0.3)], [-math.sin(0.3), math.cos(0.3)]])
    )
    a = match(sq, turned, Tolerances(curve_point_weight=1.0))
    b = match(sq, turned, Tolerances(curve_point_weight=0.25))
    assert a is not None and b is not None
    assert a.rotation == b.rotation
