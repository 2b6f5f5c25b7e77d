"""The made turn spread: how far a made tile's own deviation moves its best-fit turn."""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
import pytest
from scipy.optimize import minimize_scalar
from scipy.spatial import cKDTree

from qshape import geometry as geo
from qshape.design import Design
from qshape.design.generator import DesignGenerator
from qshape.design.made_turn import made_turn_sd
from qshape.design.rules import DesignRules
from qshape.design.slot import Slot
from qshape.design.turn_cues import rule_cues
from qshape.errors import DesignError, SmallFeatureWarning

RULES = DesignRules()
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


def _design(shape: dict[str, Any], name: str = "s") -> dict[str, Any]:
    return {
        "name": "made",
        "mesh": {"width": 100, "height": 100},
        "joint": 2.0,
        "slots": [{"name": name, "shape": shape, "color": "#2aa39a", "pose": {"x": 50, "y": 50}}],
    }


def _slot(shape: dict[str, Any]) -> Slot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SmallFeatureWarning)
        return Design.from_dict(_design(shape)).slots[0]


def _centroid(loops: list[np.ndarray]) -> np.ndarray:
    """Area centroid of the first loop less the others (all counter-clockwise)."""
    area, moment = 0.0, np.zeros(2)
    for k, v in enumerate(loops):
        w = np.roll(v, -1, axis=0)
        cross = v[:, 0] * w[:, 1] - v[:, 1] * w[:, 0]
        sign = 1.0 if k == 0 else -1.0
        area += sign * 0.5 * float(cross.sum())
        moment += sign * ((v + w) * cross[:, None]).sum(axis=0) / 6.0
    return moment / area


def _monte_carlo_sd(slot: Slot, deviation: float, copies: int, seed: int) -> float:
    """Std [deg] of the least-squares best-fit turn of made copies (every vertex deviated)."""
    path = slot.local_path
    drawn = [path.outer.made_vertices(RULES.made_arc_step_mm)]
    drawn += [h.made_vertices(RULES.made_arc_step_mm) for h in path.holes]
    tree = cKDTree(path.outer.dense(0.02) - _centroid(drawn))
    rng = np.random.default_rng(seed)
    turns = []
    for _ in range(copies):
        made = [v + rng.normal(0.0, deviation, v.shape) for v in drawn]
        outline = made[0] - _centroid(made)
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
