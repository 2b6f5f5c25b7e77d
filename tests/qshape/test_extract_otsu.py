"""Otsu's threshold from a sample of the colour distance, and the mask from every pixel."""

from __future__ import annotations

import importlib
from dataclasses import replace

import cv2
import numpy as np
import pytest

from qshape.design import Design
from qshape.synthetic.synth import SynthParams, generate
from qshape.vision.params import ExtractParams, ImageError

background_module = importlib.import_module("qshape.vision.background")
segment_module = importlib.import_module("qshape.vision.segment")


def _distance_inputs(img: np.ndarray, p: ExtractParams) -> tuple:
    planes = cv2.split(cv2.GaussianBlur(img, (3, 3), 0.5))
    dominant = background_module.dominant_color(cv2.merge(planes), p)[0]
    model, _, gain = background_module.illumination(planes, dominant, p)
    return planes, model, gain


def test_sampled_otsu_gives_the_same_mask_on_a_rendered_picture() -> None:
    p = ExtractParams.load()
    assert p.otsu_sample_step == 2  # the configured value is the one tested
    img = generate(Design.load("paper_mixed"), 30, 8, replace(SynthParams.load(), px_per_mm=1.8))
    planes, model, gain = _distance_inputs(img.image, p)
    full = segment_module._colour_distance(planes, model, gain, replace(p, otsu_sample_step=1))
    sampled = segment_module._colour_distance(planes, model, gain, p)
    np.testing.assert_array_equal(sampled[0], full[0])
    assert sampled[1] == full[1]
    np.testing.assert_array_equal(sampled[2], full[2])
    assert 0.05 < np.count_nonzero(full[2]) / full[2].size < 0.9


def test_sampled_otsu_is_within_a_level_or_two_where_it_decides() -> None:
    """With the clamp opened wide Otsu's own value sets the threshold: from a quarter of the
    pixels it lands within two levels of the full histogram's, and the masks differ only on
    the blurred rims' pixels between the two."""
    p = replace(ExtractParams.load(), threshold_min=1.0, threshold_max=250.0)
    for seed in range(3):
        sp = replace(SynthParams.load(), px_per_mm=1.8)
        img = generate(Design.load("square_grid"), 24, seed, sp).image
        planes, model, gain = _distance_inputs(img, p)
        full = segment_module._colour_distance(planes, model, gain, replace(p, otsu_sample_step=1))
        sampled = segment_module._colour_distance(planes, model, gain, p)
        assert p.threshold_min < full[1] < p.threshold_max  # Otsu decides here
        assert abs(sampled[1] - full[1]) <= 2.0
        differ = np.count_nonzero(sampled[2] != full[2])
        assert differ <= 0.01 * np.count_nonzero(full[2])


@pytest.mark.parametrize("field", ["otsu_sample_step", "edge_sample_step"])
def test_sample_steps_below_one_are_refused(field: str) -> None:
    with pytest.raises(ImageError, match=field):
        replace(ExtractParams.load(), **{field: 0})
