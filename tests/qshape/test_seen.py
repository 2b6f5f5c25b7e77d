"""A design's outline described as a picture's outline simplification sees it."""

from __future__ import annotations

import numpy as np
import pytest

from qshape import ExtractParams, Figure, Tolerances, extract_detailed, match
from qshape.design import Design
from qshape.design.shape_maps import rounded_polygon_shape
from qshape.errors import InvalidFigureError
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.seen import near_turns, seen_figure

PX_PER_MM = 2.05  # the default input camera's scale on the tile tops
BUNDLED = ("paper_mixed", "square_grid", "hexagon", "trencadis")


def _rounded_squares(which: list[bool]) -> Design:
    # 46 mm squares, the corners ``which`` rounded by 17.5 mm arcs tangent to both edges
    # (sagitta 5.1 mm, chord 24.7 mm: above the smallest recognised arc).
    h = 23.0
    v = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
    shape = rounded_polygon_shape(v, 17.5, np.array(which))
    slots = [
        {
            "name": f"t{i}",
            "shape": shape,
            "color": "#c0392b",
            "pose": {"x": 40 + 75 * (i % 3), "y": 60 + 100 * (i // 3), "angle": 37.0 * i},
        }
        for i in range(6)
    ]
    mesh = {"width": 230, "height": 230}
    return Design.from_dict({"name": "rounded", "mesh": mesh, "joint": 2.0, "slots": slots})


def _pixels(fig: Figure, s: float) -> Figure:
    """A y-up millimetre figure scaled to pixels (same frame)."""
    return Figure.from_polygon(fig.points * s, [], fig.color, curve_mask=fig.curve_mask)


def _pixel_tolerances(design: Design) -> Tolerances:
    mm = Tolerances.load()
    return Tolerances.load(
        joint_width=design.joint * PX_PER_MM, point_tolerance=mm.point_tolerance * PX_PER_MM
    )


@pytest.mark.parametrize("which", [[True] * 4, [True, False, True, False]])
def test_a_rounded_square_matches_as_the_picture_sees_it(which: list[bool]) -> None:
    design = _rounded_squares(which)
    tol = _pixel_tolerances(design)
    params = ExtractParams.load()
    own = _pixels(design.slots[0].figure(), PX_PER_MM)
    seen = seen_figure(design.slots[0].figure(), params.outline, PX_PER_MM)
    # The design puts a vertex at both tangent ends of every arc; a picture has no corner
    # there, so its figure has fewer relevant points and no labelling of it matches.
    assert len(seen.points) < len(own.points)
    seen_px = _pixels(seen, PX_PER_MM)
    found = own_hits = seen_hits = 0
    for seed in range(4):
        img = generate(design, 6, np.random.default_rng(seed), SynthParams(px_per_mm=PX_PER_MM))
        for fig in extract_detailed(img.image, params).figures:
            found += 1
            own_hits += match(own, fig, tol) is not None
            seen_hits += match(seen_px, fig, tol) is not None
    assert found == 24
    assert own_hits == 0
    assert seen_hits == found


def test_a_plain_square_does_not_match_a_rounded_one_as_seen() -> None:
    design = _rounded_squares([True] * 4)
    seen_px = _pixels(seen_figure(design.slots[0].figure(), ExtractParams.load().outline, 1.0), 1)
    square = Figure.rectangle(46.0, 46.0, seen_px.color)
    assert match(seen_px, square, Tolerances.load()) is None


@pytest.mark.parametrize("name", BUNDLED)
def test_the_bundled_designs_are_seen_as_they_are_described(name: str) -> None:
    # What keeps the bundled designs' figures unchanged: each class's seen figure matches its
    # own description, so no slot of theirs gets a second description.
    design = Design.load(name)
    tol = _pixel_tolerances(design)
    outline = ExtractParams.load().outline
    done: set[str] = set()
    for slot in design.slots:
        if slot.class_key in done:
            continue
        done.add(slot.class_key)
        own = slot.figure()
        seen = seen_figure(own, outline, PX_PER_MM)
        assert match(_pixels(own, PX_PER_MM), _pixels(seen, PX_PER_MM), tol) is not None, slot.name
        assert len(seen.holes) == len(own.holes) and seen.color == own.color


@pytest.mark.parametrize("scale", [0.0, -1.0, float("nan")])
def test_the_scale_must_be_positive(scale: float) -> None:
    square = Figure.rectangle(40.0, 40.0)
    with pytest.raises(InvalidFigureError, match="px_per_mm"):
        seen_figure(square, ExtractParams.load().outline, scale)


def test_near_turns_count_the_turns_a_figure_nearly_has() -> None:
    assert near_turns(Figure.rectangle(40.0, 40.0), 0.01) == 4
    assert near_turns(Figure.rectangle(40.0, 30.0), 0.01) == 2
    scalene = Figure.from_polygon([[0.0, 0.0], [0.0, 30.0], [44.0, 0.0]])
    assert near_turns(scalene, 0.05) == 1
    # A rectangle of 40 x 38 mm is a square within a residual of about 0.02.
    assert near_turns(Figure.rectangle(40.0, 38.0), 0.01) == 2
    assert near_turns(Figure.rectangle(40.0, 38.0), 0.05) == 4
