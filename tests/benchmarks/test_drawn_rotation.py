"""A drawn tile's true orientation (benchmarks.recognition.drawn_rotation) on generated pictures."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from benchmarks.recognition.drawn_rotation import drawn_angle
from qshape.design import Design
from qshape.geometry import rotate
from qshape.synthetic.effects import CameraEffects
from qshape.synthetic.synth import SynthParams, generate


def _turn_error_deg(a: float, b: float, symmetry: int) -> float:
    return math.degrees(math.remainder(a - b, 2.0 * math.pi / max(symmetry, 1)))


def test_a_tile_drawn_as_designed_is_at_its_drawing_angle(synth_params: SynthParams) -> None:
    sp = synth_params
    clean = replace(sp, vertex_jitter_mm=0.0, bulge_jitter=0.0)
    for name in ("hexagon", "trencadis"):
        img = generate(Design.load(name), 6, 4, clean)
        for t in img.tiles:
            assert t.outline_px is not None
            err = _turn_error_deg(drawn_angle(t, sp.px_per_mm), t.angle, t.slot.symmetry)
            assert abs(err) < 0.01, (name, err)


def test_an_outline_drawn_turned_is_found_turned(synth_params: SynthParams) -> None:
    sp = synth_params
    img = generate(Design.load("trencadis"), 4, 7, sp)
    turn = math.radians(1.5)
    for t in img.tiles:
        before = drawn_angle(t, sp.px_per_mm)
        centre = t.outline_px.mean(axis=0)  # type: ignore[union-attr]
        # y down in the picture: a CCW (y up) turn is a clockwise turn of the pixel coordinates.
        turned = rotate(t.outline_px - centre, -turn) + centre  # type: ignore[operator]
        after = drawn_angle(replace(t, outline_px=turned), sp.px_per_mm)
        assert _turn_error_deg(after - before, turn, 1) == pytest.approx(0.0, abs=0.01)


def test_rough_edges_turn_a_tile_as_drawn(synth_params: SynthParams) -> None:
    """With 0.4 mm rough edges the drawn outline is no longer at the drawing angle."""
    sp = synth_params
    rough = replace(sp, effects=CameraEffects(edge_roughness_mm=0.4))
    img = generate(Design.load("hexagon"), 10, 2, rough)
    errs = [
        abs(_turn_error_deg(drawn_angle(t, sp.px_per_mm), t.angle, t.slot.symmetry))
        for t in img.tiles
    ]
    assert max(errs) > 0.3
    assert max(errs) < 3.0


def test_a_tile_without_its_outline_is_refused(synth_params: SynthParams) -> None:
    sp = synth_params
    t = generate(Design.load("hexagon"), 1, 1, sp).tiles[0]
    with pytest.raises(ValueError, match="outline_px"):
        drawn_angle(replace(t, outline_px=None), sp.px_per_mm)
    assert np.all(np.isfinite(t.outline_px))  # type: ignore[arg-type]
