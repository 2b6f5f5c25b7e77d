"""Synthetic tile images: determinism, geometry of the ground truth, noise levels."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qshape import Boundary, Figure, Tolerances, match
from qshape.design import Design
from qshape.errors import QShapeError
from qshape.geometry import points_in_polygon, wrap_angle
from qshape.synthetic.synth import SynthParams, generate, place_path
from qshape.vision.extract import extract_detailed


def test_deterministic(design: Design) -> None:
    a = generate(design, 8, 5)
    b = generate(design, 8, 5)
    np.testing.assert_array_equal(a.image, b.image)
    assert [t.slot.name for t in a.tiles] == [t.slot.name for t in b.tiles]
    for ta, tb in zip(a.tiles, b.tiles, strict=True):
        np.testing.assert_array_equal(ta.points_px, tb.points_px)
    c = generate(design, 8, 6)
    assert not np.array_equal(a.image, c.image)


def test_image_and_truth(design: Design, synth_params: SynthParams) -> None:
    sp = synth_params
    img = generate(design, 12, 1, sp)
    assert img.image.shape == (492, 656, 3) and img.image.dtype == np.uint8
    assert 8 <= len(img.tiles) <= 12
    for t in img.tiles:
        assert t.slot in design.slots
        assert np.all(t.points_px >= 0) and np.all(t.points_px[:, 0] < 656)
        assert np.all(t.points_px[:, 1] < 492)
        assert -math.pi < t.rotation <= math.pi
        assert len(t.points_px) == len(t.curve_mask)
        assert all(0.0 <= v <= 1.0 for v in t.color)
    # No relevant point of one tile lies inside another tile.
    for i, a in enumerate(img.tiles):
        for b in img.tiles[i + 1 :]:
            assert not points_in_polygon(a.points_px, b.points_px).any()


def test_truth_matches_rendered_tiles(design: Design, synth_params: SynthParams) -> None:
    sp = synth_params.noise_level(0.0)
    img = generate(design, 10, 2, sp)
    res = extract_detailed(img.image)
    assert len(res.figures) == len(img.tiles)
    tol = Tolerances(joint_width=design.joint * sp.px_per_mm)
    for t in img.tiles:
        fig = min(res.figures, key=lambda f: float(np.hypot(*(f.centroid - t.center_px))))
        assert np.hypot(*(fig.centroid - t.center_px)) < 1.0
        # The truth's own figure (y down) matches the slot with the truth's rotation.
        holes = [
            Boundary.make(h, hm, y_down=True)
            for h, hm in zip(t.hole_points_px, t.hole_curve_masks, strict=True)
        ]
        truth_fig = Figure.from_polygon(
            t.points_px, holes, t.color, curve_mask=t.curve_mask, y_down=True
        )
        ref = t.slot.figure()
        s = sp.px_per_mm
        ref = Figure.from_polygon(
            ref.points * s,
            [Boundary.make(h.points * s, h.curve_mask) for h in ref.holes],
            ref.color,
            curve_mask=ref.curve_mask,
        )
        m = match(ref, truth_fig, tol, use_color=True)
        assert m is not None, t.slot.name
        if t.slot.symmetry:
            period = 2 * math.pi / t.slot.symmetry
            err = min(abs(math.remainder(r - t.rotation, period)) for r in m.rotations)
            assert err < 1e-3, t.slot.name


def test_noise_levels(design: Design, synth_params: SynthParams) -> None:
    clean = generate(design, 4, 3, synth_params.noise_level(0.0))
    belt = np.round(255 * np.array(synth_params.belt_color))
    corner = clean.image[:3, :3].reshape(-1, 3)
    np.testing.assert_array_equal(corner, np.broadcast_to(belt, corner.shape))
    noisy = generate(design, 4, 3, synth_params.noise_level(3.0))
    assert noisy.image[:40, :40].std() > clean.image[:40, :40].std()
    p = synth_params.noise_level(2.0)
    assert p.vertex_jitter_mm == pytest.approx(1.0)


def test_place_path_and_wrap(design: Design) -> None:
    slot = design.slot("rect_yellow")
    placed = place_path(slot.local_path, math.pi / 2, (100.0, 50.0), 2.0)
    ext = np.ptp(placed.outer.vertices, axis=0)
    np.testing.assert_allclose(ext, [48.0, 96.0], atol=1e-9)  # 48 x 24 mm turned upright
    assert wrap_angle(3 * math.pi) == pytest.approx(math.pi)
    assert wrap_angle(-math.pi) == pytest.approx(math.pi)


def test_bad_params(design: Design) -> None:
    with pytest.raises(QShapeError):
        SynthParams(px_per_mm=0.0)
    with pytest.raises(QShapeError):
        SynthParams(noise_std=-1.0)
    with pytest.raises(QShapeError):
        generate([], 3, 0)
    assert generate(design, 0, 0).tiles == []
