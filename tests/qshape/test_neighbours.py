"""Structural neighbours at match time (`qshape.theory.neighbours`, `qshape.match_best`).

The measured outlines below are real: relevant points `qshape.extract` found on the realistic
benchmark level's pictures (2.5 px/mm, blur, roughness, chips) for tiles that matched no class
as measured: a hexagon whose corner blur cut into two (a chamfer), and trencadis pieces whose
shallow corner was placed several pixels along its edge.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import qshape
from qshape import Boundary, Figure, Tolerances, describe, match, match_best
from qshape.design import Design
from qshape.errors import MatchError, ToleranceError
from qshape.theory.neighbours import neighbours

_PX_PER_MM = 2.5

_CHAMFERED_HEXAGON = [
    [589.19, 198.65],
    [627.55, 226.29],
    [619.21, 269.88],
    [580.46, 288.45],
    [552.39, 271.39],
    [544.0, 254.72],
    [547.07, 217.93],
]
_SLID_TRENCADIS_A = [
    [233.41, 12.7],
    [260.28, 35.03],
    [241.64, 62.93],
    [261.7, 100.91],
    [222.38, 117.0],
    [192.15, 82.15],
    [189.24, 44.76],
]
_SLID_TRENCADIS_B = [
    [392.16, 202.42],
    [413.31, 207.95],
    [446.15, 283.89],
    [367.37, 312.74],
    [349.25, 285.02],
    [381.51, 258.39],
]


def _classes(name: str) -> tuple[dict[str, Figure], Tolerances]:
    """A design's shape classes in pixels and the tolerances scaled to them."""
    design = Design.load(name)
    tol = Tolerances.load(joint_width=design.joint * _PX_PER_MM, point_tolerance=0.5 * _PX_PER_MM)
    refs: dict[str, Figure] = {}
    for slot in design.slots:
        if slot.shape_key in refs:
            continue
        fig = slot.figure()
        holes = [Boundary.make(h.points * _PX_PER_MM, h.curve_mask) for h in fig.holes]
        refs[slot.shape_key] = Figure.from_polygon(
            fig.points * _PX_PER_MM, holes, fig.color, curve_mask=fig.curve_mask
        )
    return refs, tol


@pytest.mark.parametrize(
    ("points", "design", "key"),
    [
        (_CHAMFERED_HEXAGON, "hexagon", "0ef3e0c1dfd3"),
        (_SLID_TRENCADIS_A, "trencadis", "747e3bab6f48"),
        (_SLID_TRENCADIS_B, "trencadis", "e522c4465ef9"),
    ],
)
def test_measured_misses_match_through_one_neighbour(
    points: list[list[float]], design: str, key: str
) -> None:
    refs, tol = _classes(design)
    cand = Figure.from_polygon(points, y_down=True)
    assert all(match(ref, cand, tol, use_color=False) is None for ref in refs.values())
    found = match_best(refs, cand, tol, use_color=False)
    assert found is not None
    got, m = found
    assert got == key
    assert m.neighbour is not None
    assert m.score <= tol.neighbour_residual
    # Off: the figure as measured matches nothing.
    off = Tolerances.load(
        joint_width=tol.joint_width, point_tolerance=tol.point_tolerance, neighbour_residual=0.0
    )
    assert match_best(refs, cand, off, use_color=False) is None


def test_chamfer_merges_into_the_cut_corner() -> None:
    _, tol = _classes("hexagon")
    desc = describe(Figure.from_polygon(_CHAMFERED_HEXAGON, y_down=True), tol)
    six = [d for d in neighbours(desc, tol) if len(d.outer.codes) == 6]
    # The chamfer's two corners (turning 32 and 31 deg) merged, and each removed alone.
    assert len(six) == 3
    # The merged corner lies on both outer edges' lines: its turn is the two turns' sum.
    turns = []
    for d in six:
        p = d.outer.points
        u = p - np.roll(p, 1, axis=0)
        v = np.roll(p, -1, axis=0) - p
        turns.append(np.degrees(np.arctan2(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0], (u * v).sum(1))))
    assert sum(bool(np.isclose(np.abs(t), 32.0 + 31.5, atol=0.5).any()) for t in turns) == 1


def test_sharp_figures_have_no_neighbours() -> None:
    tol = Tolerances.load()
    for fig in (
        Figure.regular_polygon(6, 20.0),
        Figure.rectangle(30.0, 20.0),
        Figure.regular_polygon(3, 20.0),
        Figure.circle(10.0),
        Figure.semicircle(10.0),
    ):
        assert neighbours(describe(fig, tol), tol) == []


def test_weak_corner_on_an_edge_is_removed() -> None:
    # A 40 x 30 rectangle whose top edge bends by 2 x 16 deg at a point 1 mm above it.
    tol = Tolerances.load()
    bent = Figure.from_polygon([[0, 0], [0, 30], [20, 31], [40, 30], [40, 0]])
    rect = Figure.rectangle(40.0, 30.0)
    assert match(rect, bent, tol) is None
    found = match_best({"rect": rect}, bent, tol)
    assert found is not None and found[0] == "rect"
    assert found[1].neighbour is not None and len(found[1].neighbour.outer.codes) == 4


def test_a_neighbour_matching_two_references_is_no_match() -> None:
    tol = Tolerances.load()
    bent = Figure.from_polygon([[0, 0], [0, 30], [20, 31], [40, 30], [40, 0]])
    rect = Figure.rectangle(40.0, 30.0)
    assert match_best({"a": rect, "b": Figure.rectangle(40.0, 30.0)}, bent, tol) is None


def test_direct_matches_pick_as_the_lowest_score() -> None:
    tol = Tolerances.load()
    refs = {
        "square": Figure.rectangle(20.0, 20.0),
        "square_b": Figure.rectangle(20.2, 20.0),
        "hexagon": Figure.regular_polygon(6, 12.0),
    }
    rng = np.random.default_rng(3)
    for _ in range(10):
        pts = Figure.rectangle(20.0, 20.0).points + rng.normal(0.0, 0.2, (4, 2))
        cand = Figure.from_polygon(pts)
        scores = {k: m.score for k, r in refs.items() if (m := match(r, cand, tol)) is not None}
        found = match_best(refs, cand, tol)
        assert found is not None
        assert found[0] == min(scores, key=lambda k: scores[k])
        assert found[1].neighbour is None
        assert math.isclose(found[1].score, scores[found[0]])


def test_match_best_errors() -> None:
    with pytest.raises(MatchError, match="mapping"):
        match_best([Figure.rectangle(1.0, 1.0)], Figure.rectangle(1.0, 1.0))  # type: ignore[arg-type]
    with pytest.raises(MatchError):
        match_best({"a": 3}, Figure.rectangle(1.0, 1.0))  # type: ignore[dict-item]
    assert qshape.match_best is match_best


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("weak_turn_deg", 90.0),
        ("weak_turn_deg", -1.0),
        ("weak_pair_fraction", -0.5),
        ("weak_slide_fraction", -0.1),
        ("neighbour_residual", -0.01),
    ],
)
def test_weak_corner_tolerances_are_checked(field: str, value: float) -> None:
    with pytest.raises(ToleranceError, match=field):
        Tolerances.load(None, **{field: value})
