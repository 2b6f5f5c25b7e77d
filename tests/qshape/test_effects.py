"""A real line's effects on synthetic pictures (qshape.synthetic.effects, qshape.synthetic.synth
with effects)."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest
from shapely.geometry import Polygon

from qshape.design import Design
from qshape.errors import QShapeError
from qshape.synthetic.effects import (
    CameraEffects,
    chip_corners,
    distort_points,
    jpeg,
    lens_distort,
    motion_blur,
    motion_kernel,
    roughen,
)
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.extract import extract_detailed


def _square(side: float = 100.0, step: float = 0.5) -> np.ndarray:
    t = np.arange(0.0, side, step)
    z, s = np.zeros_like(t), np.full_like(t, side)
    return np.concatenate(
        [np.stack(v, axis=1) for v in ((t, z), (s, t), (side - t, s), (z, side - t))]
    )


def test_roughen_moves_along_normals_by_sigma() -> None:
    sq = _square()
    rough = roughen(sq, 1.0, 2.5, np.random.default_rng(0))
    bottom = (sq[:, 1] == 0.0) & (sq[:, 0] > 5.0) & (sq[:, 0] < 95.0)
    dy = rough[bottom, 1]  # the bottom edge moves in y only
    np.testing.assert_allclose(rough[bottom, 0], sq[bottom, 0], atol=1e-9)
    assert 0.6 < float(dy.std()) < 1.4
    assert abs(float(dy.mean())) < 0.6
    assert roughen(sq, 0.0, 2.5, np.random.default_rng(0)) is sq


def test_chip_cuts_the_corner_off() -> None:
    sq = _square()
    corner = np.array([[100.0, 100.0]])
    chipped = chip_corners(sq, corner, 1.0, 4.0, np.random.default_rng(1))
    gap = float(np.hypot(*(chipped - corner).T).min())
    assert 1.0 < gap <= 4.0 / np.sqrt(2.0) + 1e-6  # the cut passes inside the corner
    far = np.hypot(*(sq - corner).T) > 4.0
    np.testing.assert_array_equal(chipped[far], sq[far])


def test_motion_blur_length_from_belt_speed_and_exposure() -> None:
    e = CameraEffects(belt_speed_m_s=0.1, exposure_ms=4.0)
    assert e.blur_px(2.5) == pytest.approx(1.0)
    k = motion_kernel(5.0, 0.0)
    assert k.sum() == pytest.approx(1.0)
    assert np.count_nonzero(k.sum(axis=1) > 1e-6) <= 2  # horizontal only
    step = np.zeros((20, 60, 3), np.float32)
    step[:, 30:] = 200.0
    out = motion_blur(step, 5.0, 0.0)
    ramp = np.flatnonzero((out[10, :, 0] > 1.0) & (out[10, :, 0] < 199.0))
    assert 4 <= len(ramp) <= 6
    vertical = motion_blur(step, 5.0, 90.0)
    np.testing.assert_allclose(vertical[5:15], step[5:15], atol=1e-3)


def test_lens_distortion_moves_content_where_the_model_says() -> None:
    e = CameraEffects(lens_k1=-0.3)
    h, w = 240, 320
    image = np.zeros((h, w, 3), np.float32)
    dot = np.array([280.0, 200.0])
    cv2.circle(image, (int(dot[0]), int(dot[1])), 3, (255, 255, 255), -1)
    seen = lens_distort(image, e)
    ys, xs = np.nonzero(seen[..., 0] > 128)
    where = np.array([xs.mean(), ys.mean()])
    expect = distort_points(dot[None, :], e, w, h)[0]
    assert np.hypot(*(expect - dot)) > 5.0  # a visible move (barrel: towards the centre)
    assert np.hypot(*(where - expect)) < 1.0
    centre = np.array([[(w - 1) / 2.0, (h - 1) / 2.0]])
    np.testing.assert_allclose(distort_points(centre, e, w, h), centre)


def test_jpeg_changes_a_little() -> None:
    rng = np.random.default_rng(2)
    image = np.clip(rng.normal(120, 30, (64, 64, 3)), 0, 255).astype(np.uint8)
    assert jpeg(image, 0) is image
    out = jpeg(image, 75)
    assert out.shape == image.shape and out.dtype == np.uint8
    diff = np.abs(out.astype(int) - image.astype(int)).mean()
    assert 0.5 < diff < 30.0


@pytest.mark.parametrize(
    "bad",
    [
        {"edge_roughness_mm": -0.1},
        {"chip_probability": 1.5},
        {"shadow_strength": 1.0},
        {"jpeg_quality": 101},
        {"lens_k1": float("nan")},
    ],
)
def test_bad_effects(bad: dict[str, float]) -> None:
    with pytest.raises(QShapeError):
        CameraEffects(**bad)  # type: ignore[arg-type]


def test_between_draws_inside_the_range() -> None:
    lo = CameraEffects(edge_roughness_mm=0.15, jpeg_quality=75)
    hi = CameraEffects(edge_roughness_mm=0.4, jpeg_quality=95)
    rng = np.random.default_rng(3)
    for _ in range(20):
        e = lo.between(hi, rng)
        assert 0.15 <= e.edge_roughness_mm <= 0.4
        assert 75 <= e.jpeg_quality <= 95 and isinstance(e.jpeg_quality, int)


def test_effects_off_leave_pictures_unchanged(design: Design, synth_params: SynthParams) -> None:
    sp = synth_params
    a = generate(design, 8, 4, sp)
    b = generate(design, 8, 4, replace(sp, effects=CameraEffects()))
    np.testing.assert_array_equal(a.image, b.image)


def test_touching_and_partial_tiles(design: Design, synth_params: SynthParams) -> None:
    sp = synth_params
    e = CameraEffects(touching_probability=1.0)
    img = generate(design, 8, 5, replace(sp, effects=e, noise_std=0.0))
    assert len(img.tiles) >= 4
    polys = [Polygon(t.points_px) for t in img.tiles if not t.curve_mask.any()]
    near = [min(a.distance(b) for b in polys if b is not a) for a in polys]
    assert sum(d < 1.5 for d in near) >= len(polys) // 2  # laid against each other
    e = CameraEffects(partial_probability=1.0)
    img = generate(design, 6, 6, replace(sp, effects=e))
    cut = [t for t in img.tiles if t.partial]
    assert len(cut) >= 3
    res = extract_detailed(img.image)
    assert len(res.partial) >= len(cut) - 1  # (a tile just touching the border may be lost)
    for t in cut:  # no whole figure where a border-cut tile is
        for f in res.figures:
            assert np.hypot(*(f.centroid - t.center_px)) > 0.3 * np.sqrt(t.slot.area) * 2.5


def test_lens_truth_follows_the_picture(design: Design, synth_params: SynthParams) -> None:
    sp = synth_params
    e = CameraEffects(lens_k1=-0.2)
    plain = generate(design, 6, 8, sp)
    bent = generate(design, 6, 8, replace(sp, effects=e))
    assert len(plain.tiles) == len(bent.tiles)
    moved = [
        np.hypot(*(a.center_px - b.center_px)) for a, b in zip(plain.tiles, bent.tiles, strict=True)
    ]
    assert max(moved) > 2.0
    res = extract_detailed(bent.image)
    for t in bent.tiles:
        if t.partial:
            continue
        d = min(np.hypot(*(f.centroid - t.center_px)) for f in res.figures)
        assert d < 2.0
