"""Extraction under a real line's effects: shadows, lens undistortion, noise regions, holes."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from qshape.design import Design
from qshape.synthetic.effects import (
    CameraEffects,
    distort_points,
    lens_distort,
    undistort,
    undistort_points,
)
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.extract import extract_detailed
from qshape.vision.params import ExtractParams, ImageError

BELT = (61, 66, 71)
RED = (200, 60, 40)


def _belt(h: int = 300, w: int = 400) -> np.ndarray:
    img = np.empty((h, w, 3), np.uint8)
    img[:] = BELT
    return img


def _noisy(img: np.ndarray, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.clip(img + rng.normal(0.0, 3.0, img.shape), 0, 255).astype(np.uint8)


def _blob(img: np.ndarray, centre: tuple[int, int], jag: float, rng: np.random.Generator) -> None:
    a = np.linspace(0.0, 2.0 * np.pi, 180, endpoint=False)
    r = 40.0 * (1.0 + jag * rng.uniform(-1.0, 1.0, a.size))
    pts = np.stack([centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)], axis=1)
    cv2.fillPoly(img, [np.round(pts).astype(np.int32)], RED)


def test_region_whose_outline_is_mostly_noise_gives_no_figure(
    extract_params: ExtractParams,
) -> None:
    rng = np.random.default_rng(3)
    img = _belt()
    _blob(img, (100, 100), 0.0, rng)  # a clean disc
    _blob(img, (260, 160), 0.25, rng)  # a ragged splash of the same size
    res = extract_detailed(_noisy(img), extract_params)
    assert len(res.figures) == 1
    assert np.allclose(res.figures[0].centroid, (100, 100), atol=1.5)
    assert any("mostly noise" in why for why in res.rejected)
    # The same splash is a figure when the check is off: the check is what rejects it.
    loose = extract_detailed(_noisy(img), ExtractParams.load(max_outline_excess=10.0))
    assert len(loose.figures) == 2


def test_rough_tile_edges_are_not_noise(synth_params: SynthParams, design: Design) -> None:
    sp = synth_params
    rough = replace(sp, effects=CameraEffects(edge_roughness_mm=0.6))
    img = generate(design, 12, 4, rough)
    res = extract_detailed(img.image)
    assert not any("mostly noise" in why for why in res.rejected)
    assert len(res.figures) == sum(not t.partial for t in img.tiles)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_every_tile_found_under_a_soft_shadow(
    seed: int, synth_params: SynthParams, design: Design
) -> None:
    sp = replace(synth_params, effects=CameraEffects(shadow_strength=0.35))
    img = generate(design, 14, seed, sp)
    res = extract_detailed(img.image)
    whole = [t for t in img.tiles if not t.partial]
    cents = np.array([f.centroid for f in res.figures])
    assert len(res.figures) == len(whole)
    for t in whole:
        assert np.hypot(*(cents - t.center_px).T).min() < 3.0


def _half_shadow() -> np.ndarray:
    """A red square in the light and one in a 40 % shadow covering the right half."""
    img = _belt()
    cv2.rectangle(img, (60, 110), (140, 190), RED, -1)
    cv2.rectangle(img, (260, 110), (340, 190), RED, -1)
    img = img.astype(np.float32)
    img[:, 200:] *= 0.6
    return _noisy(img.astype(np.uint8))


def test_belt_model_follows_a_shadow(extract_params: ExtractParams) -> None:
    res = extract_detailed(_half_shadow(), extract_params)
    assert len(res.figures) == 2
    lit, shaded = sorted(res.figures, key=lambda f: f.centroid[0])
    # Both colours corrected to one light: the same glaze reads the same in and out of shadow.
    assert np.abs(np.array(lit.color) - np.array(shaded.color)).max() < 0.1
    # Without the corrections the shadowed tile reads 40 % darker.
    off = extract_detailed(_half_shadow(), ExtractParams.load(correct_illumination=False))
    a, b = sorted(off.figures, key=lambda f: f.centroid[0])
    assert b.color[0] < 0.7 * a.color[0]


def test_dark_glaze_dip_is_not_a_hole() -> None:
    # A tile whose glaze fades softly towards the belt colour (under the threshold, not to the
    # belt) in a blotch: no hole. The same tile with a real hole showing the belt: one hole.
    img = _belt().astype(np.float32)
    red = np.array(RED, np.float32)
    belt = np.array(BELT, np.float32)
    yy, xx = np.mgrid[0:300, 0:400].astype(np.float32)
    img[60:181, 40:161] = red
    img[60:181, 220:341] = red
    fade = 0.7 * np.exp(-((xx - 100) ** 2 + (yy - 120) ** 2) / (2 * 12.0**2))
    inside = (yy >= 60) & (yy <= 180) & (xx >= 40) & (xx <= 160)
    img[inside] = (red + fade[..., None] * (belt - red))[inside]
    out = _noisy(img.astype(np.uint8))
    cv2.circle(out, (280, 120), 14, BELT, -1)
    p = ExtractParams.load(threshold_min=60.0, threshold_max=60.0)
    res = extract_detailed(out, p)
    by_x = sorted(res.figures, key=lambda f: f.centroid[0])
    assert [len(f.holes) for f in by_x] == [0, 1]
    # Without the belt check the blotch is taken for a hole.
    loose = extract_detailed(out, replace(p, hole_belt_fraction=100.0))
    assert [len(f.holes) for f in sorted(loose.figures, key=lambda f: f.centroid[0])] == [1, 1]


def test_undistortion_inverts_the_lens(synth_params: SynthParams) -> None:
    e = CameraEffects(lens_k1=-0.15, lens_k2=0.02)
    w, h = 656, 492
    pts = np.array([[10.0, 12.0], [328.0, 246.0], [600.0, 50.0], [640.0, 480.0]])
    back = undistort_points(distort_points(pts, e, w, h), e, w, h)
    assert np.allclose(back, pts, atol=0.05)
    sp = replace(synth_params, effects=CameraEffects())
    ideal = generate(Design.load("square_grid"), 10, 2, sp).image
    seen = lens_distort(ideal, e)
    again = undistort(seen, e)
    centre = (slice(30, 462), slice(30, 626))
    err_seen = np.abs(seen[centre].astype(int) - ideal[centre]).mean()
    err_back = np.abs(again[centre].astype(int) - ideal[centre]).mean()
    assert err_back < 0.5 * err_seen


def test_new_params_validated() -> None:
    with pytest.raises(ImageError, match="max_outline_excess"):
        ExtractParams.load(max_outline_excess=0.5)
    with pytest.raises(ImageError, match="belt_gain_min"):
        ExtractParams.load(belt_gain_min=1.5)
    with pytest.raises(ImageError, match="lit_percentile"):
        ExtractParams.load(lit_percentile=120.0)
