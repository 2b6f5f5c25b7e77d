"""Extraction's per-channel reductions computed from colour planes give numpy's own results.

numpy reduces a short last axis (the 3 colour channels) several times slower than it adds three
planes; the belt model and the dominant colour use the planes. These tests hold them to the
values of the plain reductions, bit for bit, on seeded data and rendered pictures.
"""

from __future__ import annotations

import importlib
from dataclasses import replace

import cv2
import numpy as np
import pytest

from qshape.design import Design
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.params import ExtractParams

background_module = importlib.import_module("qshape.vision.background")
segment_module = importlib.import_module("qshape.vision.segment")


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("shape", [(30, 41, 3), (492, 656, 3)])
def test_channel_sum_equals_numpys_sum_bit_for_bit(dtype: type, shape: tuple[int, ...]) -> None:
    rng = np.random.default_rng(7)
    # Values of very different sizes side by side: any change of summation order would show.
    scale = rng.choice([1e-3, 1.0, 255.0, 1e6], size=shape[:-1] + (1,))
    values = (rng.random(shape) * scale).astype(dtype)
    got = background_module._channel_sum(values)
    assert got.dtype == values.dtype
    np.testing.assert_array_equal(got, values.sum(axis=-1))


def _dominant_reference(img: np.ndarray, p: ExtractParams) -> tuple[np.ndarray, float, int]:
    """The dominant colour as plain (N, 3) reductions compute it (the definition)."""
    b, step = p.background_border_px, p.background_sample_step
    sample = np.concatenate(
        [
            img[:b, ::step].reshape(-1, 3),
            img[-b:, ::step].reshape(-1, 3),
            img[b:-b:step, :b].reshape(-1, 3),
            img[b:-b:step, -b:].reshape(-1, 3),
        ]
    )
    q = (sample.astype(np.int32) * p.background_bins) >> 8
    code = (q[:, 0] * p.background_bins + q[:, 1]) * p.background_bins + q[:, 2]
    top = int(np.argmax(np.bincount(code, minlength=p.background_bins**3)))
    dominant = np.median(sample[code == top], axis=0)
    off = np.abs(sample.astype(np.float64) - dominant)
    near = off.max(axis=1) <= p.background_tolerance
    span = int((sample.max(axis=0).astype(np.int32) - sample.min(axis=0)).max())
    return dominant, float(near.mean()), span


@pytest.mark.parametrize(("design", "seed"), [("hexagon", 0), ("paper_mixed", 3), ("trencadis", 5)])
def test_dominant_colour_from_planes_matches_the_plain_reductions(design: str, seed: int) -> None:
    p = ExtractParams.load()
    sp = replace(SynthParams.load(), px_per_mm=1.8)
    img = generate(Design.load(design), 30, seed, sp).image
    dominant, share, span = background_module.dominant_color(img, p)
    ref_dominant, ref_share, ref_span = _dominant_reference(img, p)
    np.testing.assert_array_equal(dominant, ref_dominant)
    assert share == ref_share
    assert span == ref_span
    # A real belt: most of the border sample is near the dominant colour, and the tiles or
    # noise make it span some levels.
    assert share > 0.5
    assert span > 0


@pytest.mark.parametrize("size", [(656, 492), (641, 479)])
def test_belt_model_resized_plane_by_plane_equals_the_colour_resize(size: tuple[int, int]) -> None:
    rng = np.random.default_rng(3)
    grid = rng.integers(0, 256, (30, 41, 3), dtype=np.uint8)
    whole = cv2.resize(grid, size, interpolation=cv2.INTER_LINEAR)
    planes = [cv2.resize(c, size, interpolation=cv2.INTER_LINEAR) for c in cv2.split(grid)]
    for k in range(3):
        np.testing.assert_array_equal(planes[k], whole[..., k])


def test_colour_distance_from_planes_equals_the_colour_image_difference() -> None:
    p = ExtractParams.load()
    sp = replace(SynthParams.load(), px_per_mm=1.8)
    img = generate(Design.load("paper_mixed"), 30, 2, sp).image
    dominant = background_module.dominant_color(img, p)[0]
    model, _, gain = background_module.illumination(cv2.split(img), dominant, p)
    dist, thr, mask = segment_module._colour_distance(cv2.split(img), model, gain, p)
    # The definition: the largest channel of |picture - model|, scaled by the shading gain.
    diff = cv2.absdiff(img, cv2.merge(model))
    want = cv2.multiply(diff.max(axis=2), gain, scale=1.0 / background_module.GAIN_SCALE)
    np.testing.assert_array_equal(dist, want)
    assert thr > 0.0
    assert 0.05 < np.count_nonzero(mask) / mask.size < 0.9  # tiles found, not everything
