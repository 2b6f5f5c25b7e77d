"""The split's Canny from ready-made Sobel derivatives finds exactly the edges of ``cv2.Canny``.

Extraction hands OpenCV's Canny the 3 x 3 Sobel derivatives (border replicated, as Canny takes
them itself) because that path is cheaper; these tests hold it to the image path's edges, pixel
for pixel, on rendered pictures and on seeded noise (whose edges reach the image border).
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

segment_module = importlib.import_module("qshape.vision.segment")


@pytest.mark.parametrize(("design", "seed"), [("hexagon", 1), ("paper_mixed", 4)])
def test_canny_from_derivatives_equals_canny_on_rendered_channels(design: str, seed: int) -> None:
    p = ExtractParams.load()
    sp = replace(SynthParams.load(), px_per_mm=1.8)
    img = generate(Design.load(design), 30, seed, sp).image
    for plane in cv2.split(img):
        want = cv2.Canny(plane, p.canny_low, p.canny_high)
        assert np.count_nonzero(want) > 1000  # the tiles' outlines are there
        np.testing.assert_array_equal(segment_module._canny(plane, p.canny_low, p.canny_high), want)


def test_canny_from_derivatives_equals_canny_on_noise_up_to_the_border() -> None:
    rng = np.random.default_rng(11)
    at_border = 0
    for k in range(60):
        h, w = (int(v) for v in rng.integers(3, 90, size=2))
        plane = rng.integers(0, 256, (h, w), dtype=np.uint8)
        if k % 2:
            plane = cv2.GaussianBlur(plane, (5, 5), 1.5)
        want = cv2.Canny(plane, 30.0, 90.0)
        at_border += bool(want[[0, -1], :].any() or want[:, [0, -1]].any())
        np.testing.assert_array_equal(segment_module._canny(plane, 30.0, 90.0), want)
    assert at_border > 40  # the border handling was really exercised
