"""Figures and boundaries: measures and orientation, primitives, holes, immutability, bad input
refused; the one-pass boundary checks and measures equal the one-by-one ones.
"""

import math

import numpy as np
import pytest

from qshape import Boundary, Figure, InvalidFigureError, InvalidHoleError, QShapeError
from qshape.geometry import signed_area

SQ = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]


def test_square_measures_and_orientation():
    f = Figure.from_polygon(SQ, color=(1, 0, 0))
    assert f.area == pytest.approx(100.0)
    assert f.perimeter == pytest.approx(40.0)
    np.testing.assert_allclose(f.centroid, [5.0, 5.0])
    assert signed_area(f.points) < 0  # clockwise (y-up), the paper's walk
    assert f.color == (1.0, 0.0, 0.0)
    g = Figure.from_polygon(SQ[::-1])
    assert signed_area(g.points) < 0


def test_y_down_orientation_is_clockwise_as_seen():
    f = Figure.from_polygon(SQ, y_down=True)
    assert signed_area(f.points) > 0  # clockwise on screen = CCW in y-down math coordinates
    assert f.area == pytest.approx(100.0)


def test_closing_point_is_dropped():
    f = Figure.from_polygon([*SQ, SQ[0]])
    assert len(f.points) == 4


def test_primitives_area_centroid():
    assert Figure.circle(3.0).area == pytest.approx(math.pi * 9)
    ring = Figure.ring(5.0, 2.0, center=(7.0, -3.0))
    assert ring.area == pytest.approx(math.pi * 21)
    np.testing.assert_allclose(ring.centroid, [7.0, -3.0], atol=1e-12)
    semi = Figure.semicircle(6.0, angle=math.pi / 2, center=(1.0, 1.0))
    assert semi.area == pytest.approx(math.pi * 18)
    np.testing.assert_allclose(semi.centroid, [1.0 - 8.0 / math.pi, 1.0], atol=1e-12)
    hexagon = Figure.regular_polygon(6, 2.0)
    assert hexagon.area == pytest.approx(3 * math.sqrt(3) / 2 * 4)
    rect = Figure.rectangle(4.0, 2.0, center=(1.0, 2.0), angle=0.3)
    assert rect.area == pytest.approx(8.0)
    np.testing.assert_allclose(rect.centroid, [1.0, 2.0])


def test_holed_area_and_centroid():
    hole = [[1.0, 1.0], [3.0, 1.0], [3.0, 3.0], [1.0, 3.0]]
    f = Figure.from_polygon(SQ, holes=[hole])
    assert f.area == pytest.approx(96.0)
    np.testing.assert_allclose(f.centroid, [(500 - 8) / 96, (500 - 8) / 96])
    assert f.holes[0].points.shape == (4, 2)


def test_figures_are_immutable_values():
    f = Figure.rectangle(2, 1)
    with pytest.raises(ValueError):
        f.points[0, 0] = 5.0
    assert f == Figure.rectangle(2, 1)
    assert f != Figure.rectangle(2, 1.5)


@pytest.mark.parametrize(
    ("points", "message"),
    [
        ([[0, 0], [1, 1]], "at least 3"),
        ([], "shape|at least 3"),
        ([[0, 0], [1, 0], [float("nan"), 1]], "finite"),
        ([[0, 0], [1, 0], [float("inf"), 1]], "finite"),
        ([[0, 0], [1, 0], [1, 1], [1, 0], [0, 1]], "repeated"),
        ([[0, 0], [1, 1], [2, 2]], "zero area"),
        ([[0, 0], [2, 2], [2, 0], [0, 2]], "crosses"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "shape"),
        ([["a", 0], [1, 0], [0, 1]], "numbers"),
        ([[0, 0], [0, 0], [0, 0]], "at least 3|coincide"),
    ],
)
def test_bad_polygons_raise(points, message):
    with pytest.raises(InvalidFigureError, match=message):
        Figure.from_polygon(points)


def test_bad_curve_masks_raise():
    with pytest.raises(InvalidFigureError, match="adjacent curve"):
        Figure.from_polygon(SQ, curve_mask=[True, True, False, False])
    with pytest.raises(InvalidFigureError, match="shape"):
        Figure.from_polygon(SQ, curve_mask=[True, False])
    with pytest.raises(InvalidFigureError, match="booleans"):
        Figure.from_polygon(SQ, curve_mask=[1, 0, 0, 0])


@pytest.mark.parametrize(
    ("hole", "message"),
    [
        ([[20, 20], [22, 20], [22, 22], [20, 22]], "outside"),
        ([[8, 4], [12, 4], [12, 6], [8, 6]], "crosses"),
        ([[0, 4], [4, 4], [4, 6], [0, 6]], "touches|crosses"),
    ],
)
def test_bad_holes_raise(hole, message):
    with pytest.raises(InvalidHoleError, match=message):
        Figure.from_polygon(SQ, holes=[hole])


def test_overlapping_and_nested_holes_raise():
    a = [[1, 1], [5, 1], [5, 5], [1, 5]]
    b = [[3, 3], [7, 3], [7, 7], [3, 7]]
    inner = [[2, 2], [3, 2], [3, 3], [2, 3]]
    with pytest.raises(InvalidHoleError, match="overlap"):
        Figure.from_polygon(SQ, holes=[a, b])
    with pytest.raises(InvalidHoleError, match="overlap"):
        Figure.from_polygon(SQ, holes=[a, inner])


def test_ring_needs_smaller_inner_radius_and_hole_inside_arc():
    with pytest.raises(InvalidHoleError):
        Figure.ring(2.0, 3.0)
    # a hole inside the disc but outside the inscribed square of the relevant points is fine
    ring = Figure.ring(10.0, 8.5)
    assert len(ring.holes) == 1


@pytest.mark.parametrize(
    "call",
    [
        lambda: Figure.rectangle(0, 1),
        lambda: Figure.rectangle(-1, 1),
        lambda: Figure.circle(float("nan")),
        lambda: Figure.regular_polygon(2, 1.0),
        lambda: Figure.regular_polygon(3.5, 1.0),
        lambda: Figure.rectangle(1, 1, color=(2, 0, 0)),
        lambda: Figure.rectangle(1, 1, color=(0.5, 0.5)),
        lambda: Figure.rectangle(1, 1, color="red"),
    ],
)
def test_bad_primitive_arguments_raise(call):
    with pytest.raises(QShapeError):
        call()


def test_boundary_make_normalises():
    b = Boundary.make(SQ)
    assert signed_area(b.points) < 0
    assert not b.curve_mask.any()


def test_huge_coordinates_are_rejected_not_overflowed():
    with pytest.raises(InvalidFigureError, match="magnitude"):
        Figure.from_polygon([[1e308, 1e308], [-1e308, 1e308], [0, -1e308]])
    with pytest.raises(InvalidFigureError, match="magnitude"):
        Figure.from_outline([[1e308, 1e308], [-1e308, 1e308], [0, -1e308]])


def _batch_cases() -> list[tuple[np.ndarray, np.ndarray]]:
    """Simplified boundaries of every kind: convex either way round, concave, invalid."""
    rng = np.random.default_rng(3)
    cases = []
    for n in (3, 4, 6, 9):
        t = np.sort(rng.uniform(0.0, 2.0 * math.pi, n))
        ring = np.stack([40.0 + 20.0 * np.cos(t), 30.0 + 15.0 * np.sin(t)], axis=1)
        cases += [(ring, np.zeros(n, bool)), (ring[::-1].copy(), np.zeros(n, bool))]
    arrow = np.array([[0.0, 0.0], [10.0, 5.0], [0.0, 10.0], [4.0, 5.0]])
    cases.append((arrow, np.zeros(4, bool)))  # concave
    cases.append((np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]), np.zeros(4, bool)))
    cases.append((np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 0.0], [0.0, 3.0]]), np.zeros(4, bool)))
    bow = np.array([[0.0, 0.0], [4.0, 4.0], [4.0, 0.0], [0.0, 4.0]])
    cases.append((bow, np.zeros(4, bool)))  # crosses itself
    square = np.array(SQ)
    cases.append((square, np.array([True, True, False, False])))  # adjacent curve points
    cases.append((square + 1e9, np.zeros(4, bool)))  # far from the origin, small
    return cases


@pytest.mark.parametrize("y_down", [False, True])
def test_boundaries_validated_in_one_pass_as_one_by_one(y_down: bool) -> None:
    """The one-pass check keeps, orients and refuses exactly as `Boundary.from_simplified`."""
    from qshape.theory.boundary import boundaries_many  # noqa: PLC0415

    cases = _batch_cases()
    whats = [f"figure {k}" for k in range(len(cases))]
    batch = boundaries_many(cases, y_down=y_down, whats=whats)
    for (pts, mask), what, got in zip(cases, whats, batch, strict=True):
        try:
            want = Boundary.from_simplified(pts, mask, y_down=y_down, what=what)
        except InvalidFigureError as exc:
            assert isinstance(got, InvalidFigureError)
            assert str(got) == str(exc)
            continue
        assert isinstance(got, Boundary)
        assert got == want


def test_measures_in_one_pass_as_one_by_one() -> None:
    """Areas, centroids and perimeters of the batch equal the per-boundary ones."""
    from qshape.theory.boundary import measures_many  # noqa: PLC0415

    bounds = []
    for (pts, mask), y_down in zip(_batch_cases(), [False, True] * 20, strict=False):
        try:
            bounds.append(Boundary.from_simplified(pts, mask, y_down=y_down, what="b"))
        except InvalidFigureError:
            continue
    bounds.append(Figure.circle(5.0, center=(3.0, 4.0)).outer)  # an arc: measured alone
    assert len(bounds) >= 10
    for b, (area, centroid, perimeter) in zip(bounds, measures_many(bounds), strict=True):
        a, c, p = b.measures()
        assert area == pytest.approx(a, rel=1e-12)
        assert perimeter == pytest.approx(p, rel=1e-12)
        np.testing.assert_allclose(centroid, c, rtol=1e-12, atol=1e-12 * max(abs(a), 1.0))
