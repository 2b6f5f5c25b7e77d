"""Rotation with holes: among the turns the outline allows, the whole figure decides.

A regular pentagon with a centred square hole has no rotational symmetry, but its outline has
five equivalent turns and the hole's qualitative position (the centre) is the same at each:
the hole's own orientation must choose. Checked on design figures (exact) and on rendered and
extracted pictures, through `qshape.match` and `qshape.assign`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from qshape import Boundary, Figure, assign, match
from qshape.design import Design, Slot
from qshape.synthetic.render import render_design
from qshape.vision.extract import extract_detailed

PX_PER_MM = 2.05
"""The default input camera's scale on the tile tops [px/mm] (0.24 m over 492 px)."""
ANGLES = (0.0, 37.0, 72.0, 100.0, 144.0, 200.0, 290.0, 333.0)
CASES = [
    # (outline, hole, hole centre, symmetry of the whole tile)
    (
        {"kind": "regular_polygon", "sides": 5, "radius": 22},
        {"kind": "square", "size": 12},
        (0, 0),
        1,
    ),
    (
        {"kind": "regular_polygon", "sides": 6, "radius": 22},
        {"kind": "square", "size": 12},
        (0, 0),
        2,
    ),
    (
        {"kind": "regular_polygon", "sides": 6, "radius": 22},
        {"kind": "regular_polygon", "sides": 3, "radius": 8},
        (0, 0),
        3,
    ),
    (
        {"kind": "regular_polygon", "sides": 6, "radius": 22},
        {"kind": "regular_polygon", "sides": 5, "radius": 8},
        (0, 0),
        1,
    ),
    (
        {"kind": "square", "size": 40},
        {"kind": "regular_polygon", "sides": 3, "radius": 8},
        (0, 0),
        1,
    ),
    ({"kind": "square", "size": 40}, {"kind": "rectangle", "width": 14, "height": 7}, (0, 0), 2),
    (
        {"kind": "regular_polygon", "sides": 5, "radius": 22},
        {"kind": "rectangle", "width": 14, "height": 7},
        (4, 2),
        1,
    ),
    (
        {"kind": "regular_polygon", "sides": 6, "radius": 22},
        {"kind": "regular_polygon", "sides": 3, "radius": 7},
        (5, 0),
        1,
    ),
    ({"kind": "square", "size": 40}, {"kind": "square", "size": 10}, (8, 3), 1),
]
IDS = [
    "pentagon-square",
    "hexagon-square",
    "hexagon-triangle",
    "hexagon-pentagon",
    "square-triangle",
    "square-rectangle",
    "pentagon-rect-off",
    "hexagon-triangle-off",
    "square-square-off",
]


def _design(outline: dict[str, Any], hole: dict[str, Any], at: tuple[float, float]) -> Design:
    slots = []
    for i, a in enumerate(ANGLES):
        shape = {**outline, "holes": [{**hole, "x": at[0], "y": at[1], "angle": 10.0}]}
        slots.append(
            {
                "name": f"s{i}",
                "shape": shape,
                "color": "#c0392b",
                "pose": {"x": 30 + 55 * (i % 4), "y": 30 + 55 * (i // 4), "angle": a},
            }
        )
    return Design.from_dict(
        {"name": "holed", "mesh": {"width": 230, "height": 120}, "joint": 2.0, "slots": slots}
    )


def _error_deg(rotation: float, angle_deg: float, symmetry: int) -> float:
    period = 360.0 / max(symmetry, 1)
    return (math.degrees(rotation) - angle_deg + period / 2.0) % period - period / 2.0


@pytest.mark.parametrize(("outline", "hole", "at", "symmetry"), CASES, ids=IDS)
def test_design_figures_turn_the_one_right_way(
    outline: dict, hole: dict, at: tuple, symmetry: int
) -> None:
    design = _design(outline, hole, at)
    ref = design.slots[0]
    assert ref.symmetry == symmetry
    for s in design.slots:
        # The tile as it lies: the slot turned, at the origin (match aligns centroids).
        tile = Slot("tile", s.shape, s.color, 0.0, 0.0, s.angle, s.rules).figure()
        m = match(ref.figure(), tile)
        assert m is not None
        assert abs(_error_deg(-m.rotation, s.angle, symmetry)) < 0.5  # tile onto slot


@pytest.mark.parametrize(("outline", "hole", "at", "symmetry"), CASES[:5], ids=IDS[:5])
def test_assign_chooses_the_turn_by_the_hole(
    outline: dict, hole: dict, at: tuple, symmetry: int
) -> None:
    design = _design(outline, hole, at)
    ref = design.slots[0].figure()
    tiles = [
        Slot("tile", s.shape, s.color, 0.0, 0.0, s.angle, s.rules).figure() for s in design.slots
    ]
    result = assign(tiles, [ref] * len(tiles))
    assert len(result) == len(tiles)
    for a in result:
        angle = design.slots[a.tile].angle
        assert abs(_error_deg(-a.rotation, angle, symmetry)) < 0.5  # tile onto slot


def _measured(fig: Figure) -> Figure:
    """A pixel figure (y down) in millimetres."""
    holes = [
        Boundary.make(
            np.asarray(h.points) / PX_PER_MM, np.asarray(h.curve_mask), y_down=True, what="hole"
        )
        for h in fig.holes
    ]
    return Figure.from_polygon(
        np.asarray(fig.outer.points) / PX_PER_MM,
        holes,
        fig.color,
        curve_mask=np.asarray(fig.outer.curve_mask),
        y_down=True,
    )


@pytest.mark.parametrize(("outline", "hole", "at", "symmetry"), CASES, ids=IDS)
def test_rendered_tiles_turn_the_one_right_way(
    outline: dict, hole: dict, at: tuple, symmetry: int
) -> None:
    design = _design(outline, hole, at)
    ref = design.slots[0].figure()
    image = render_design(design, px_per_mm=PX_PER_MM)
    height_mm = image.shape[0] / PX_PER_MM
    figures = extract_detailed(image).figures
    assert len(figures) == len(ANGLES)
    right = 0
    for f in figures:
        cx, cy = np.asarray(f.centroid) / PX_PER_MM
        s = min(design.slots, key=lambda q: math.hypot(q.x - cx, q.y - (height_mm - cy)))
        m = match(ref, _measured(f))
        if m is None:
            continue  # a hole traced with a corner too many or too few: no match, not a wrong turn
        assert abs(_error_deg(-m.rotation, s.angle, symmetry)) < 3.0, s.name
        right += 1
    assert right >= len(ANGLES) - 2
