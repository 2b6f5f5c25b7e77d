"""Turn cues: what fixes a slot's turn in a picture; loader warnings; the generator keeps them."""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
import pytest

from qshape.design import Design
from qshape.design.generator import DesignGenerator
from qshape.design.rules import DesignRules
from qshape.design.turn_cues import TurnCues, turn_cues
from qshape.errors import DesignError, SmallFeatureWarning

RULES = DesignRules()


def _design(shape: dict[str, Any], name: str = "s") -> dict[str, Any]:
    return {
        "name": "cues",
        "mesh": {"width": 100, "height": 100},
        "joint": 2.0,
        "slots": [{"name": name, "shape": shape, "color": "#c0392b", "pose": {"x": 50, "y": 50}}],
    }


def _cues(shape: dict[str, Any]) -> TurnCues:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SmallFeatureWarning)
        slot = Design.from_dict(_design(shape)).slots[0]
    return turn_cues(
        slot,
        tolerance_deg=RULES.turn_tolerance_deg,
        window_deg=RULES.turn_window_deg,
        step_deg=RULES.turn_step_deg,
        spacing_mm=RULES.check_step_mm,
    )


RECTANGLE = {"kind": "polygon", "vertices": [[0, 0], [40, 0], [40, 20], [0, 20]]}
# One corner moved 1 mm: not two-fold symmetric (the design's symmetry test tells), but its half
# turn moves the outline by about a tenth of a millimetre on average.
NEARLY = {"kind": "polygon", "vertices": [[0, 0], [40, 0], [41, 20], [0, 20]]}
HEPTAGON_HEX = {
    "kind": "regular_polygon",
    "sides": 7,
    "radius": 20.9,
    "holes": [{"kind": "regular_polygon", "sides": 6, "radius": 6.0, "x": 0.0, "y": 0.0}],
}
PENTAGON_SQUARE = {
    "kind": "regular_polygon",
    "sides": 5,
    "radius": 20.0,
    "holes": [{"kind": "square", "size": 8.0, "x": 0.0, "y": 0.0}],
}


def test_a_rectangle_is_told_from_its_turns_and_a_nearly_symmetric_one_is_not() -> None:
    exact = _cues(RECTANGLE)
    assert exact.asymmetry_mm > 1.0  # 10 deg off its half turn already moves it 1.5 mm
    assert exact.turn_shift_mm > RULES.min_turn_shift_mm
    assert exact.hole_gap_mm == math.inf
    nearly = _cues(NEARLY)
    # Its half turn moves the outline by a tenth of a millimetre, under the camera's limit.
    assert nearly.asymmetry_mm < RULES.min_asymmetry_mm
    assert nearly.asymmetry_mm == pytest.approx(0.14, abs=0.04)


def test_a_hole_of_another_symmetry_keeps_turns_apart_unless_it_barely_moves() -> None:
    # A centred square hole turns the pentagon's 72 deg turns into distinct ones: its corners
    # move by millimetres.
    penta = _cues(PENTAGON_SQUARE)
    assert penta.asymmetry_mm > RULES.min_asymmetry_mm
    assert penta.hole_gap_mm > RULES.min_hole_turn_mm
    # A centred hexagon in a heptagon: the next turn is the hexagon's 8.6 deg misfit.
    hepta = _cues(HEPTAGON_HEX)
    assert hepta.hole_gap_mm < RULES.min_hole_turn_mm
    assert hepta.asymmetry_mm < RULES.min_asymmetry_mm


def test_the_loader_warns_per_slot_naming_the_cue_and_refuses_on_request() -> None:
    with pytest.warns(SmallFeatureWarning, match=r"slot 'near'.*nearly symmetric.*0\.3 mm"):
        Design.from_dict(_design(NEARLY, "near"))
    with pytest.warns(SmallFeatureWarning, match=r"slot 'hepta'.*only its holes tell"):
        Design.from_dict(_design(HEPTAGON_HEX, "hepta"))
    with pytest.raises(DesignError, match=r"slot 'near'.*small_features: refuse"):
        Design.from_dict(_design(NEARLY, "near"), rules=DesignRules(small_features="refuse"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Design.from_dict(_design(RECTANGLE))
        Design.from_dict(_design(PENTAGON_SQUARE))
        Design.from_dict(_design(NEARLY), rules=DesignRules(min_asymmetry_mm=0.05))
        Design.from_dict(_design(NEARLY), rules=DesignRules(small_features="ignore"))


def test_bad_turn_limits_are_typed_errors() -> None:
    with pytest.raises(DesignError, match="min_asymmetry_mm"):
        DesignRules(min_asymmetry_mm=-1.0)
    with pytest.raises(DesignError, match="turn_step_deg"):
        DesignRules(turn_step_deg=0.0)


def test_the_generator_keeps_turn_cues_the_loader_would_warn_about_out() -> None:
    # Design 21 drawn without the limits holds a heptagon with a centred hexagon hole.
    off = DesignRules(min_turn_shift_mm=0.0, min_asymmetry_mm=0.0, min_hole_turn_mm=0.0)
    old = DesignGenerator(rules=off).draw(np.random.default_rng(21), name="r21")
    with pytest.warns(SmallFeatureWarning, match="only its holes tell"):
        Design.from_dict(old.to_dict())
    with warnings.catch_warnings():
        warnings.simplefilter("error", SmallFeatureWarning)
        design = DesignGenerator().draw(np.random.default_rng(21), name="r21")
    for slot in design.slots:
        cues = turn_cues(slot, tolerance_deg=2.0, window_deg=10.0, step_deg=6.0, spacing_mm=1.0)
        assert cues.turn_shift_mm >= RULES.min_turn_shift_mm
        assert cues.asymmetry_mm >= RULES.min_asymmetry_mm
        assert cues.hole_gap_mm >= RULES.min_hole_turn_mm
