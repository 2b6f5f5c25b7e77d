"""The rotation of a match: curve points weigh less than corners; edges share the fit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qshape import Figure, ToleranceError, Tolerances, assign, match


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
    for w in (1.0, 0.25):  # the points' weights alone (the edges' share is tested below)
        m = match(ref, cand, Tolerances(curve_point_weight=w, rotation_corner_share=1.0))
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


def _turned(points: np.ndarray, deg: float) -> np.ndarray:
    t = math.radians(deg)
    return points @ np.array([[math.cos(t), math.sin(t)], [-math.sin(t), math.cos(t)]])


def _with_tilted_edge(points: np.ndarray, edge: int, tilt_deg: float) -> np.ndarray:
    """The polygon with edge ``edge``'s line turned about its middle, corners re-intersected.

    What a bump at one end of a short edge does to a line fitted over that edge: its two
    corners slide along the neighbouring edges' lines, which stay where they were.
    """
    n = len(points)
    lines = []
    for i in range(n):
        p, q = points[i], points[(i + 1) % n]
        lines.append((0.5 * (p + q), _turned(q - p, tilt_deg)) if i == edge else (p, q - p))
    out = []
    for i in range(n):
        (p1, d1), (p2, d2) = lines[i - 1], lines[i]
        t = np.linalg.solve(np.array([d1, -d2]).T, p2 - p1)
        out.append(p1 + t[0] * d1)
    return np.array(out)


# Two trencadis-like pieces with a short edge (index 1) between long ones, in mm.
_PIECES = [
    np.array([[0.0, 0.0], [30.0, 0.0], [30.0, 6.0], [0.0, 20.0]]),
    np.array([[0.0, 0.0], [28.0, 0.0], [26.0, 7.0], [2.0, 18.0]]),
]


@pytest.mark.parametrize("piece", range(len(_PIECES)))
@pytest.mark.parametrize("tilt", [-10.0, 10.0])
def test_edges_keep_the_rotation_when_a_short_edge_is_misfitted(piece, tilt):
    ref_pts = _PIECES[piece]
    ref = Figure.from_polygon(ref_pts)
    cand = Figure.from_polygon(_turned(_with_tilted_edge(ref_pts, 1, tilt), 25.0))
    errs = {}
    for share in (1.0, 0.33, 0.0):
        m = match(ref, cand, Tolerances(rotation_corner_share=share, check_size=False))
        assert m is not None
        errs[share] = abs(math.degrees(m.rotation) + 25.0)
    # Points alone: the two slid corners turn the match by 0.35-0.7 deg.
    assert errs[1.0] > 0.3
    assert errs[0.0] < 0.25 * errs[1.0]
    assert errs[0.33] < 0.8 * errs[1.0]


@pytest.mark.parametrize("share", [0.0, 0.33, 1.0])
def test_exact_shapes_turn_exactly_whatever_the_share(share):
    ref_pts = _PIECES[1]
    for turn in (-170.0, -30.0, 0.0, 12.5, 90.0):
        cand = Figure.from_polygon(_turned(ref_pts, turn))
        m = match(Figure.from_polygon(ref_pts), cand, Tolerances(rotation_corner_share=share))
        assert m is not None
        assert abs(math.remainder(m.rotation + math.radians(turn), 2 * math.pi)) < 1e-9


def test_a_semicircle_chord_weighs_as_its_curve_point():
    # The apex slid along the arc: the chords from the ends to the apex turn with it, so the
    # edges' share must not undo the curve point's low weight.
    ref = _semicircle(0.0)
    cand = _semicircle(30.0, apex_shift_deg=6.0)
    m = match(ref, cand, Tolerances(rotation_corner_share=0.33))
    w1 = match(ref, cand, Tolerances(curve_point_weight=1.0, rotation_corner_share=1.0))
    assert m is not None and w1 is not None
    assert abs(math.degrees(m.rotation) + 30.0) < 0.5 * abs(math.degrees(w1.rotation) + 30.0)


@pytest.mark.parametrize("bad", [-0.1, 1.5, float("nan")])
def test_rotation_corner_share_is_checked(bad):
    with pytest.raises(ToleranceError, match="rotation_corner_share"):
        Tolerances(rotation_corner_share=bad)


def test_assign_does_not_use_the_edges_share():
    ref_pts = _PIECES[0]
    slots = [Figure.from_polygon(ref_pts)]
    tiles = [Figure.from_polygon(_turned(_with_tilted_edge(ref_pts, 1, 2.0), 25.0))]
    a = assign(tiles, slots, Tolerances(rotation_corner_share=1.0, check_size=False))
    b = assign(tiles, slots, Tolerances(rotation_corner_share=0.0, check_size=False))
    assert len(a) == len(b) == 1
    assert a[0].rotation == b[0].rotation
