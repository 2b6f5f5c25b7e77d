"""Turn cues: what fixes a slot's turn in a picture and in the made tile; loader warnings; the
generator keeps them."""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
import pytest
import shapely
from scipy.optimize import minimize_scalar
from scipy.spatial import cKDTree

from qshape import geometry as geo
from qshape.design import Design
from qshape.design.generator import DesignGenerator
from qshape.design.made_turn import made_turn_sd
from qshape.design.rules import DesignRules
from qshape.design.slot import Slot
from qshape.design.turn_cues import TurnCues, rule_cues
from qshape.errors import DesignError, SmallFeatureWarning

RULES = DesignRules()


def _design(shape: dict[str, Any], name: str = "s") -> dict[str, Any]:
    return {
        "name": "cues",
        "mesh": {"width": 100, "height": 100},
        "joint": 2.0,
        "slots": [{"name": name, "shape": shape, "color": "#c0392b", "pose": {"x": 50, "y": 50}}],
    }


def _slot(shape: dict[str, Any]) -> Slot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SmallFeatureWarning)
        return Design.from_dict(_design(shape)).slots[0]


def _cues(shape: dict[str, Any]) -> TurnCues:
    return rule_cues(_slot(shape), RULES)


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
        cues = rule_cues(slot, RULES)
        assert cues.turn_shift_mm >= RULES.min_turn_shift_mm
        assert cues.asymmetry_mm >= RULES.min_asymmetry_mm
        assert cues.hole_gap_mm >= RULES.min_hole_turn_mm


# The crescent random design 199 held before the capability limit: a concave and a convex arc
# whose centres nearly meet, two sharp tips and a 12 mm straight edge.
CRESCENT = {
    "kind": "polygon",
    "vertices": [[3.4447, -11.8984, -0.5411], [5.9841, 10.8457], [-6.2057, 10.7204, 0.4511]],
}
SQUARE = {"kind": "square", "size": 20.0}
PENTAGON_HOLE = {
    "kind": "regular_polygon",
    "sides": 5,
    "radius": 18.0,
    "holes": [{"kind": "square", "size": 6.0, "x": 3.0, "y": 0.0}],
}


def _centroid(outer: np.ndarray, holes: list[np.ndarray]) -> np.ndarray:
    """Area centroid of ``outer`` less ``holes`` (shapely's, independent of the code tested)."""
    c = shapely.Polygon(outer, holes).centroid
    return np.array([c.x, c.y])


def _monte_carlo_sd(slot: Slot, deviation: float, copies: int, seed: int) -> float:
    """Std [deg] of the least-squares best-fit turn of made copies (every vertex deviated)."""
    path = slot.local_path
    drawn = [path.outer.made_vertices(RULES.made_arc_step_mm)]
    drawn += [h.made_vertices(RULES.made_arc_step_mm) for h in path.holes]
    tree = cKDTree(path.outer.dense(0.02) - _centroid(drawn[0], drawn[1:]))
    rng = np.random.default_rng(seed)
    turns = []
    for _ in range(copies):
        made = [v + rng.normal(0.0, deviation, v.shape) for v in drawn]
        outline = made[0] - _centroid(made[0], made[1:])
        closed = np.vstack([outline, outline[:1]])
        probes = np.concatenate(
            [
                a + np.linspace(0, 1, 8, endpoint=False)[:, None] * (b - a)
                for a, b in zip(closed[:-1], closed[1:], strict=True)
            ]
        )
        res = minimize_scalar(
            lambda r, p=probes: float(np.mean(tree.query(geo.rotate(p, r))[0] ** 2)),
            bounds=(-0.1, 0.1),
            method="bounded",
            options={"xatol": 1e-6},
        )
        turns.append(math.degrees(float(res.x)))
    return float(np.std(turns))


@pytest.mark.parametrize(
    ("shape", "expected"), [(CRESCENT, 0.69), (SQUARE, 0.41), (PENTAGON_HOLE, 0.29)]
)
def test_the_first_order_spread_matches_made_copies(shape: dict[str, Any], expected: float) -> None:
    slot = _slot(shape)
    sd = RULES.tile_deviation_mm * made_turn_sd(
        slot, arc_step_mm=RULES.made_arc_step_mm, spacing_mm=0.25
    )
    assert sd == pytest.approx(expected, abs=0.02)
    assert _monte_carlo_sd(slot, RULES.tile_deviation_mm, 300, seed=3) == pytest.approx(sd, rel=0.2)


def test_capability_tells_the_crescent_from_a_square_the_turn_shift_does_not() -> None:
    crescent = rule_cues(_slot(CRESCENT), RULES)
    square = rule_cues(_slot(SQUARE), RULES)
    # A 2 deg turn moves both outlines by about 0.19 mm on average, over the camera's limit...
    assert crescent.turn_shift_mm == pytest.approx(square.turn_shift_mm, abs=0.01)
    assert min(crescent.turn_shift_mm, square.turn_shift_mm) > RULES.min_turn_shift_mm
    # ...but the square's four corners fix its turn, the crescent's arcs slide along themselves.
    assert crescent.capability(RULES.turn_tolerance_deg) < RULES.min_turn_capability
    assert square.capability(RULES.turn_tolerance_deg) > 1.6


def test_the_loader_warns_about_a_low_capability_and_refuses_on_request() -> None:
    with pytest.warns(
        SmallFeatureWarning, match=r"slot 'moon'.*0\.69 deg \(std\).*capability 0\.97"
    ):
        Design.from_dict(_design(CRESCENT, "moon"))
    with pytest.raises(DesignError, match=r"slot 'moon'.*capability.*small_features: refuse"):
        Design.from_dict(_design(CRESCENT, "moon"), rules=DesignRules(small_features="refuse"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", SmallFeatureWarning)
        Design.from_dict(_design(CRESCENT), rules=DesignRules(min_turn_capability=0.9))
        Design.from_dict(_design(CRESCENT), rules=DesignRules(tile_deviation_mm=0.1))
        Design.from_dict(_design(SQUARE))


def test_bad_made_tile_rules_are_typed_errors() -> None:
    with pytest.raises(DesignError, match="made_arc_step_mm"):
        DesignRules(made_arc_step_mm=0.0)
    with pytest.raises(DesignError, match="tile_deviation_mm"):
        DesignRules(tile_deviation_mm=-0.1)


def test_the_generator_draws_no_tile_below_the_capability() -> None:
    off = DesignRules(min_turn_capability=0.0)
    old = DesignGenerator(rules=off).draw(np.random.default_rng(199), name="r199")
    low = [s for s in old.slots if rule_cues(s, RULES).capability(2.0) < 1.0]
    assert len(low) == 4  # the four crescents
    with warnings.catch_warnings():
        warnings.simplefilter("error", SmallFeatureWarning)
        design = DesignGenerator().draw(np.random.default_rng(199), name="r199")
    assert all(rule_cues(s, RULES).capability(2.0) >= 1.0 for s in design.slots)
