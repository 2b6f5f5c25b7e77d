"""Contract tests of qshape's matching and assignment entry points: what each documents about
its arguments, its errors and its result, beyond the behaviour tests of `test_matching`,
`test_assign` and `test_neighbours`.

Each test names the bug it guards against. They are part of the mutation selection
(`pyproject.toml` `[tool.mutmut]`): written so that a changed argument, a dropped check or a
swapped branch in `match`, `match_best`, `assign` and their input checks makes one fail.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from qshape import Boundary, Figure, MatchError, Tolerances, assign, describe, match, match_best
from qshape.theory.matching import check_match_inputs, is_continuous
from spatial.angles import rotate_xy

GREY = (0.5, 0.5, 0.5)
L_TILE = np.array([[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]], float)
# A rectangle whose long top edge is bent by one shallow corner: it matches no rectangle as
# measured, and the rectangle through its structural neighbour (the weak corner removed).
BENT = [[0, 0], [0, 30], [20, 31], [40, 30.6], [40, 0]]


def _circle_with_hole(hole: Figure) -> Figure:
    disc = Figure.circle(10.0)
    return Figure(disc.points, disc.curve_mask, (Boundary.make(hole.points, hole.curve_mask),))


# -- input checks: the message names the argument at fault --------------------------------------


@pytest.mark.parametrize("bad", ["square", 3, None, [Figure.rectangle(2, 2), "x"]])
def test_assign_names_bad_slots_and_bad_tiles(bad: object) -> None:
    """A bad ``slots`` (or ``tiles``) argument is reported under its own name: a check that
    names the wrong argument (or none) sends the user looking in the wrong place."""
    ok = [Figure.rectangle(2, 2)]
    with pytest.raises(MatchError, match=r"^slots(\[1\])? must be"):
        assign(ok, bad)  # type: ignore[arg-type]
    with pytest.raises(MatchError, match=r"^tiles(\[1\])? must be"):
        assign(bad, ok)  # type: ignore[arg-type]


def test_check_match_inputs_returns_the_tolerances_to_use() -> None:
    """None gives the bundled defaults, a `Tolerances` is used as given: a check that dropped
    the caller's tolerances would assign under the wrong bands."""
    own = Tolerances(symmetry_residual=0.01)
    assert check_match_inputs([], [], own, True) is own
    assert check_match_inputs([], [], None, False) == Tolerances.load()
    with pytest.raises(MatchError, match=r"^use_color must be True or False, got 'yes'"):
        check_match_inputs([], [], None, "yes")


@pytest.mark.parametrize("entry", ["match", "match_best"])
def test_a_non_bool_use_color_is_named(entry: str) -> None:
    """``use_color="no"`` (truthy) would silently compare colours: it is refused, and the
    message names ``use_color``."""
    a = Figure.rectangle(4, 2)
    call = {
        "match": lambda: match(a, a, use_color="no"),
        "match_best": lambda: match_best({0: a}, a, use_color="no"),
    }  # type: ignore[arg-type]
    with pytest.raises(MatchError, match=r"^use_color must be True or False, got 'no'"):
        call[entry]()


def test_match_best_rejects_a_non_figure_reference_and_candidate() -> None:
    """Every reference and the candidate are checked, each by its type's name."""
    a = Figure.rectangle(4, 2)
    with pytest.raises(MatchError, match="got str"):
        match_best({0: a, 1: "square"}, a)  # type: ignore[dict-item]
    with pytest.raises(MatchError, match="got int"):
        match_best({0: a}, 5)  # type: ignore[arg-type]


# -- continuous figures ----------------------------------------------------------------------


def test_only_concentric_circular_holes_keep_a_disc_continuous() -> None:
    """A disc stays rotationally continuous only while every hole is a circle at its centre:
    a circular hole off the centre, or a square hole at it, fixes the disc's turn."""
    tol = Tolerances.load()
    centred = _circle_with_hole(Figure.circle(3.0))
    off_centre = _circle_with_hole(Figure.circle(3.0, center=(5.0, 0.0)))
    square = _circle_with_hole(Figure.rectangle(4.0, 4.0))
    assert is_continuous(describe(centred, tol))
    assert not is_continuous(describe(off_centre, tol))
    assert not is_continuous(describe(square, tol))
    assert not is_continuous(describe(Figure.regular_polygon(4, 5.0), tol))
    m = match(off_centre, off_centre)
    assert m is not None and not m.continuous
    ring = match(centred, centred)
    assert ring is not None and ring.continuous


# -- match_best --------------------------------------------------------------------------------


def test_match_best_with_figures_and_descriptions_alike() -> None:
    """References and the candidate may be figures or descriptions: the answer is the same
    (a reference or candidate left undescribed, or described without the caller's
    tolerances, changes it)."""
    tol = Tolerances(symmetry_residual=0.02)
    refs = {"L": Figure.from_polygon(L_TILE), "square": Figure.rectangle(20, 20)}
    cand = Figure.from_polygon(rotate_xy(L_TILE, 0.7) + 3.0)
    by_fig = match_best(refs, cand, tol)
    by_desc = match_best({k: describe(v, tol) for k, v in refs.items()}, describe(cand, tol), tol)
    assert by_fig is not None and by_desc is not None
    assert by_fig[0] == by_desc[0] == "L"
    assert by_fig[1] == by_desc[1] == match(refs["L"], cand, tol)
    assert abs(math.remainder(by_fig[1].rotation + 0.7, 2 * math.pi)) < 1e-9


def test_match_best_keeps_the_lowest_score_not_the_first_or_last() -> None:
    """Of several direct matches the lowest score wins, wherever it is listed (comparing with
    the wrong entry, or keeping the first or last match, picks another)."""
    tol = Tolerances.load()
    cand = Figure.rectangle(20.0, 10.0, angle=0.4)
    refs = {f"r{k}": Figure.rectangle(20.0 + d, 10.0) for k, d in enumerate((0.6, 0.0, 0.3))}
    scores = {k: match(r, cand, tol).score for k, r in refs.items()}  # type: ignore[union-attr]
    assert len(set(scores.values())) == 3
    for order in (["r0", "r1", "r2"], ["r1", "r2", "r0"], ["r2", "r0", "r1"]):
        found = match_best({k: refs[k] for k in order}, cand, tol)
        assert found is not None and found[0] == "r1"
        assert found[1].score == scores["r1"]


def test_match_best_through_a_neighbour_carries_it_and_respects_the_tolerances() -> None:
    """The bent rectangle reaches the rectangle through its neighbour: the match carries that
    neighbour (four nodes), its score is the neighbour's own `match` score within
    ``neighbour_residual``, and the neighbours are made with the caller's tolerances."""
    tol = Tolerances.load()
    bent = Figure.from_polygon(BENT)
    rect = Figure.rectangle(40.0, 30.0, center=(20.0, 15.0))
    triangle = Figure.regular_polygon(3, 20.0)
    for refs in ({"rect": rect, "tri": triangle}, {"tri": triangle, "rect": rect}):
        found = match_best(refs, bent, tol)
        assert found is not None and found[0] == "rect"
        key, m = found
        assert m.neighbour is not None and len(m.neighbour.outer.codes) == 4
        direct = match(rect, m.neighbour, tol)
        assert direct is not None
        assert m.score == direct.score <= tol.neighbour_residual
        assert m.rotation == direct.rotation and m.correspondence == direct.correspondence
    # A stricter neighbour residual than this neighbour's score: no match at all.
    m0 = match_best({"rect": rect}, bent, tol)
    assert m0 is not None
    strict = Tolerances.load(neighbour_residual=m0[1].score * 0.999)
    assert match_best({"rect": rect}, bent, strict) is None
    loose = Tolerances.load(neighbour_residual=m0[1].score)
    assert match_best({"rect": rect}, bent, loose) is not None


def test_match_best_neighbours_matching_several_references_and_none() -> None:
    """Through neighbours, a reference matched by two keys is ambiguous (None), one reached by
    no neighbour is no match, and a candidate that matches nothing gives None."""
    tol = Tolerances.load()
    bent = Figure.from_polygon(BENT)
    rect = Figure.rectangle(40.0, 30.0)
    assert match_best({"a": rect, "b": Figure.rectangle(40.0, 30.0, angle=1.0)}, bent, tol) is None
    assert match_best({"hexagon": Figure.regular_polygon(6, 20.0)}, bent, tol) is None
    assert match_best({}, bent, tol) is None


# -- assign ------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["optimal", "greedy"])
def test_assign_mixed_figures_and_descriptions(method: str) -> None:
    """Tiles and slots may mix figures and descriptions in one list: each keeps its place and
    the result equals the all-described one (a description passed through the figure path, or
    a figure left undescribed, breaks it)."""
    tol = Tolerances.load()
    slots = [Figure.rectangle(20, 10, GREY), Figure.from_polygon(L_TILE), Figure.circle(6.0)]
    tiles = [
        Figure.circle(6.0, angle=0.3),
        Figure.from_polygon(rotate_xy(L_TILE, 1.1)),
        Figure.rectangle(20, 10, GREY, angle=-0.5),
    ]
    mixed_tiles = [describe(tiles[0], tol), tiles[1], describe(tiles[2], tol)]
    mixed_slots = [slots[0], describe(slots[1], tol), slots[2]]
    want = assign([describe(t, tol) for t in tiles], [describe(s, tol) for s in slots], tol, method)
    got = assign(mixed_tiles, mixed_slots, tol, method)
    assert [(a.tile, a.slot) for a in want] == [(0, 2), (1, 1), (2, 0)]
    assert got == want


def _rhombus(corner_deg: float, angle: float = 0.0) -> Figure:
    t = math.radians(corner_deg)
    pts = [
        [0, 0],
        [20, 0],
        [20 + 20 * math.cos(t), 20 * math.sin(t)],
        [20 * math.cos(t), 20 * math.sin(t)],
    ]
    return Figure.from_polygon(rotate_xy(np.array(pts, float), angle))


def _blocks_design(n_tiles: int) -> tuple[list[Figure], list[Figure]]:
    """Slots: rhombi of 90 and 100 deg corners (two keys). Tiles: one of 95 deg, whose
    admissible labels reach both keys and which matches both slots; one of 90 deg (the first
    slot only); one of 100 deg (the second only). The candidate blocks share tiles: one merged
    group of two blocks (two tiles) or three (three tiles)."""
    slots = [_rhombus(90.0), _rhombus(100.0)]
    tiles = [_rhombus(95.0, 0.3), _rhombus(90.0, -1.0), _rhombus(100.0, 2.0)][:n_tiles]
    tol = Tolerances.load()
    ok = [[match(s, x, tol) is not None for s in slots] for x in tiles]
    assert ok == [[True, True], [True, False], [False, True]][:n_tiles]
    return tiles, slots


def test_greedy_on_a_merged_group_takes_every_block_into_account() -> None:
    """The paper's loop over a group of three blocks: tile 0 takes the first slot, tile 1
    finds it taken, tile 2 takes the second. A shortcut answering from the group's first
    block alone would lose tile 2."""
    tiles, slots = _blocks_design(3)
    for classes in (True, False):
        out = assign(tiles, slots, method="greedy", slot_classes=classes)
        assert [(a.tile, a.slot) for a in out] == [(0, 0), (2, 1)]


@pytest.mark.parametrize("n_tiles", [2, 3])
def test_optimal_on_a_merged_group_places_every_tile_it_can(n_tiles: int) -> None:
    """Optimal on a group of two or three blocks: every tile that can be placed is (tile 0
    gives way to tile 1), each slot once, each pair's own score: the group's slots are the
    union of its blocks' (the first block's alone would drop the second slot)."""
    tol = Tolerances(rotation_corner_share=1.0)  # assign fits turns by points alone
    tiles, slots = _blocks_design(n_tiles)
    out = assign(tiles, slots, tol)
    want = [(0, 1), (1, 0)] if n_tiles == 2 else [(1, 0), (2, 1)]
    assert [(a.tile, a.slot) for a in out] == want
    for a in out:
        m = match(slots[a.slot], tiles[a.tile], tol)
        assert m is not None and a.score == pytest.approx(m.score, abs=1e-12)
        assert abs(math.remainder(a.rotation - m.rotation, 2 * math.pi)) < 1e-9


def test_assign_with_classes_skips_a_group_without_pairs_and_goes_on() -> None:
    """With slot classes, a tile group whose keys meet a class but whose pairs all fail (the
    hole in another place) places nothing, and the groups after it are still assigned."""
    out = [[-10.0, -10], [10, -10], [10, 10], [-10, 10]]
    hole = np.array([[-2.0, -2], [2, -2], [2, 2], [-2, 2]])
    holed = Figure.from_polygon(out, [hole + (5.0, -5.0)])
    moved = Figure.from_polygon(out, [hole])  # the hole at the centre: no slot's
    assert match(holed, moved) is None
    slots = [holed, holed, Figure.from_polygon(L_TILE), Figure.from_polygon(L_TILE)]
    for tiles in (
        [moved, Figure.from_polygon(rotate_xy(L_TILE, 0.5))],
        [Figure.from_polygon(rotate_xy(L_TILE, 0.5)), moved],
    ):
        got = assign(tiles, slots)
        ell = 1 if tiles[1] is not moved else 0
        assert [(a.tile, a.slot) for a in got] == [(ell, 2)]


def test_figures_are_described_with_the_caller_s_tolerances() -> None:
    """A figure is described under the tolerances given, not the bundled ones: with a right
    angle band of 70-110 deg a 76 deg rhombus is a square, by figure or by description."""
    wide = Tolerances.load(right_angle_deg=(70.0, 110.0))
    rhombus, square = _rhombus(76.0), _rhombus(90.0, 0.4)
    assert match(square, rhombus) is None
    by_fig = match(square, rhombus, wide)
    assert by_fig is not None
    assert by_fig == match(describe(square, wide), describe(rhombus, wide), wide)
    found = match_best({"square": square}, rhombus, wide)
    assert found is not None and found[1] == by_fig
    for method in ("optimal", "greedy"):  # the rhombus as the tile
        assert assign([rhombus], [square], method=method) == []
        got = assign([rhombus], [square], wide, method)
        assert [(a.tile, a.slot) for a in got] == [(0, 0)]


def test_match_best_defaults_ties_and_messages() -> None:
    """Colours are compared unless told otherwise; of equal scores the first listed wins; a
    non-mapping is refused by its type's name; with ``neighbour_residual`` 0 no neighbour is
    tried, even one that would fit exactly."""
    red = Figure.rectangle(20, 10, (0.9, 0.1, 0.1))
    blue = Figure.rectangle(20, 10, (0.1, 0.1, 0.9), angle=0.5)
    assert match_best({"red": red}, blue) is None
    assert match_best({"red": red}, blue, use_color=False) is not None
    twin = Figure.rectangle(20, 10, (0.1, 0.1, 0.9))
    for first, second in (("a", "b"), ("b", "a")):
        found = match_best({first: twin, second: twin}, blue)
        assert found is not None and found[0] == first
    with pytest.raises(MatchError, match=r"got list$"):
        match_best([red], blue)  # type: ignore[arg-type]
    exact_bent = Figure.from_polygon([[0, 0], [0, 30], [20, 31], [40, 30], [40, 0]])
    rect = Figure.rectangle(40.0, 30.0)
    found = match_best({"rect": rect}, exact_bent)
    assert found is not None and found[1].score == 0.0  # its neighbour is the rectangle
    off = Tolerances.load(neighbour_residual=0.0)
    assert match_best({"rect": rect}, exact_bent, off) is None


def test_references_and_tiles_are_described_with_the_caller_s_tolerances_too() -> None:
    """The same as above with the roles turned: the 76 deg rhombus as the reference (and as
    the slot), the square as the candidate (and the tile), through `match`, `match_best` and
    `assign` with figures on both sides."""
    wide = Tolerances.load(right_angle_deg=(70.0, 110.0))
    rhombus, square = _rhombus(76.0), _rhombus(90.0, 0.4)
    assert match(rhombus, square) is None
    assert match(rhombus, square, wide) is not None
    found = match_best({"rhombus": rhombus}, square, wide)
    assert found is not None and found[1] == match(rhombus, square, wide)
    for method in ("optimal", "greedy"):
        assert assign([square], [rhombus], method=method) == []
        got = assign([square], [rhombus], wide, method)
        assert [(a.tile, a.slot) for a in got] == [(0, 0)]
        got = assign([square, square], [rhombus, rhombus], wide, method)  # one slot class
        assert [(a.tile, a.slot) for a in got] == [(0, 0), (1, 1)]


def test_match_best_evaluates_under_the_caller_s_tolerances() -> None:
    """A wide symmetry residual lists the near-symmetric turns of a 20 x 17 rectangle: the
    match `match_best` returns carries exactly the rotations `match` gives under those
    tolerances, directly and through a neighbour; the neighbours honour ``use_color``."""
    loose = Tolerances.load(symmetry_residual=0.2)
    ref = Figure.rectangle(20.0, 17.0)
    cand = Figure.rectangle(20.0, 17.0, angle=0.3)
    direct = match(ref, cand, loose)
    assert direct is not None and len(direct.rotations) == 4
    assert len(match(ref, cand).rotations) == 2  # type: ignore[union-attr]
    found = match_best({"r": ref}, cand, loose)
    assert found is not None and found[1].rotations == direct.rotations
    bent = Figure.from_polygon(BENT, color=(0.9, 0.1, 0.1))
    rect = Figure.rectangle(40.0, 30.0, (0.1, 0.1, 0.9))
    assert match_best({"rect": rect}, bent, loose) is None  # colours differ
    via = match_best({"rect": rect}, bent, loose, use_color=False)
    assert via is not None and via[1].neighbour is not None
    assert via[1].rotations == match(rect, via[1].neighbour, loose, use_color=False).rotations  # type: ignore[union-attr]


def test_symmetric_rotations_are_listed_by_magnitude() -> None:
    """After the chosen turn, the equivalent ones come smallest magnitude first (documented
    order; listing them by offset instead puts a larger turn before a smaller one)."""
    for n, angle in ((4, 2.0), (6, -2.5), (3, 2.9)):
        m = match(Figure.regular_polygon(n, 10.0), Figure.regular_polygon(n, 10.0, angle=angle))
        assert m is not None and len(m.rotations) == n
        rest = [abs(r) for r in m.rotations[1:]]
        assert rest == sorted(rest)
        assert abs(m.rotation) == min(abs(r) for r in m.rotations)


@pytest.mark.parametrize("method", ["optimal", "greedy"])
def test_colour_decides_among_slots_of_one_shape(method: str) -> None:
    """Colours are compared on every path (``use_color`` left at its default): blue tiles go
    to the blue slots, whether the slots are all different (pairwise path) or copies (slot
    classes); with ``use_color=False`` the first slots of the shape are taken instead."""
    red, blue = (0.9, 0.1, 0.1), (0.1, 0.1, 0.9)
    tiles = [Figure.rectangle(20, 10, blue, angle=0.4), Figure.rectangle(20, 10, blue, angle=1.3)]
    distinct = [Figure.rectangle(20, 10, red), Figure.rectangle(20, 10, blue)]
    got = assign(tiles[:1], distinct, method=method)
    assert [(a.tile, a.slot) for a in got] == [(0, 1)]
    copies = [Figure.rectangle(20, 10, red), Figure.rectangle(20, 10, red, angle=0.7)]
    copies += [Figure.rectangle(20, 10, blue, angle=1.1), Figure.rectangle(20, 10, blue)]
    got = assign(tiles, copies, method=method)
    assert sorted(a.slot for a in got) == [2, 3]
    got = assign(tiles, copies, method=method, slot_classes=False)
    assert sorted(a.slot for a in got) == [2, 3]
    blind = assign(tiles, copies, method=method, use_color=False)
    assert len(blind) == 2


def test_bad_items_are_reported_by_their_type_names() -> None:
    """The refusal names the type given: the list itself, or the entry at fault."""
    ok = [Figure.rectangle(2, 2)]
    with pytest.raises(MatchError, match=r"^slots must be .* got str$"):
        assign(ok, "square")  # type: ignore[arg-type]
    with pytest.raises(MatchError, match=r"^tiles\[1\] must be .* got int$"):
        assign([ok[0], 3], ok)  # type: ignore[list-item]
