"""Label rules exactly on, just inside and just outside every band edge, and robust matching."""

import math

import numpy as np
import pytest

import qshape
from qshape import Figure, Tolerances
from qshape.theory.description import node_of
from qshape.theory.labels import measure, node_codes

TOL = Tolerances()  # defaults: right 85-95 deg (margin 2), equal 0.8-1.25 (5%),
# semicircle 0.9-1.1 (3%), convexity margin 2 deg
EPS = 1e-9


def vertex(angle_deg: float, ratio: float = 1.0, tol: Tolerances = TOL):
    """Node at V=(0,0) with interior angle ``angle_deg`` and |prev V| / |V next| = ratio."""
    a = math.radians(angle_deg)
    nxt = np.array([math.cos(-math.pi / 2), math.sin(-math.pi / 2)])
    prev = ratio * np.array([math.cos(-math.pi / 2 + a), math.sin(-math.pi / 2 + a)])
    pts = np.array([prev, [0.0, 0.0], nxt])
    if measure(pts, np.roll(pts, 1, 0), np.roll(pts, -1, 0))[1][1] < 0:  # make V convex
        pts = pts * np.array([-1.0, 1.0])
    return node_of(int(node_codes(pts, np.zeros(3, bool), tol)[1]))


def bent(bend_deg: float, tol: Tolerances = TOL):
    """Node whose boundary bends by ``bend_deg`` (positive: convex) at V."""
    b = math.radians(bend_deg)
    pts = np.array([[-1.0, 0.0], [0.0, 0.0], [math.cos(b), -math.sin(b)]])
    return node_of(int(node_codes(pts, np.zeros(3, bool), tol)[1]))


def curve(ratio: float, tol: Tolerances = TOL):
    """Curve node with half-chord / sagitta = ratio."""
    pts = np.array([[-ratio, 0.0], [0.0, 1.0], [ratio, 0.0]])
    return node_of(int(node_codes(pts, np.array([False, True, False]), tol)[1]))


@pytest.mark.parametrize(
    ("angle", "primary", "admissible"),
    [
        (90.0, "right", {"right"}),
        (85.0 + EPS, "right", {"right", "acute"}),  # on the edge (inside by a hair)
        (86.0, "right", {"right", "acute"}),  # just inside, within margin
        (84.0, "acute", {"acute", "right"}),  # just outside, within margin
        (87.5, "right", {"right"}),  # inside, beyond margin
        (82.5, "acute", {"acute"}),  # outside, beyond margin
        (95.0 - EPS, "right", {"right", "obtuse"}),
        (94.0, "right", {"right", "obtuse"}),
        (96.0, "obtuse", {"obtuse", "right"}),
        (92.5, "right", {"right"}),
        (97.5, "obtuse", {"obtuse"}),
        (30.0, "acute", {"acute"}),
        (150.0, "obtuse", {"obtuse"}),
    ],
)
def test_angle_band_edges(angle, primary, admissible):
    node = vertex(angle)
    assert node.labels[0] == primary
    assert set(node.admissible[0]) == admissible


@pytest.mark.parametrize("edge", [85.0, 95.0])
def test_angle_exactly_on_edge_admits_both(edge):
    node = vertex(edge)
    other = "acute" if edge < 90 else "obtuse"
    assert set(node.admissible[0]) == {"right", other}


@pytest.mark.parametrize(
    ("ratio", "primary", "admissible"),
    [
        (1.0, "equal", {"equal"}),
        (0.8, "equal", {"equal", "smaller"}),
        (0.81, "equal", {"equal", "smaller"}),
        (0.79, "smaller", {"smaller", "equal"}),
        (0.9, "equal", {"equal"}),
        (0.7, "smaller", {"smaller"}),
        (1.25, "equal", {"equal", "bigger"}),
        (1.24, "equal", {"equal", "bigger"}),
        (1.26, "bigger", {"bigger", "equal"}),
        (1.1, "equal", {"equal"}),
        (1.4, "bigger", {"bigger"}),
    ],
)
def test_length_band_edges(ratio, primary, admissible):
    node = vertex(70.0, ratio)
    assert node.labels[2] == primary
    assert set(node.admissible[2]) == admissible


@pytest.mark.parametrize(
    ("ratio", "primary", "admissible"),
    [
        (1.0, "semicircle", {"semicircle"}),
        (0.9, "semicircle", {"semicircle", "acute"}),
        (0.91, "semicircle", {"semicircle", "acute"}),
        (0.89, "acute", {"acute", "semicircle"}),
        (0.85, "acute", {"acute"}),
        (0.95, "semicircle", {"semicircle"}),
        (1.1, "semicircle", {"semicircle", "plane"}),
        (1.09, "semicircle", {"semicircle", "plane"}),
        (1.11, "plane", {"plane", "semicircle"}),
        (1.2, "plane", {"plane"}),
        (3.0, "plane", {"plane"}),
        (0.3, "acute", {"acute"}),
    ],
)
def test_semicircle_band_edges(ratio, primary, admissible):
    node = curve(ratio)
    assert node.kind == "curve"
    assert node.labels[0] == "Curve"
    assert node.labels[2] == primary
    assert set(node.admissible[2]) == admissible


@pytest.mark.parametrize(
    ("bend", "primary", "admissible"),
    [
        (0.0, "convex", {"convex", "concave"}),  # collinear: both
        (1.5, "convex", {"convex", "concave"}),
        (-1.5, "concave", {"concave", "convex"}),
        (2.0, "convex", {"convex", "concave"}),
        (2.5, "convex", {"convex"}),
        (-2.5, "concave", {"concave"}),
        (90.0, "convex", {"convex"}),
        (-90.0, "concave", {"concave"}),
    ],
)
def test_convexity_near_collinear(bend, primary, admissible):
    node = bent(bend)
    assert node.labels[1] == primary
    assert set(node.admissible[1]) == admissible


def test_curve_convexity():
    pts = np.array([[-1.0, 0.0], [0.0, -1.0], [1.0, 0.0]])  # bowing inwards
    node = node_of(int(node_codes(pts, np.array([False, True, False]), TOL)[1]))
    assert node.labels[1] == "concave"


def rhombus(angle_deg: float, side: float = 20.0, rot: float = 0.0) -> Figure:
    a = math.radians(angle_deg)
    pts = np.array(
        [
            [0.0, 0.0],
            [side, 0.0],
            [side + side * math.cos(a), side * math.sin(a)],
            [side * math.cos(a), side * math.sin(a)],
        ]
    )
    c, s = math.cos(rot), math.sin(rot)
    return Figure.from_polygon(pts @ np.array([[c, s], [-s, c]]))


@pytest.mark.parametrize(("a", "b"), [(94.0, 96.0), (84.0, 86.0), (93.5, 97.0), (95.5, 94.5)])
def test_copies_across_an_angle_edge_still_match(a, b):
    ra, rb = rhombus(a), rhombus(b, rot=0.7)
    assert qshape.match(ra, rb) is not None
    # Without margins (labels alone) the two copies, on opposite sides of an edge, would not match.
    assert qshape.match(ra, rb, Tolerances(angle_margin_deg=0.0, point_tolerance=0.0)) is None


def test_far_apart_angles_do_not_match():
    assert qshape.match(rhombus(92.0), rhombus(98.0), Tolerances(point_tolerance=0.0)) is None
    assert qshape.match(rhombus(92.0), rhombus(102.0)) is None


def test_point_tolerance_admits_what_a_displaced_vertex_reaches():
    # 20 mm edges: a 0.5 mm displacement turns an angle by ~2 deg, so 98 deg (3 deg past the
    # right-angle band, 1 deg past its 2 deg margin) may be a 92 deg design; 102 deg may not.
    tol = Tolerances(point_tolerance=0.5)
    assert qshape.match(rhombus(92.0), rhombus(98.0, rot=0.4), tol) is not None
    assert (
        qshape.match(rhombus(92.0), rhombus(98.0, rot=0.4), Tolerances(point_tolerance=0.2)) is None
    )
    # Longer edges: the same displacement turns the angle less.
    big = Tolerances(point_tolerance=0.5, check_size=False)
    assert qshape.match(rhombus(92.0, side=60.0), rhombus(98.0, side=60.0), big) is None


@pytest.mark.parametrize(("a", "b"), [(1.24, 1.26), (0.79, 0.81)])
def test_copies_across_a_length_edge_still_match(a, b):
    def kite(ratio: float) -> Figure:
        return Figure.from_polygon([[0, 0], [20, 0], [20, 20 * ratio], [0, 20 * ratio]])

    assert qshape.match(kite(a), kite(b), Tolerances(check_size=False)) is not None
    assert (
        qshape.match(
            kite(a), kite(b), Tolerances(check_size=False, length_margin=0.0, point_tolerance=0.0)
        )
        is None
    )


@pytest.mark.parametrize(("a", "b"), [(1.09, 1.11), (0.89, 0.91)])
def test_copies_across_a_semicircle_edge_still_match(a, b):
    def arc(ratio: float) -> Figure:
        return Figure.from_polygon(
            [[-10 * ratio, 0], [0, 10], [10 * ratio, 0]], curve_mask=[False, True, False]
        )

    loose = Tolerances(check_size=False)
    assert qshape.match(arc(a), arc(b), loose) is not None
    assert (
        qshape.match(
            arc(a), arc(b), Tolerances(check_size=False, semicircle_margin=0.0, point_tolerance=0.0)
        )
        is None
    )


def test_copies_across_convexity_edge_still_match():
    def notch(depth: float) -> Figure:
        return Figure.from_polygon([[0, 0], [10, depth], [20, 0], [20, 10], [0, 10]])

    a, b = notch(0.15), notch(-0.15)  # bends of about +-1.7 degrees at (10, depth)
    assert qshape.match(a, b) is not None
    assert qshape.match(a, b, Tolerances(convexity_margin_deg=0.0)) is None


@pytest.mark.parametrize(("dist", "ok"), [(0.19, True), (0.2, True), (0.21, False), (0.0, True)])
def test_colour_threshold(dist, ok):
    base = (0.3, 0.4, 0.5)
    other = (0.3, 0.4, 0.5 + dist)
    a = Figure.rectangle(20, 10, base)
    b = Figure.rectangle(20, 10, other, angle=1.0)
    assert (qshape.match(a, b) is not None) == ok
    assert qshape.match(a, b, use_color=False) is not None


def test_unknown_colour_matches_any_colour():
    assert qshape.match(Figure.rectangle(20, 10, (1, 0, 0)), Figure.rectangle(20, 10)) is not None


@pytest.mark.parametrize(("side", "ok"), [(13.9, True), (14.0, True), (14.1, False), (10.0, True)])
def test_size_threshold_from_joint(side, ok):
    # |side^2 - 100| <= joint 2 mm x mean perimeter (40 + 4 side) / 2  <=>  side <= 14
    a = Figure.rectangle(10.0, 10.0)
    b = Figure.rectangle(side, side, angle=0.3)
    assert (qshape.match(a, b) is not None) == ok


def test_size_absolute_threshold_and_switch():
    a, b = Figure.rectangle(10.0, 10.0), Figure.rectangle(11.0, 11.0)
    assert qshape.match(a, b, Tolerances(size_area_threshold=20.0)) is None
    assert qshape.match(a, b, Tolerances(size_area_threshold=21.0)) is not None
    assert qshape.match(a, Figure.rectangle(100.0, 100.0), Tolerances(check_size=False))
