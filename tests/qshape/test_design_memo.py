"""The bounded memo of shape results: at most its size, least recently used dropped first, and
a shape's symmetry order remembered across slots, copies and poses without changing it."""

from __future__ import annotations

import warnings

import pytest

from qshape.design import Design
from qshape.design.memo import BoundedMemo
from qshape.design.slot import SYMMETRY_MEMO, SYMMETRY_MEMO_SIZE, Slot
from qshape.errors import DesignError, SmallFeatureWarning


def test_the_memo_holds_at_most_its_size_dropping_the_least_recently_used() -> None:
    memo: BoundedMemo[int] = BoundedMemo(3)
    for k in range(3):
        assert memo.get(k, lambda k=k: k * k) == k * k
    assert memo.get(0, lambda: -1) == 0  # kept: not computed again; 0 is now the most recent
    memo.get(3, lambda: 9)
    assert len(memo) == 3 and 1 not in memo and 0 in memo and 3 in memo
    for k in range(100):
        memo.get(("other", k), lambda: 0)
    assert len(memo) == 3
    assert (memo.hits, memo.misses) == (1, 104)


def test_a_memo_of_no_entries_is_refused() -> None:
    with pytest.raises(DesignError, match="maxsize=0"):
        BoundedMemo(0)


def test_symmetry_is_remembered_by_shape_and_equals_the_computed_order() -> None:
    design = Design.load("paper_mixed")
    square = next(s for s in design.slots if s.shape.get("kind") == "square")
    SYMMETRY_MEMO.clear()
    fresh = Slot("a", square.shape, (1.0, 0.0, 0.0), 10.0, 20.0, 33.0, square.rules)
    order = fresh.symmetry
    assert order == 4 and len(SYMMETRY_MEMO) == 1
    hits = SYMMETRY_MEMO.hits
    moved = Slot("b", dict(square.shape), (0.0, 1.0, 0.0), -5.0, 2.0, 71.0, square.rules)
    assert moved.symmetry == order and SYMMETRY_MEMO.hits == hits + 1
    assert SYMMETRY_MEMO.maxsize == SYMMETRY_MEMO_SIZE


def test_a_design_file_loads_once_and_a_changed_file_loads_anew(tmp_path) -> None:
    from qshape.design.model import LOADED_DESIGNS  # noqa: PLC0415

    path = tmp_path / "d.yaml"
    Design.load("paper_mixed").save(path)
    first = Design.load(path)
    assert Design.load(path) is first  # the same file text: the design validated once
    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace("name: paper_mixed", "name: changed", 1), encoding="utf-8")
    changed = Design.load(path)
    assert changed is not first and changed.name == "changed" and first.name == "paper_mixed"
    assert LOADED_DESIGNS >= 1


def test_parsed_configuration_text_is_a_fresh_copy_each_time() -> None:
    from configs import PARSED_TEXTS, parse_yaml  # noqa: PLC0415

    text = "a: {b: [1, 2]}\n"
    first = parse_yaml(text)
    first["a"]["b"].append(3)
    assert parse_yaml(text) == {"a": {"b": [1, 2]}}
    assert parse_yaml("a: {b: [1, 2, 4]}\n") == {"a": {"b": [1, 2, 4]}}
    assert PARSED_TEXTS >= 1


def test_a_remembered_design_warns_at_every_load(tmp_path) -> None:
    """A load answered from the memo says again what the first load said (a user loading a
    design twice must see its small-feature warnings twice; a re-emission that a warnings
    registry swallows fails here)."""
    path = tmp_path / "bowed.yaml"
    path.write_text(
        "name: bowed\nmesh: {width: 230, height: 230}\njoint: 2.0\nslots:\n"
        "  - name: bowed\n"
        "    shape: {kind: polygon, vertices: [[0, 0, 0.1], [40, 0], [40, 40], [0, 40]]}\n"
        "    color: '#27ae60'\n    pose: {x: 100, y: 100, angle: 0}\n"
    )
    for _ in range(2):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            Design.load(path)
        assert caught and all(issubclass(w.category, SmallFeatureWarning) for w in caught)
        assert all("bowed" in str(w.message) for w in caught)


def test_turn_cues_are_remembered_by_shape_and_equal_the_measured_ones() -> None:
    from qshape.design.turn_cues import CUES_MEMO, CUES_MEMO_SIZE, rule_cues, turn_cues  # noqa: PLC0415

    design = Design.load("paper_mixed")
    slot = next(s for s in design.slots if s.shape.get("holes"))
    r = slot.rules
    measured = turn_cues(
        slot,
        tolerance_deg=r.turn_tolerance_deg,
        window_deg=r.turn_window_deg,
        step_deg=r.turn_step_deg,
        spacing_mm=r.check_step_mm,
        deviation_mm=r.tile_deviation_mm,
        arc_step_mm=r.made_arc_step_mm,
    )
    CUES_MEMO.clear()
    assert rule_cues(slot, r) == measured and len(CUES_MEMO) == 1
    hits = CUES_MEMO.hits
    moved = Slot("b", dict(slot.shape), (0.0, 1.0, 0.0), -5.0, 2.0, 71.0, r)
    assert rule_cues(moved, r) == measured and CUES_MEMO.hits == hits + 1
    assert CUES_MEMO.maxsize == CUES_MEMO_SIZE


def test_a_slot_makes_its_figure_once() -> None:
    slot = Design.load("paper_mixed").slots[0]
    figure = slot.figure()
    assert slot.figure() is figure
    assert figure == slot.path.figure(slot.color, slot.rules.max_arc_deg)
