"""The placement contract on exact figures: commands, reasons, seen outlines and refinements.

Tiles and slots are built from exact polygons (world mm for tiles, mesh mm for slots, no
render), so every documented field and branch of `agents.scripted.placement` is pinned to a
value: where a command picks and places, which turn it takes, why a tile is left out.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import qshape
from agents.scripted.config import PlacementConfig
from agents.scripted.outline_fit import TileOutline, fit_outline
from agents.scripted.perception import PerceivedTile, SlotTarget
from agents.scripted.placement import (
    REASONS,
    FeasiblePairs,
    PickPlace,
    fitted_command,
    outline_residual,
    plan_placements,
    refine_rotation,
    wrap,
)
from agents.scripted.seen_slots import SeenSlot
from envs.task_spec import PickPlaceCommand
from qshape import Figure, describe
from qshape.theory.tolerances import default_tolerances
from spatial.angles import rotate_xy, symmetry_period
from spatial.units import MM_PER_M
from tests.agents.scripted.polygons import BLUE, ELL, RED, SQUARE, turned

# The L with its outer corner cut 8 mm back: a design corner a picture would not show.
CUT_ELL = np.array([[8, 0], [40, 0], [40, 14], [14, 14], [14, 40], [0, 40], [0, 8]], float)
TRIANGLE = np.array([[0, 0], [40, 0], [20, 30]], float)


def _tile(
    index: int,
    points: np.ndarray,
    color: tuple[float, float, float] = RED,
    outline: np.ndarray | None = None,
) -> PerceivedTile:
    """A perceived tile whose figure is ``points`` (world mm); grasp 3 mm off its centre."""
    fig = Figure.from_polygon(points, color=color)
    centre = np.asarray(fig.centroid) / MM_PER_M
    grasp = centre + [0.003, 0.001]
    return PerceivedTile(
        index, fig, fig, describe(fig), centre, centre, grasp, color, fig.area * 1e-6, None, outline
    )


def _slot(
    index: int,
    points: np.ndarray,
    pose: tuple[float, float, float],
    symmetry: int = 1,
    *,
    color: tuple[float, float, float] = RED,
    seen: np.ndarray | None = None,
) -> SlotTarget:
    """A slot of figure ``points`` (mesh mm) at world ``pose``, with a seen outline if given."""
    fig = Figure.from_polygon(points, color=color)
    seen_slot = None
    if seen is not None:
        seen_fig = Figure.from_polygon(seen, color=color)
        seen_slot = SeenSlot(seen_fig, describe(seen_fig))
    return SlotTarget(
        index, f"s{index}", fig, describe(fig), np.asarray(pose), symmetry, color, seen_slot, "c"
    )


# --- fitted_command: the fields of one command ----------------------------------------------


def test_a_fitted_command_places_on_the_slot_pose_and_keeps_the_grasp() -> None:
    """Guards against a field of the command read from the wrong place (the place's y from
    the slot's yaw, the tile's position instead of its index, the grasp not turned)."""
    t = dataclasses.replace(_tile(0, SQUARE), index=7)
    s = _slot(3, SQUARE, (0.5, 0.2, 0.3), symmetry=4)
    centre = np.array([0.1, -0.05])
    c = fitted_command(t, s, 0.5, centre, score=0.25, cfg=PlacementConfig())
    assert (c.tile, c.slot, c.slot_name, c.symmetry, c.score) == (7, 3, "s3", 4, 0.25)
    assert c.place == (0.5, 0.2, 0.3)
    assert c.pick == pytest.approx((0.1, -0.05, 0.3 - 0.5), abs=1e-12)
    assert c.rotation == 0.5
    assert c.grasp_pick == (float(t.grasp[0]), float(t.grasp[1]))
    # The pad point turns with the tile about its centre and ends beside the slot's centroid.
    g = np.array([0.5, 0.2]) + rotate_xy(t.grasp - centre, 0.5)
    assert c.grasp_place == pytest.approx(tuple(g), abs=1e-12)
    assert c.place_yaws == pytest.approx(
        (0.3, 0.3 + math.pi / 2, wrap(0.3 + math.pi), wrap(0.3 + 1.5 * math.pi)), abs=1e-12
    )
    assert c.command == PickPlaceCommand(c.grasp_pick, c.pick[2], c.grasp_place, c.rotation)


def test_a_fitted_command_wraps_its_turn_and_lists_continuous_yaws() -> None:
    """Guards against the rotation left unwrapped or ``continuous_yaw_steps`` ignored."""
    t = _tile(0, SQUARE)
    s = _slot(0, SQUARE, (0.5, 0.2, -3.0), symmetry=0)
    c = fitted_command(t, s, 4.0, t.centre, score=0.0, cfg=PlacementConfig(continuous_yaw_steps=5))
    assert c.rotation == pytest.approx(4.0 - 2 * math.pi, abs=1e-12)
    assert c.pick[2] == pytest.approx(-7.0 + 2 * math.pi, abs=1e-12)
    assert len(c.place_yaws) == 5 and c.place_yaws[0] == pytest.approx(-3.0)
    assert all(-math.pi <= y < math.pi for y in c.place_yaws)


# --- plan_placements: assignment, commands, reasons -------------------------------------------


def test_a_turned_tile_gets_the_turn_onto_its_slot() -> None:
    """Guards against the plan's command built for the wrong pair or its turn mirrored: an L
    tile turned by -70 deg turns +70 deg onto its slot, picked at its own centroid."""
    t = _tile(0, turned(ELL, -70.0, (300.0, -120.0)))
    s = _slot(0, ELL, (0.5, 0.2, 0.3))
    plan = plan_placements([t], [s])
    (c,) = plan.commands
    assert math.degrees(c.rotation) == pytest.approx(70.0, abs=1e-6)
    assert c.pick[:2] == pytest.approx((0.3, -0.12), abs=1e-12)
    assert c.place == (0.5, 0.2, 0.3)
    assert (plan.unplaced, plan.open_slots, plan.method, plan.use_color) == (
        (),
        (),
        "optimal",
        True,
    )


def test_the_turn_without_a_traced_outline_is_refined_on_the_figures() -> None:
    """Guards against the refinement's span or tolerance dropped for a tile with no traced
    outline: an L with one inner corner 1.5 mm off gets qshape's turn from its relevant points,
    and the dense outlines then fit best some 0.4 deg away; the command takes that fit."""
    bent = ELL.copy()
    bent[3] = [15.5, 14.0]
    t = _tile(0, turned(bent, -70.0, (300.0, -120.0)))
    s = _slot(0, ELL, (0.5, 0.2, 0.3))
    cfg = PlacementConfig()
    (a,) = qshape.assign([t.description], [s.description])
    (c,) = plan_placements([t], [s], cfg).commands
    span, step = math.radians(cfg.refine_span_deg), math.radians(cfg.refine_tolerance_deg)
    want = refine_rotation(
        t.figure,
        s.figure,
        a.rotation,
        span,
        step,
        spacing=cfg.refine_spacing_mm,
        scan=math.radians(cfg.refine_scan_deg),
    )
    assert abs(math.degrees(want - a.rotation)) > 0.2
    assert c.rotation == pytest.approx(wrap(want), abs=1e-12)


def test_a_traced_outline_decides_the_turn_within_the_scanned_span() -> None:
    """Guards against the traced outline or the scan step dropped from the refinement: the
    figure says 60 deg, the traced outline 70 deg; with a 5 deg span scanned every 3 deg the
    best scanned turn is 64 deg and the refinement within one scan of it ends at 67 deg
    (scanned every 1 deg it would end at 66 deg; on the figure, at 60 deg)."""
    s = _slot(0, ELL, (0.5, 0.2, 0.3))
    t = _tile(0, turned(ELL, -60.0, (300.0, -120.0)), outline=turned(ELL, -70.0, (300, -120)))
    cfg = PlacementConfig(refine_span_deg=5.0, refine_scan_deg=3.0)
    (c,) = plan_placements([t], [s], cfg).commands
    assert math.degrees(c.rotation) == pytest.approx(67.0, abs=0.05)
    wide = PlacementConfig(refine_span_deg=12.0)
    (c,) = plan_placements([t], [s], wide).commands
    assert math.degrees(c.rotation) == pytest.approx(70.0, abs=0.05)


def test_every_reason_a_tile_is_left_out() -> None:
    """Guards against a reason misnamed or misjudged: a triangle (no such slot), a blue square
    (only a red square slot), a second red square (its slot taken) - with their details."""
    tiles = [
        _tile(0, turned(SQUARE, 0.0, (0, 0))),
        _tile(1, turned(TRIANGLE, 0.0, (100, 0))),
        _tile(2, turned(SQUARE, 0.0, (200, 0)), BLUE),
        _tile(3, turned(SQUARE, 0.0, (300, 0))),
    ]
    slots = [_slot(5, SQUARE, (0.5, 0.2, 0.0), 4)]
    plan = plan_placements(tiles, slots)
    assert [c.tile for c in plan.commands] == [0]
    assert [(u.tile, u.reason, u.detail) for u in plan.unplaced] == [
        (1, "shape_absent", REASONS["shape_absent"]),
        (2, "color_absent", REASONS["color_absent"]),
        (3, "slots_taken", REASONS["slots_taken"]),
    ]
    assert REASONS["slots_taken"] == "every matching slot is taken by another tile"
    # Shape alone: the blue square matches the red slot, which is taken.
    plan = plan_placements(tiles, slots, PlacementConfig(use_color=False))
    assert [(u.tile, u.reason) for u in plan.unplaced] == [
        (1, "shape_absent"),
        (2, "slots_taken"),
        (3, "slots_taken"),
    ]
    assert plan.use_color is False


def test_a_filled_slot_makes_its_tile_a_taken_one_by_the_tolerances_given() -> None:
    """Guards against the reasons judged with the bundled tolerances instead of the caller's:
    a blue square against a filled red square slot is ``color_absent``, but ``slots_taken``
    when the colour distance allowed spans both colours."""
    tiles = [_tile(0, SQUARE, BLUE)]
    filled = [_slot(2, SQUARE, (0.5, 0.2, 0.0), 4)]
    plan = plan_placements(tiles, [], filled=filled)
    assert [(u.tile, u.reason) for u in plan.unplaced] == [(0, "color_absent")]
    wide = dataclasses.replace(default_tolerances(), color_distance=1.5)
    plan = plan_placements(tiles, [], tolerances=wide, filled=filled)
    assert [(u.tile, u.reason) for u in plan.unplaced] == [(0, "slots_taken")]
    assert plan.commands == () and plan.open_slots == ()
    # Pairs found by the caller are used as they are.
    pairs = FeasiblePairs(tiles, filled, wide)
    plan = plan_placements(tiles, [], filled=filled, pairs=pairs)
    assert [u.reason for u in plan.unplaced] == ["slots_taken"]


def test_open_slots_are_the_slots_no_tile_went_to_by_design_index() -> None:
    """Guards against open slots reported by position or including assigned ones."""
    tiles = [_tile(0, turned(ELL, 20.0, (0, 0)))]
    slots = [_slot(4, SQUARE, (0.1, 0.1, 0.0), 4), _slot(9, ELL, (0.3, 0.1, 0.2))]
    plan = plan_placements(tiles, slots, PlacementConfig(method="greedy"))
    assert [c.slot for c in plan.commands] == [9]
    assert plan.open_slots == (4,) and plan.method == "greedy"


def test_feasible_pairs_name_slot_indices_per_tile_and_colour_mode() -> None:
    """Guards against the table keyed by slot position, or colour mixed up with shape."""
    tiles = [_tile(0, SQUARE), _tile(1, SQUARE, BLUE), _tile(2, TRIANGLE)]
    slots = [_slot(6, SQUARE, (0, 0, 0), 4), _slot(8, ELL, (0, 0, 0))]
    pairs = FeasiblePairs(tiles, slots)
    assert [pairs.slots_of(k, True) for k in range(3)] == [{6}, set(), set()]
    assert [pairs.slots_of(k, False) for k in range(3)] == [{6}, {6}, set()]
    assert FeasiblePairs([], slots).slots_of(0, True) == set()
    assert FeasiblePairs(tiles, []).slots_of(0, False) == set()
    plan = plan_placements(tiles, [])
    assert [u.reason for u in plan.unplaced] == ["shape_absent"] * 3


# --- seen outlines ----------------------------------------------------------------------------


def _seen_scene(outline: bool) -> tuple[list[PerceivedTile], list[SlotTarget]]:
    """A square and an L tile; a square slot and a cut-corner L slot seen as a plain L."""
    ell = turned(ELL, -70.0, (300.0, -120.0))
    tiles = [
        _tile(0, turned(SQUARE, 10.0, (100.0, 0.0))),
        _tile(1, ell, outline=ell if outline else None),
    ]
    slots = [_slot(0, SQUARE, (0.1, 0.2, 0.0), 4), _slot(1, CUT_ELL, (0.5, 0.2, 0.3), seen=ELL)]
    return tiles, slots


def test_a_tile_matching_only_a_seen_outline_is_placed_there_and_recentred() -> None:
    """Guards against the second assignment (on the seen descriptions) dropped or its tile and
    slot positions not mapped back, and against the centre not moved (or moved the wrong
    way) by the design centroid's offset from the seen figure's, turned into the tile's frame."""
    tiles, slots = _seen_scene(outline=False)
    assert (
        FeasiblePairs(tiles, [dataclasses.replace(slots[1], seen=None)]).slots_of(1, True) == set()
    )
    plan = plan_placements(tiles, slots)
    assert [(c.tile, c.slot) for c in plan.commands] == [(0, 0), (1, 1)]
    assert not plan.unplaced and plan.open_slots == ()
    c = plan.commands[1]
    assert math.degrees(c.rotation) == pytest.approx(70.0, abs=1e-3)
    assert slots[1].seen is not None
    offset = np.asarray(slots[1].figure.centroid) - np.asarray(slots[1].seen.figure.centroid)
    assert np.linalg.norm(offset) > 0.5  # [mm] the cut corner moves the design centroid
    want = tiles[1].centre + rotate_xy(offset / MM_PER_M, -c.rotation)
    assert c.pick[:2] == pytest.approx(tuple(want), abs=1e-12)
    assert c.place == (0.5, 0.2, 0.3)
    # The square tile, matched by its design description, is picked at its own centre.
    assert plan.commands[0].pick[:2] == pytest.approx(tuple(tiles[0].centre), abs=1e-12)


def test_a_seen_match_with_a_traced_outline_is_centred_on_that_outline() -> None:
    """Guards against a seen match's traced outline not used for its centre: the tile is
    picked at the traced outline's area centroid, not moved by the seen figure's offset."""
    tiles, slots = _seen_scene(outline=True)
    plan = plan_placements(tiles, slots)
    c = plan.commands[1]
    assert (c.tile, c.slot) == (1, 1)
    assert c.pick[:2] == pytest.approx((0.3, -0.12), abs=1e-9)


def _checked_scene(
    **cfg: float,
) -> tuple[PerceivedTile, SlotTarget, PlacementConfig]:
    """An L tile whose figure says 60 deg and traced outline 70 deg, on a seen cut-corner L."""
    t = _tile(0, turned(ELL, -60.0, (300.0, -120.0)), outline=turned(ELL, -70.0, (300, -120)))
    s = _slot(0, CUT_ELL, (0.5, 0.2, 0.3), seen=ELL)
    base = PlacementConfig(
        refine_span_deg=0.0, fit_max_residual=0.03, fit_margin=1.5, fit_turn_window_deg=5.0
    )
    return t, s, dataclasses.replace(base, **cfg)


def test_a_seen_match_takes_the_traced_outline_fit_turn_when_far_from_the_match() -> None:
    """Guards against the outline check skipped or fed the wrong arguments: the match says
    60 deg, the traced outline fits tightly at 70 deg, 10 deg away (over the 5 deg window):
    the fit's turn is taken (the refinement is off, so it is the command's)."""
    t, s, cfg = _checked_scene()
    outline = TileOutline.of(t)
    assert outline is not None
    fit = fit_outline(outline, s, cfg, cfg.fit_spacing_mm)
    assert fit.residual < cfg.fit_max_residual and fit.runner_up > cfg.fit_margin
    (c,) = plan_placements([t], [s], cfg).commands
    assert c.rotation == pytest.approx(wrap(fit.rotation), abs=1e-12)
    assert math.degrees(c.rotation) == pytest.approx(70.0, abs=0.3)


@pytest.mark.parametrize(
    ("change", "why"),
    [
        ({"fit_max_residual": 0.0}, "the check is off"),
        ({"fit_max_residual": 1e-4}, "the fit is not tight enough"),
        ({"fit_margin": 1e6}, "other turns fit nearly as well"),
        ({"fit_turn_window_deg": 12.0}, "the fit lies within the window of the match"),
    ],
)
def test_a_seen_match_keeps_its_turn_unless_the_fit_is_tight_unambiguous_and_far(
    change: dict[str, float], why: str
) -> None:
    """Guards against each of the outline check's conditions ignored: the match's 60 deg is
    kept when the check is off, the fit is loose, ambiguous or within the window."""
    t, s, cfg = _checked_scene(**change)
    (c,) = plan_placements([t], [s], cfg).commands
    assert math.degrees(c.rotation) == pytest.approx(60.0, abs=1e-6), why


def test_a_symmetric_seen_slot_compares_turns_modulo_its_symmetry() -> None:
    """Guards against the window compared over a full turn on a symmetric slot: a square's fit
    a quarter turn from the match's turn is the same turn, and the match's is kept."""
    cut = np.array([[6, 0], [40, 0], [40, 40], [0, 40], [0, 6]], float)
    t = _tile(0, turned(SQUARE, -20.0, (0, 0)), outline=turned(SQUARE, -20.0, (0, 0)))
    s = _slot(0, cut, (0.5, 0.2, 0.0), symmetry=4, seen=SQUARE)
    cfg = PlacementConfig(refine_span_deg=0.0, fit_max_residual=0.05, fit_margin=1.0)
    (c,) = plan_placements([t], [s], cfg).commands
    (a,) = qshape.assign([t.description], [s.seen.description])  # type: ignore[union-attr]
    assert c.rotation == pytest.approx(wrap(a.rotation), abs=1e-12)


# --- the refinement itself ----------------------------------------------------------------


def test_refine_rotation_keeps_the_rotation_with_no_span_or_no_better_fit() -> None:
    """Guards against a zero span refined anyway, or a worse turn returned: the exact turn of
    an L comes back as it is, bit for bit."""
    t = _tile(0, turned(ELL, -70.0, (0, 0))).figure
    s = _slot(0, ELL, (0, 0, 0)).figure
    exact = math.radians(70.0)
    assert refine_rotation(t, s, exact + 0.05, 0.0) == exact + 0.05
    assert refine_rotation(t, s, exact, math.radians(5.0)) == pytest.approx(exact, abs=1e-4)
    found = refine_rotation(t, s, exact - math.radians(3.0), math.radians(5.0))
    assert found == pytest.approx(exact, abs=1e-4)


def test_refine_rotation_fits_the_traced_points_given() -> None:
    """Guards against the traced points ignored: a square figure at 0 deg with traced points
    of an L turned -40 deg refines to 40 deg within the 45 deg span."""
    fig = Figure.from_polygon(SQUARE)
    s = _slot(0, ELL, (0, 0, 0)).figure
    points = turned(ELL, -40.0, (20.0, 20.0))
    got = refine_rotation(fig, s, 0.0, math.radians(45.0), points=points)
    assert math.degrees(got) == pytest.approx(40.0, abs=0.3)


def test_the_refinement_precision_is_the_tolerance_given() -> None:
    """Guards against the tolerance not handed to the refinement: a coarse tolerance stops
    within it, a fine one lands on the exact turn."""
    t = _tile(0, turned(ELL, -70.0, (0, 0))).figure
    s = _slot(0, ELL, (0, 0, 0)).figure
    start, span = math.radians(66.3), math.radians(5.0)
    fine = refine_rotation(t, s, start, span, 1e-6, scan=math.radians(2.0))
    coarse = refine_rotation(t, s, start, span, math.radians(0.5), scan=math.radians(2.0))
    assert math.degrees(fine) == pytest.approx(70.0, abs=1e-3)
    assert 1e-3 < abs(math.degrees(coarse) - 70.0) < 1.0


def test_outline_residual_is_the_mean_distance_to_the_slot_outline() -> None:
    """Guards against the residual read from the neighbour indices instead of the distances:
    an L on itself leaves 0, and the residual grows with the turn off it."""
    t = _tile(0, turned(ELL, -70.0, (300, -120))).figure
    s = _slot(0, ELL, (0, 0, 0)).figure
    assert outline_residual(t, s, math.radians(70.0)) == pytest.approx(0.0, abs=1e-9)
    near = outline_residual(t, s, math.radians(72.0))
    far = outline_residual(t, s, math.radians(90.0))
    assert 0.0 < near < far < 20.0  # [mm] within the L's size


def test_a_pick_place_command_is_in_the_codec_s_terms() -> None:
    """Guards against the command's fields mixed up (pick yaw, pad points, rotation)."""
    p = PickPlace(
        1, 2, "s", (0.1, 0.2, 0.3), (0.4, 0.5, 0.6), (0.11, 0.21), (0.41, 0.51), 0.3, (0.6,), 1, 0.0
    )
    assert p.command == PickPlaceCommand((0.11, 0.21), 0.3, (0.41, 0.51), 0.3)


# --- the caller's settings reach every step ---------------------------------------------------


def test_the_caller_s_tolerances_and_colour_mode_decide_the_assignment() -> None:
    """Guards against the first assignment run with the bundled tolerances or with colour
    always matched: a blue square and a red square slot pair up only when the caller's colour
    distance spans both colours, or colour is not matched."""
    tiles, slots = [_tile(0, SQUARE, BLUE)], [_slot(0, SQUARE, (0.5, 0.2, 0.0), 4)]
    assert plan_placements(tiles, slots).commands == ()
    wide = dataclasses.replace(default_tolerances(), color_distance=1.5)
    assert [c.slot for c in plan_placements(tiles, slots, tolerances=wide).commands] == [0]
    shape_only = PlacementConfig(use_color=False)
    assert [c.slot for c in plan_placements(tiles, slots, shape_only).commands] == [0]


def test_the_seen_assignment_uses_the_caller_s_tolerances_and_colour_mode() -> None:
    """Guards against the second assignment (on the seen descriptions) run with the bundled
    tolerances or with colour always matched: a blue L reaches the red cut-corner L slot."""
    tiles = [_tile(0, turned(ELL, -70.0, (300.0, -120.0)), BLUE)]
    slots = [_slot(0, CUT_ELL, (0.5, 0.2, 0.3), seen=ELL)]
    assert [u.reason for u in plan_placements(tiles, slots).unplaced] == ["color_absent"]
    wide = dataclasses.replace(default_tolerances(), color_distance=1.5)
    for plan in (
        plan_placements(tiles, slots, tolerances=wide),
        plan_placements(tiles, slots, PlacementConfig(use_color=False)),
    ):
        assert [(c.tile, c.slot) for c in plan.commands] == [(0, 0)]
        assert math.degrees(plan.commands[0].rotation) == pytest.approx(70.0, abs=1e-3)


def test_a_slot_taken_by_its_design_description_takes_no_second_tile_by_its_seen_one() -> None:
    """Guards against the seen assignment offered slots the first one filled, and against a
    design match moved as if seen: a cut-corner L tile fills the cut-corner slot (picked at its
    own centre); the plain L, which only the seen outline matches, is left as slots_taken."""
    cut = _tile(0, turned(CUT_ELL, -40.0, (100.0, 50.0)))
    plain = _tile(1, turned(ELL, -70.0, (300.0, -120.0)))
    slots = [_slot(0, CUT_ELL, (0.5, 0.2, 0.3), seen=ELL)]
    plan = plan_placements([cut, plain], slots)
    assert [(c.tile, c.slot) for c in plan.commands] == [(0, 0)]
    assert [(u.tile, u.reason) for u in plan.unplaced] == [(1, "slots_taken")]
    c = plan.commands[0]
    assert c.pick[:2] == pytest.approx(tuple(cut.centre), abs=1e-12)
    assert math.degrees(c.rotation) == pytest.approx(40.0, abs=1e-3)


COARSE = PlacementConfig(
    refine_span_deg=6.0, refine_tolerance_deg=0.5, refine_scan_deg=2.5, refine_spacing_mm=3.0
)
"""Refinement settings far from `refine_rotation`'s defaults (each changes its result)."""


def _refined(t: PerceivedTile, s: SlotTarget, turn: float, cfg: PlacementConfig) -> float:
    """`refine_rotation` of the pair with ``cfg``'s refinement settings, wrapped."""
    return wrap(
        refine_rotation(
            t.figure,
            s.figure,
            turn,
            math.radians(cfg.refine_span_deg),
            math.radians(cfg.refine_tolerance_deg),
            points=t.outline_mm,
            spacing=cfg.refine_spacing_mm,
            scan=math.radians(cfg.refine_scan_deg),
        )
    )


@pytest.mark.parametrize("traced", [False, True])
def test_every_refinement_setting_reaches_the_refinement(traced: bool) -> None:
    """Guards against a refinement setting (tolerance, spacing, scan) dropped on the way to
    `refine_rotation`, with and without a traced outline, and the pair's score not kept: an L
    with one inner corner 1.5 mm off (its figure, or its traced outline beside a plain L
    figure) is refined with coarse settings, which give another turn than the defaults."""
    bent = ELL.copy()
    bent[3] = [15.5, 14.0]
    if traced:
        t = _tile(0, turned(ELL, -70.0, (300, -120)), outline=turned(bent, -70.0, (300, -120)))
    else:
        t = _tile(0, turned(bent, -70.0, (300.0, -120.0)))
    s = _slot(0, ELL, (0.5, 0.2, 0.3))
    (a,) = qshape.assign([t.description], [s.description])
    (c,) = plan_placements([t], [s], COARSE).commands
    assert c.rotation == _refined(t, s, a.rotation, COARSE)
    assert c.score == a.score
    for change in ("refine_tolerance_deg", "refine_spacing_mm", "refine_scan_deg"):
        default = getattr(PlacementConfig(), change)
        other = _refined(t, s, a.rotation, dataclasses.replace(COARSE, **{change: default}))
        assert other != c.rotation, change


def test_a_sharp_tipped_tile_is_centred_by_its_traced_outline() -> None:
    """Guards against the centre fit of a sharp-tipped slot (`centre_fit_below_deg`) not given
    the traced outline or the turn: a 20 deg tip's tile whose relevant points put its centre
    1 mm off is picked at its traced outline's true centroid."""
    tip = np.array([[0.0, 0.0], [60.0, 0.0], [60.0, 60.0 * math.tan(math.radians(20.0))]])
    traced = turned(tip, -30.0, (200.0, 40.0))
    t = dataclasses.replace(_tile(0, traced, outline=traced), centre=np.array([0.201, 0.040]))
    s = _slot(0, tip, (0.5, 0.2, 0.0))
    (c,) = plan_placements([t], [s]).commands
    assert math.degrees(c.rotation) == pytest.approx(30.0, abs=0.05)
    assert c.pick[:2] == pytest.approx((0.2, 0.04), abs=2e-5)


@pytest.mark.parametrize("edge", ["fit_max_residual", "fit_margin", "fit_turn_window_deg"])
def test_the_outline_check_s_thresholds_admit_the_fit_at_their_edges(edge: str) -> None:
    """Guards against an outline-check bound made strict: a fit whose residual equals
    ``fit_max_residual``, whose runner-up equals ``fit_margin``, or whose turn lies exactly
    is taken; a fit exactly ``fit_turn_window_deg`` from the match's turn is not farther than
    the window, and the match's turn is kept."""
    t, s, cfg = _checked_scene()
    outline = TileOutline.of(t)
    assert outline is not None
    fit = fit_outline(outline, s, cfg, cfg.fit_spacing_mm)
    if edge == "fit_turn_window_deg":
        assert s.seen is not None
        (a,) = qshape.assign([t.description], [s.seen.description])
        off = abs(math.remainder(fit.rotation - a.rotation, symmetry_period(s.symmetry)))
        window = math.degrees(off)
        assert math.radians(window) == off  # exactly at the edge
        cfg = dataclasses.replace(cfg, fit_turn_window_deg=window)
        (c,) = plan_placements([t], [s], cfg).commands
        assert math.degrees(c.rotation) == pytest.approx(60.0, abs=1e-6)
        return
    value = fit.residual if edge == "fit_max_residual" else fit.runner_up
    cfg = dataclasses.replace(cfg, **{edge: value})
    (c,) = plan_placements([t], [s], cfg).commands
    assert c.rotation == pytest.approx(wrap(fit.rotation), abs=1e-12)


def test_refine_rotation_defaults_are_the_documented_ones() -> None:
    """Guards against a default of `refine_rotation` changed (tolerance 1e-4 rad, spacing
    0.5, scan 1 deg): the defaults give what those values given explicitly give."""
    bent = ELL.copy()
    bent[3] = [15.5, 14.0]
    t = _tile(0, turned(bent, -70.0, (0, 0))).figure
    s = _slot(0, ELL, (0, 0, 0)).figure
    start, span = math.radians(66.37), math.radians(6.0)
    explicit = refine_rotation(t, s, start, span, 1e-4, spacing=0.5, scan=math.radians(1.0))
    assert refine_rotation(t, s, start, span) == explicit
    assert abs(explicit - start) > math.radians(3.0)


def test_refine_rotation_returns_the_given_turn_when_nothing_fits_better() -> None:
    """Guards against the refined turn returned although it fits worse than the one given, or
    the refinement kept over an exactly scanned turn: the exact turn of an L, scanned past
    (0.7 deg steps), comes back bit for bit; scanned onto (1 deg steps from 3 deg off), the
    scanned turn is returned."""
    t = _tile(0, turned(ELL, -70.0, (0, 0))).figure
    s = _slot(0, ELL, (0, 0, 0)).figure
    exact = math.radians(70.0)
    assert refine_rotation(t, s, exact, math.radians(5.0), scan=math.radians(0.7)) == exact
    found = refine_rotation(t, s, exact - math.radians(3.0), math.radians(5.0))
    assert found == pytest.approx(exact, abs=1e-12)
