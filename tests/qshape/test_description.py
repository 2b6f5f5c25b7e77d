"""Descriptions of figures: labels of squares, rectangles, L tiles, triangles, curves and holes;
invariance to start vertex, orientation, translation and scale; the batch equals one by one.
"""

import math

import numpy as np
import pytest

import qshape
from qshape import Description, Figure, ParseError, Tolerances, describe, parse
from qshape.theory.description import describe_many

RNG_SEED = 1234
L_TILE = [[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]]


def labels(d: Description) -> list[tuple[str, str, str]]:
    return [n.labels for n in d.nodes]


def test_square_description():
    d = describe(Figure.rectangle(10, 10, (0.5, 0.5, 0.5)))
    assert d.type_hole == "without holes"
    assert d.type_curve == "without curves"
    assert labels(d) == [("right", "convex", "equal")] * 4
    assert d.color == (0.5, 0.5, 0.5)
    assert d.area == pytest.approx(100.0)


def test_rectangle_and_start_vertex_is_upper_left():
    d = describe(Figure.rectangle(20, 10))
    np.testing.assert_allclose(d.outer.points[0], [-10.0, 5.0])
    assert labels(d) == [("right", "convex", "smaller"), ("right", "convex", "bigger")] * 2


def test_l_tile_is_concave_at_one_vertex():
    d = describe(Figure.from_polygon(L_TILE))
    conv = [n.labels[1] for n in d.nodes]
    assert conv.count("concave") == 1
    assert all(n.labels[0] == "right" for n in d.nodes)


def test_triangles():
    right_iso = describe(Figure.from_polygon([[0, 0], [10, 0], [0, 10]]))
    assert sorted(n.labels[0] for n in right_iso.nodes) == ["acute", "acute", "right"]
    equi = describe(Figure.regular_polygon(3, 5.0))
    assert labels(equi) == [("acute", "convex", "equal")] * 3


def test_curves():
    semi = describe(Figure.semicircle(5.0))
    assert semi.type_curve == "with curves"
    kinds = [n.labels for n in semi.nodes]
    assert ("Curve", "convex", "semicircle") in kinds
    circle = describe(Figure.circle(5.0))
    assert circle.type_curve == "only curves"
    flat = describe(
        Figure.from_polygon(
            [[-10, 0], [0, 2], [10, 0], [0, -10]], curve_mask=[False, True, False, False]
        )
    )
    assert ("Curve", "convex", "plane") in [n.labels for n in flat.nodes]
    pointed = describe(
        Figure.from_polygon(
            [[-3, 0], [0, 10], [3, 0], [0, -3]], curve_mask=[False, True, False, False]
        )
    )
    assert ("Curve", "convex", "acute") in [n.labels for n in pointed.nodes]
    dent = describe(
        Figure.from_polygon(
            [[-10, 0], [0, 3], [10, 0], [10, 10], [-10, 10]],
            curve_mask=[False, True, False, False, False],
        )
    )
    assert ("Curve", "concave", "plane") in [n.labels for n in dent.nodes]


def test_ring_hole_is_centre():
    d = describe(Figure.ring(10, 4))
    assert d.type_hole == "with holes"
    assert d.holes[0].position == ("C",)
    assert d.holes[0].relation == "CIi"
    assert d.holes[0].boundary.type_curve == "only curves"


def holed_square(angle: float, hole_at=(5.0, -5.0)) -> Figure:
    c, s = math.cos(angle), math.sin(angle)
    rot = np.array([[c, s], [-s, c]])
    out = np.array([[-10, -10], [10, -10], [10, 10], [-10, 10]], float) @ rot
    hole = (np.array([[-2, -2], [2, -2], [2, 2], [-2, 2]], float) + hole_at) @ rot
    return Figure.from_polygon(out, [hole])


def test_hole_position_is_in_the_frame_of_the_first_vertex():
    d = describe(holed_square(0.0))
    # First vertex is the upper-left corner: north points to NW of the image, the hole at SE.
    assert d.holes[0].position == ("S",)
    rotated = describe(holed_square(math.radians(30)))  # another vertex becomes the first
    assert rotated.holes[0].position in {("S",), ("W",), ("E",), ("N",)}


def test_hole_starts_at_vertex_nearest_parent_first_vertex():
    d = describe(holed_square(0.0))
    first = d.outer.points[0]
    dist = np.hypot(*(d.holes[0].boundary.points - first).T)
    assert np.argmin(dist) == 0


def test_start_vertex_and_orientation_do_not_change_the_description():
    pts = np.array(L_TILE, float)
    ref = describe(Figure.from_polygon(pts))
    for k in range(len(pts)):
        assert describe(Figure.from_polygon(np.roll(pts, k, axis=0))) == ref
        assert describe(Figure.from_polygon(np.roll(pts[::-1], k, axis=0))) == ref


def test_y_down_figure_describes_like_its_y_up_mirror():
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(10):
        pts = rng.uniform(0, 50, (3, 2))
        pts = np.vstack([pts, pts.mean(axis=0) + [30, 30]])
        try:
            up = Figure.from_polygon(pts * [1, -1])
        except qshape.InvalidFigureError:
            continue
        down = Figure.from_polygon(pts, y_down=True)
        assert describe(down) == describe(up)
    hole_up = Figure.from_polygon(np.array(L_TILE) * [1, -1], holes=[[[2, -2], [5, -2], [5, -5]]])
    hole_down = Figure.from_polygon(L_TILE, holes=[[[2, 2], [5, 2], [5, 5]]], y_down=True)
    assert describe(hole_down) == describe(hole_up)


def test_translation_and_scale_keep_labels():
    rng = np.random.default_rng(RNG_SEED)
    base = Figure.from_polygon(L_TILE)
    ref = describe(base)
    for _ in range(5):
        shift = rng.uniform(-1000, 1000, 2)
        scale = rng.uniform(0.1, 10)
        d = describe(Figure.from_polygon(np.array(L_TILE) * scale + shift))
        assert np.array_equal(d.outer.codes, ref.outer.codes)
        np.testing.assert_allclose(d.outer.points, ref.outer.points * scale, atol=1e-9 * scale)


def test_describe_many_equals_describe():
    figs = [
        Figure.rectangle(20, 10, angle=0.2),
        Figure.ring(10, 4, (1, 1, 0)),
        Figure.semicircle(5, y_down=True),
        holed_square(0.4),
        Figure.from_polygon(L_TILE, y_down=True),
        Figure.regular_polygon(7, 3.0),
    ]
    assert describe_many(figs) == [describe(f) for f in figs]
    assert describe_many([]) == []


ROUND_TRIP = [
    Figure.rectangle(20, 10, (0.1, 0.2, 0.3), angle=0.123),
    Figure.ring(10, 4),
    Figure.semicircle(7.5, (1.0, 1.0, 1.0)),
    Figure.from_polygon(L_TILE),
    holed_square(0.7),
    Figure.from_polygon([[0, 0], [10, 0.15], [20, 0], [20, 10], [0, 10]]),  # ambiguous labels
]


@pytest.mark.parametrize("fig", ROUND_TRIP)
def test_text_round_trip_is_exact(fig):
    d = describe(fig, Tolerances())
    text = str(d)
    assert text.startswith("qshape-description v1\n")
    back = parse(text)
    assert back == d
    assert str(back) == text
    assert qshape.match(back, d) is not None


def test_ambiguous_labels_are_in_the_text():
    d = describe(Figure.from_polygon([[0, 0], [10, 0.15], [20, 0], [20, 10], [0, 10]]))
    assert "convex/concave" in str(d) or "concave/convex" in str(d)
    assert any(n.ambiguous for n in d.nodes)


def test_text_is_readable():
    text = str(describe(Figure.ring(10, 4, (0.5, 0.25, 1.0))))
    assert "type: with holes, only curves" in text
    assert "color: 0.5 0.25 1.0" in text
    assert "<Curve, convex, semicircle>" in text
    assert "hole: CIi [C] only curves, nodes: 4" in text


GOOD = str(describe(Figure.ring(10, 4, (0.5, 0.25, 1.0))))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "header"),
        ("hello\n", "header"),
        (GOOD.replace("type: with holes, only curves", "type: maybe holes, only curves"), "type"),
        (GOOD.replace("color: 0.5 0.25 1.0", "color: 0.5 0.25"), "color"),
        (GOOD.replace("color: 0.5 0.25 1.0", "color: 0.5 0.25 7"), r"\[0, 1\]"),
        (GOOD.replace("area: ", "area: x"), "area"),
        (GOOD.replace("nodes: 4\n", "nodes: 40\n", 1), "ends"),
        (GOOD.replace("nodes: 4\n", "nodes: two\n", 1), "node count"),
        (GOOD.replace("<Curve, convex, semicircle>", "<Curve, round, semicircle>", 1), "round"),
        (GOOD.replace("<right, convex, equal>", "<right, convex>", 1), "node"),
        (GOOD.replace("<right, convex, equal>", "<right/right, convex, equal>", 1), "repeated"),
        (GOOD.replace("CIi [C]", "CI [C]"), "relation"),
        (GOOD.replace("CIi [C]", "CIi [X]"), "position"),
        (GOOD.replace("CIi [C]", "CIi [C, N]"), "position"),
        (GOOD.replace("type: with holes", "type: without holes"), "holes"),
        (GOOD.replace("only curves\n", "with curves\n", 1), "type"),
        (GOOD + "garbage line\n", "hole"),
        (GOOD.replace("@ (", "@ (nan", 1), "node|finite"),
    ],
)
def test_malformed_text_raises_parse_error(text, message):
    with pytest.raises(ParseError, match=message):
        parse(text)


def test_parse_rejects_non_strings():
    with pytest.raises(ParseError):
        parse(b"qshape-description v1")  # type: ignore[arg-type]
