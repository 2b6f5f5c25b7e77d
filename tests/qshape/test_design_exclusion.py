"""Tile classes kept out of drawn designs: equality by the theory's matching, redraws, refusal."""

from __future__ import annotations

import numpy as np
import pytest

from qshape.design import Design
from qshape.design.exclusion import ClassExclusion, draw_excluding
from qshape.design.generator import DesignGenerator
from qshape.design.generator_config import GeneratorConfig
from qshape.errors import DesignError, ExcludedClassError

HEX_COLORS = ("#3f9e4d", "#e8c33a", "#8e4fb5")
"""The colours of the bundled ``hexagon`` design's classes."""
HEXAGON_ONLY = GeneratorConfig(
    tiles=(6, 6),
    classes=(1, 1),
    size_mm=(36.0, 36.0),  # the bundled hexagon's circumradius 18 mm
    families={"regular": 1.0},
    hole_probability=0.0,
    recolor_probability=0.0,
    turns_deg=0.0,
    palette=(HEX_COLORS[0],),
)
"""A generator of one class of regular polygons (3-8 sides) the size and colour of ``hexagon``'s
green tiles: a sixth of its designs are the hexagon design's green class."""


def _is_hexagon_class(design: Design) -> bool:
    return any(
        s.shape.get("kind") == "regular_polygon" and s.shape.get("sides") == 6 for s in design.slots
    )


def _regular_polygons(color: str) -> Design:
    """A design of one regular polygon of every side count the generator draws (3-8), r 18 mm."""
    slots = [
        {
            "name": f"p{n}",
            "shape": {"kind": "regular_polygon", "sides": n, "radius": 18.0},
            "color": color,
            "pose": {"x": 25.0 + 40.0 * (n - 3), "y": 115.0, "angle": 0.0},
        }
        for n in range(3, 9)
    ]
    data = {"name": "regulars", "mesh": {"width": 250.0, "height": 230.0}, "joint": 2.0}
    return Design.from_dict({**data, "slots": slots})


def test_a_design_shares_its_classes_with_itself_and_not_with_other_shapes() -> None:
    hexagon, trencadis = Design.load("hexagon"), Design.load("trencadis")
    held_out = ClassExclusion([hexagon, trencadis])
    clashes = held_out.clashes(hexagon)
    assert len(clashes) == 3  # three colours of one hexagon
    assert all(c.excluded.design == "hexagon" for c in clashes)
    assert "is the class of 'hexagon' slot" in str(clashes[0])
    assert held_out.clashes(trencadis)
    for name in ("paper_mixed", "square_grid"):  # the rung's training designs hold none
        assert held_out.clashes(Design.load(name)) == []


def test_colour_tells_classes_apart() -> None:
    green = ClassExclusion([_regular_polygons("#3f9e4d")])
    assert len(green.clashes(_regular_polygons("#3f9e4d"))) == 6
    assert green.clashes(_regular_polygons("#c0392b")) == []


def test_drawn_designs_holding_an_excluded_class_are_drawn_again() -> None:
    gen = DesignGenerator(HEXAGON_ONLY)
    held_out = ClassExclusion([Design.load("hexagon")])
    plain = [gen.draw(np.random.default_rng(s)) for s in range(24)]
    hexagons = [d for d in plain if _is_hexagon_class(d)]
    assert hexagons  # the generator does draw the held-out class ...
    assert all(held_out.clashes(d) for d in hexagons)  # ... which the theory recognises
    assert not any(held_out.clashes(d) for d in plain if not _is_hexagon_class(d))
    for s in range(24):
        design = draw_excluding(gen, np.random.default_rng(s), held_out, tries=50)
        assert not _is_hexagon_class(design)
        assert held_out.clashes(design) == []


def test_a_generator_that_only_draws_excluded_classes_is_refused() -> None:
    gen = DesignGenerator(HEXAGON_ONLY)
    every_regular = ClassExclusion([_regular_polygons(HEX_COLORS[0])])
    with pytest.raises(ExcludedClassError, match=r"every one of 5 drawn designs.*'regulars'"):
        draw_excluding(gen, np.random.default_rng(0), every_regular, tries=5)
    with pytest.raises(DesignError, match="tries must be an int >= 1"):
        draw_excluding(gen, np.random.default_rng(0), every_regular, tries=0)
